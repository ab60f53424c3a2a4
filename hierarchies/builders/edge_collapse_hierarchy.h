// SPDX-License-Identifier: MIT
#pragma once

#include <memory>
#include <string_view>

#include "framework/config.h"
#include "framework/hierarchy.h"
#include "hierarchies/builders/level_limits.h"

namespace harap {

/// A manifold-preserving hierarchy by quadric-error edge collapse: the alternative to vertex
/// clustering that the paper compares against in Fig. 18 (Section 7, "an edge collapse algorithm
/// [LZBCJ21] ... we can ensure its manifoldness"). Triangle surfaces only.
///
/// Levels: one decimation pass of OpenMesh's Decimater (DecimaterT) over the input surface, with
/// ModQuadricT as the priority (Garland–Heckbert quadric error, no error bound),
/// ModNormalFlippingT refusing collapses that turn a face normal by more than
/// `max_normal_deviation` and ModAspectRatioT refusing collapses that create faces worse than
/// `max_aspect_ratio`. The decimater only performs collapses that OpenMesh's is_collapse_ok()
/// allows (the link condition, boundary rules), so every level is a manifold surface with the
/// input's topology. Whenever the vertex count reaches the next level's target, the current mesh
/// is copied out as that level and the same pass goes on: level l+1 is the decimation of level l,
/// so the levels are nested.
///
///   - Vertex counts: by default those of the `octree` hierarchy (default options, with this
///     hierarchy's `min_vertices`, `coarsest` and `max_levels`) for the same mesh, so the two
///     hierarchies can be compared level by level (the octree's build is part of this
///     hierarchy's build time, a few percent of it at most). With `ratio` > 0 instead, level l+1
///     gets ⌈ratio · n_l⌉ vertices until a level has at most `min_vertices` (with `coarsest =
///     at_least`: until the next target would be below it). When no legal collapse is left before
///     a target (e.g. closed components stop at 4 vertices, flat parts at the aspect-ratio
///     bound), the mesh reached so far is the last level.
///   - Coarse rest positions: OpenMesh collapses halfedges v0 → v1, and v1 keeps its position.
///     Every coarse vertex therefore sits exactly at the rest position of an input vertex (the
///     one it still is), not at an optimized or averaged position.
///   - Fine → coarse map (HierarchyLevel::coarse_vertex): each collapse v0 → v1 is recorded; a
///     vertex of level l maps to the vertex of level l+1 it was collapsed into, following chains
///     (v0 → v1 → v2 ... to the survivor), or to itself if it survived. The vertices mapped to one
///     coarse vertex are thus its cluster: connected in the fine mesh (each collapse merges two
///     adjacent clusters) and containing the coarse vertex itself, so in_cluster is 1 for every
///     vertex an element references: the up-samplers' Eq. (6)/(7) (fine vertices move rigidly
///     with their cluster's coarse vertex) mean what they mean for octree cells, and Eq. (11)/(12)
///     (element ↔ vertex rotation averages) need only the levels' own elements.
///   - Vertices no element references map to kNoVertex (in_cluster 0), as in the octree; they
///     are not part of the decimation and do not appear on the coarse levels.
///   - Several components are decimated together (one priority queue); each keeps its topology.
///
/// Input OpenMesh's halfedge structure cannot represent:
///   - a non-manifold vertex (its triangles form several fans joined only at the vertex, e.g. the
///     pinched vertex of the shared cow, the 38 of the teapot) is handled: before decimation the
///     vertex is duplicated once per extra fan (fans: triangles at the vertex connected through
///     its edges), so the surface is cut apart there; the copies share the rest position and
///     decimate independently. The input vertex maps to the coarse vertex of its first fan (the
///     one of its lowest triangle). A copy is no level-0 vertex, so on level 0 the cluster that
///     absorbs it may be connected only through it, and if the copy survives, its coarse vertex
///     has no input vertex at its position; from level 1 on, copies are ordinary vertices.
///   - an edge shared by more than two triangles, or by two triangles that traverse it in the
///     same direction (inconsistent orientation), and triangles that repeat a vertex: InputError
///     naming the first such edge/triangle and the count, suggesting the octree.
///   - tetrahedral meshes: InputError (this hierarchy decimates surfaces).
///
/// Build() is const and thread-safe (each call decimates its own OpenMesh copy); the decimation
/// itself is sequential, so its cost does not depend on the thread count. It is deterministic.
class EdgeCollapseHierarchy final : public Hierarchy {
 public:
  static constexpr std::string_view kName = "edge_collapse";

  struct Options : LevelLimits {
    /// 0: the octree's level vertex counts. In (0, 1): each level keeps ⌈ratio · n⌉ of the n
    /// vertices of the level below.
    double ratio = 0.0;
    // min_vertices, coarsest, max_levels: LevelLimits; with ratio 0, all three are passed to the
    // octree that gives the counts.
    /// Largest angle (degrees, in (0, 180]) by which a collapse may turn the normal of a
    /// remaining face (OpenMesh's ModNormalFlippingT; its default 90 forbids fold-overs; 180
    /// allows everything but exactly reversed normals).
    double max_normal_deviation = 90.0;
    /// Largest aspect ratio (longest edge / its height) of the faces a collapse may create,
    /// unless it improves on the worst face around the collapse (OpenMesh's ModAspectRatioT;
    /// ≥ 1, 0 = no check). Without it, flat regions (where every quadric error is 0) decimate
    /// into needles and zero-area faces. OpenMesh's default 5 keeps every angle above ~10° on
    /// Armadillo but stops the Dragon (437K vertices, 407 holes) at 6,278 vertices, far above
    /// the octree's 3,550 of that level; 20 (angles ≥ ~3°) reaches 3,550 and stops at 2,697.
    double max_aspect_ratio = 20.0;

    /// Reads the options and rejects unknown keys and invalid values (ConfigError).
    static Options FromConfig(OptionReader node);
    /// Throws ConfigError listing every violated constraint.
    void Validate() const;
  };

  explicit EdgeCollapseHierarchy(const Options& options);

  MeshHierarchy Build(const Mesh& mesh, const Context& context) const override;

  const Options& options() const { return options_; }

 private:
  Options options_;
};

}  // namespace harap
