// SPDX-License-Identifier: MIT
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "framework/mesh.h"

namespace harap {

/// How TetGen fills a surface (scenario keys of the same names, see docs/input.md).
struct TetrahedralizeOptions {
  /// Largest tetrahedron volume as a fraction of the volume the surface encloses (TetGen -a);
  /// 1e-4 gives at least about 10^4 tetrahedra. 0: no volume bound.
  double max_volume = 0.0;
  /// Quality refinement (TetGen -q): largest circumradius / shortest edge of a tetrahedron. 2.0 is
  /// TetGen's default; 0 turns quality refinement off (the constrained Delaunay tetrahedralization
  /// of the surface vertices alone). Otherwise at least 1.1 (TetGen may not terminate below).
  double max_radius_edge_ratio = 2.0;
  /// Quality refinement also aims for dihedral angles of at least this many degrees (TetGen
  /// -q ratio/angle); 0 (TetGen's default) leaves dihedral angles to the ratio bound. At most 25:
  /// TetGen does not terminate reliably for larger bounds.
  double min_dihedral_angle = 0.0;
};

/// Checks the ranges documented above; returns the problem ("" if none), naming the option.
std::string CheckTetrahedralizeOptions(const TetrahedralizeOptions& options);

/// Fills the closed surface `surface` with tetrahedra (TetGen 1.5, switches -pYJQ plus -q/-a from
/// `options`). The surface is kept exactly: vertices 0..#V−1 of the result are the surface's
/// vertices, bit-identical and in the same order (so handle indices stay valid; vertices no
/// triangle uses stay in the result, unused), the boundary faces of the tetrahedra are exactly the
/// surface's triangles (-Y: no Steiner points on the surface), and interior Steiner points follow
/// as vertices #V, #V+1, ... Every tetrahedron is positively oriented (tetrahedra.h).
///
/// TetGen runs in a forked child process: TetGen 1.5 crashes (segfaults, fails assertions) on
/// some invalid inputs, self-intersecting surfaces among them, and a crash must not take harap
/// down. Its console output is discarded. Throws InputError starting with `what` when the surface
/// is not a closed, consistently oriented triangle surface (naming an offending edge or triangle),
/// when TetGen fails (naming intersecting triangles where TetGen's detection finds them), or when
/// its result does not keep the surface.
Mesh Tetrahedralize(const Mesh& surface, const TetrahedralizeOptions& options,
                    std::string_view what);

}  // namespace harap
