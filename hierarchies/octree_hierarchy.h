// SPDX-License-Identifier: MIT
#pragma once

#include <memory>
#include <string_view>

#include "framework/config.h"
#include "framework/hierarchy.h"

namespace harap {

/// Vertex clustering on nested regular grids (an octree), Section 4 of Meyer, Bickel & Alexa,
/// *Hierarchical Optimization of the As-Rigid-As-Possible Energy* (triangles; tetrahedra by
/// Eq. 10).
///
/// Integer coordinates (Eq. 2) over the bounding box b_min..b_max of the referenced vertices:
///
///     w_i,d = ⌊(2^q_d − 1) (v̄_i,d − b_min,d) / (b_max,d − b_min,d) + ½⌋,
///
/// with q_d the smallest bit depth whose cell length is at most the mean length Ē of the unique
/// element edges: q_d = 0 if the extent is ≤ Ē (a flat axis, e.g. z of a planar mesh, is one
/// cell), else q_d = ⌈log₂(extent/Ē + 1)⌉ (Eq. 3, with the 2^q − 1 of Eq. 2 taken into account
/// so that the cell length extent/(2^q − 1) really is ≤ Ē; q_d ≤ 21).
///
/// Level 0 is the input mesh verbatim. Level l uses the cells w >> s_l for a strictly increasing
/// shift s_l (normally s_l = l, Eq. 4): level l+1 clusters the vertices of level l that share a
/// cell at shift s_l + 1. A shift that merges nothing is skipped (the next one is tried), so every
/// level has strictly fewer vertices than the one before.
///
///   - Topology awareness (`topology_aware`, the paper's "Topology" paragraph): two vertices of
///     one cell merge only if a path of level-l element edges inside the cell joins them. This is
///     Algorithm 1 with its test corrected (neighbour k must lie in the start vertex's cell), and
///     is computed as union–find over the element edges whose ends share a cell, which gives the
///     same classes as the per-class BFS without building an adjacency structure.
///   - Elements survive iff their vertices lie in 3 (triangles, Eq. 5) or 4 (tetrahedra, Eq. 10)
///     different clusters. Surviving elements with the same cluster set are kept once (the first
///     in level-l order, with its orientation): such duplicates arise only from the clustering
///     (e.g. both sides of a collapsed thin part) and would otherwise double the element's
///     weight in the coarse energy. The paper does not say; we deduplicate.
///   - A coarse level holds only the clusters used by its surviving elements, indexed
///     0..n_{l+1}−1 in the order of their smallest level-l member.
///   - coarse_vertex[i]: the coarse vertex of i's cluster if that survived (in_cluster = 1);
///     otherwise the coarse vertex of the closest level-l vertex whose cluster survived, by hop
///     distance in the level-l vertex–edge graph (multi-source BFS; ties → lowest coarse index),
///     in_cluster = 0; kNoVertex if no such vertex is reachable (isolated or unreferenced
///     vertices, components that vanished).
///   - Input vertices that no element references take part in no cluster (in either mode):
///     they map to kNoVertex on level 0 and never appear on coarser levels.
///
/// Coarse rest positions (`coarse_positions`):
///   - "mean" (default): the mean of the rest positions of the cluster's *finest* (level-0)
///     members. Distinct clusters get distinct positions, coarse tetrahedra keep volume.
///   - "quantized" (the paper): the centre of the cluster's cell (clipped to the bounding box),
///     decoded from the truncated integer coordinates. A cell split by the topology check holds
///     several clusters that would all get the same centre (zero-length edges, zero-area
///     elements), so each of those clusters takes the mean instead.
///   The default is "mean" because it gives better-shaped coarse levels on real meshes: with
///   quantized positions a large share of coarse tetrahedra are flat (four cells in a plane) and
///   coarse triangles sit up to half a cell diagonal off the surface. Measurements (Armadillo,
///   Dragon, tetrahedral bunny) are in octree_hierarchy.cpp.
///
/// Building stops when the coarsest level has at most `min_vertices` vertices, when no shift
/// reduces it any more (or a coarser level would have no element), or after `max_levels` levels.
///
/// Build() is const and thread-safe; it runs in context's task arena (TBB) and is deterministic
/// (the result does not depend on the thread count).
class OctreeHierarchy final : public Hierarchy {
 public:
  static constexpr std::string_view kName = "octree";

  enum class CoarsePositions {
    kMean,       ///< mean of the finest members' rest positions
    kQuantized,  ///< cell centre of the truncated integer coordinates (the paper)
  };

  struct Options {
    /// Merge the vertices of one cell only if they are connected inside it (the paper's
    /// "Topology" paragraph); false merges every vertex of a cell.
    bool topology_aware = true;
    /// Rest positions of coarse vertices; see the class comment for the measured choice.
    CoarsePositions coarse_positions = CoarsePositions::kMean;
    /// Stop once the coarsest level has at most this many vertices (≥ 0; the paper uses 750).
    int min_vertices = 750;
    /// At most this many levels, level 0 included (≥ 0; 0 = no limit).
    int max_levels = 0;

    /// Reads the options and rejects unknown keys and invalid values (ConfigError).
    static Options FromConfig(const ConfigNode& node);
    /// Throws ConfigError listing every violated constraint.
    void Validate() const;
  };

  explicit OctreeHierarchy(const Options& options);
  static std::unique_ptr<Hierarchy> Create(const ConfigNode& node);

  MeshHierarchy Build(const Mesh& mesh, const Context& context) const override;

  const Options& options() const { return options_; }

  static std::string_view ToString(CoarsePositions positions);

 private:
  Options options_;
};

}  // namespace harap
