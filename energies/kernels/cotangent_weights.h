// SPDX-License-Identifier: MIT
#pragma once

#include "framework/types.h"

namespace harap {

/// A triangle whose area is below this fraction of its longest edge squared has no well-defined
/// angles (its cotangents would be ±inf or NaN); its weights are set to zero, i.e. it contributes
/// nothing to the energy. See docs/energies.md.
inline constexpr double kDegenerateTriangleRatio = 1e-12;

/// ½·cot of the interior angle at each corner of each triangle (#F×3): column a belongs to the
/// edge opposite corner a (the Pinkall–Polthier / Chao et al. weight w_{f,jk}). Degenerate
/// triangles get zeros and are counted in `num_degenerate` (if given).
Eigen::Matrix<double, Eigen::Dynamic, 3> HalfCotangents(const Positions& vertices,
                                                        const Elements& triangles,
                                                        Index* num_degenerate = nullptr);

/// Mixed Voronoi area of each vertex [Meyer, Desbrun, Schröder, Barr 2003], the lumped mass
/// matrix of libigl's MASSMATRIX_TYPE_VORONOI: in a non-obtuse triangle each corner gets its
/// Voronoi region, ⅛ Σ over its two edges of |e|²·cot(angle opposite e); in an obtuse triangle
/// the obtuse corner gets half the triangle's area and the other two a quarter each. The areas
/// add up to the mesh area. Degenerate triangles (same test as HalfCotangents) contribute nothing,
/// so a vertex used only by degenerate triangles (or by none) has area 0.
Eigen::VectorXd MixedVoronoiAreas(const Positions& vertices, const Elements& triangles);

}  // namespace harap
