// SPDX-License-Identifier: MIT
#pragma once

#include <memory>
#include <string_view>

#include "framework/config.h"
#include "framework/hierarchy.h"
#include "hierarchies/builders/level_limits.h"

namespace harap {

/// Vertex clustering on nested regular grids (an octree), Section 4 of Meyer, Bickel & Alexa,
/// *Hierarchical Optimization of the As-Rigid-As-Possible Energy*: triangles (Eq. 5) and
/// tetrahedra (Eq. 10), told apart by the element size.
///
/// Integer coordinates (Eq. 2) over the bounding box b_min..b_max of the referenced vertices:
///
///     w_i,d = ⌊(2^q_d − 1) (v̄_i,d − b_min,d) / (b_max,d − b_min,d) + ½⌋,
///
/// q_d the smallest bit depth whose cell length is at most the mean length Ē of the unique
/// element edges (Eq. 3 with the 2^q − 1 of Eq. 2 taken into account): q_d = 0 if the extent is
/// ≤ Ē (a flat axis, e.g. z of a planar mesh, is one cell), else ⌈log₂(extent/Ē + 1)⌉, at most
/// 21. Ē counts every edge once; averaging over element corners instead would weigh interior
/// tetrahedral edges by their ~5 tetrahedra (+9% Ē on the WRAPD tetrahedral meshes).
///
/// Level 0 is the input mesh verbatim. Level l ≥ 1 uses the cells w >> s_l of a strictly
/// increasing shift, s_l = l unless a shift merges nothing (it is then skipped, so every level
/// has fewer vertices than the one before): level l+1 clusters the vertices of level l that share
/// a cell at shift s_l + 1 (Eq. 4). Read literally, Eq. (5) would build level 1 from the finest
/// cells w themselves; they are at most Ē wide and merge only 10–30% of the vertices (173K → 147K
/// on Armadillo), so that extra level is left out.
///
///   - Topology awareness (`topology_aware`, the paper's "Topology" paragraph): two vertices of
///     one cell merge only if a path of level-l element edges inside the cell joins them. This is
///     Algorithm 1 with its test corrected (neighbour k must lie in the start vertex's cell),
///     computed as union–find over the element edges whose ends share a cell: the same classes
///     as the per-class BFS, without an adjacency structure. Without it, all vertices of a cell
///     merge.
///   - Elements survive iff their vertices lie in K different clusters (Eqs. 5, 10). Survivors
///     with the same cluster set are kept once (the first in level-l order, with its
///     orientation): such duplicates arise only from the clustering (0.2–2% of the survivors
///     per level on Armadillo, e.g. both sides of a collapsed thin part) and would double the
///     element's weight in the coarse energy. The paper does not say; we deduplicate.
///   - A coarse level holds only the clusters used by its surviving elements, indexed
///     0..n_{l+1}−1 in the order of their smallest level-l member.
///   - coarse_vertex[i]: the coarse vertex of i's cluster if that survived (in_cluster = 1);
///     otherwise that of the closest level-l vertex whose cluster survived, by hop distance in the
///     level-l vertex–edge graph (multi-source BFS; ties → lowest coarse index), in_cluster = 0;
///     kNoVertex if none is reachable (isolated vertices, components that vanished).
///   - Input vertices that no element references join no cluster (in either mode): they map to
///     kNoVertex and do not influence the coarse levels.
///
/// Coarse rest positions (`coarse_positions`):
///   - "mean" (default): the mean of the rest positions of the cluster's finest (level-0)
///     members, i.e. the centroid of the input vertices the coarse vertex stands for.
///   - "quantized" (the paper): the centre of the cluster's cell, decoded from the truncated
///     integer coordinates (clipped to the bounding box). The clusters of a cell split by the
///     topology check would all get the same centre (zero-length edges, zero-area elements), so
///     they take their means instead.
///   Why "mean": it starts the finest level closer to its solution, so that level (the
///   costliest) needs fewer iterations for a similar or lower energy (docs/results.md, "Octree
///   coarse positions", with the command), and the cell centres of neighbouring clusters can lie
///   on a line (three cells in a row: a zero-area triangle) or in a plane (four cells: a flat
///   tetrahedron), which the means of distinct clusters almost never do.
///
/// Building stops when the coarsest level has at most `min_vertices` vertices (with `coarsest =
/// at_least`: before a level with fewer would be added), when no shift reduces it any more or a
/// coarser level would have no element, or after `max_levels` levels.
///
/// Build() is const and thread-safe; it runs in the context's task arena and its result does not
/// depend on the thread count. Its cost: docs/benchmarks.md ("Hierarchy construction").
class OctreeHierarchy final : public Hierarchy {
 public:
  static constexpr std::string_view kName = "octree";

  enum class CoarsePositions {
    kMean,       ///< mean of the finest members' rest positions
    kQuantized,  ///< cell centre of the truncated integer coordinates (the paper)
  };

  struct Options : LevelLimits {
    /// Merge the vertices of one cell only if they are connected inside it (the paper's
    /// "Topology" paragraph); false merges every vertex of a cell.
    bool topology_aware = true;
    /// Rest positions of coarse vertices; see the class comment for the measured choice.
    CoarsePositions coarse_positions = CoarsePositions::kMean;
    // min_vertices, coarsest, max_levels: LevelLimits.

    /// Reads the options and rejects unknown keys and invalid values (ConfigError).
    static Options FromConfig(OptionReader node);
    /// Throws ConfigError listing every violated constraint.
    void Validate() const;
  };

  explicit OctreeHierarchy(const Options& options);

  MeshHierarchy Build(const Mesh& mesh, const Context& context) const override;

  const Options& options() const { return options_; }

  static std::string_view ToString(CoarsePositions positions);

 private:
  Options options_;
};

}  // namespace harap
