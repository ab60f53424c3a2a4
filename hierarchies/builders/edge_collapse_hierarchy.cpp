// SPDX-License-Identifier: MIT
#include "hierarchies/builders/edge_collapse_hierarchy.h"

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModAspectRatioT.hh>
#include <OpenMesh/Tools/Decimater/ModNormalFlippingT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>
#include <algorithm>
#include <cmath>
#include <functional>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "framework/disjoint_sets.h"
#include "framework/error.h"
#include "hierarchies/builders/octree_hierarchy.h"

// Cost: the decimation dominates and is sequential (one priority queue): about a hundred times
// the octree's build time (docs/results.md, "Fig. 18: octree vs edge collapse"). Most of it is
// OpenMesh's legality test is_collapse_ok(), which DecimaterT calls for every outgoing halfedge
// of every vertex around each collapse.

namespace harap {
namespace {

// Double-precision points: OpenMesh's default traits store float positions, and the coarse rest
// positions must equal input positions exactly.
struct DoubleTraits : public OpenMesh::DefaultTraits {
  typedef OpenMesh::Vec3d Point;
  typedef OpenMesh::Vec3d Normal;
};
using SurfaceMesh = OpenMesh::TriMesh_ArrayKernelT<DoubleTraits>;

/// A binary decimation module that allows every collapse and records each one performed:
/// collapsed_into[v0] = v1 for the halfedge collapse v0 → v1 (v0 is removed, v1 stays).
template <class MeshT>
class ModCollapseRecorderT : public OpenMesh::Decimater::ModBaseT<MeshT> {
 public:
  DECIMATING_MODULE(ModCollapseRecorderT, MeshT, CollapseRecorder);

  explicit ModCollapseRecorderT(MeshT& mesh) : Base(mesh, /*is_binary=*/true) {}

  void postprocess_collapse(const CollapseInfo& collapse) override {
    (*collapsed_into)[collapse.v0.idx()] = collapse.v1.idx();
  }

  std::vector<int>* collapsed_into = nullptr;
};

/// Classes of triangle corners (corner 3t + k is corner k of triangle t) that share a vertex
/// and a fan; the root of a class is its smallest corner, so the classes and their roots do not
/// depend on the order of the unions.
using CornerClasses = DisjointSets<Index>;

/// The input's triangles in OpenMesh, each non-manifold vertex split into one vertex per fan.
struct Surface {
  SurfaceMesh mesh;
  /// OpenMesh vertex of each input vertex (the one of its first fan); -1 if unreferenced.
  std::vector<int> vertex_of_input;
};

std::string TriangleList(const std::vector<Index>& triangles) {
  return fmt::format("{}", fmt::join(triangles, ", "));
}

/// Checks that every edge has at most two triangles that traverse it in opposite directions and
/// joins, at both ends of each such interior edge, the corners of its two triangles. Afterwards
/// the corner classes at a vertex are its fans. Throws InputError for what OpenMesh's halfedge
/// structure cannot hold.
void JoinFans(const Mesh& input, CornerClasses& fans) {
  const Index n = input.num_vertices();
  const Index m = input.num_elements();
  const Index* e = input.elements.data();  // row-major: corner c is e[c]
  auto vertex = [&](Index corner) { return e[corner]; };
  auto next = [](Index corner) { return corner - corner % 3 + (corner % 3 + 1) % 3; };

  // Repeated vertices in a triangle: no halfedge structure holds them.
  Index repeated = 0, first_repeated = -1;
  for (Index t = 0; t < m; ++t) {
    const Index a = e[3 * t], b = e[3 * t + 1], c = e[3 * t + 2];
    if (a == b || b == c || a == c) {
      if (repeated++ == 0) first_repeated = t;
    }
  }
  if (repeated > 0) {
    throw InputError(fmt::format(
        "the edge_collapse hierarchy cannot decimate this mesh: {} triangle(s) repeat a vertex "
        "(first: triangle {} with vertices {} {} {}); use the octree hierarchy",
        repeated, first_repeated, e[3 * first_repeated], e[3 * first_repeated + 1],
        e[3 * first_repeated + 2]));
  }

  // The directed edges (one per corner: corner → next corner), bucketed by their smaller end
  // (counting sort); a bucket holds every triangle of every edge at that end.
  std::vector<Index> offsets(std::size_t(n) + 1, 0);
  for (Index c = 0; c < 3 * m; ++c) ++offsets[std::min(vertex(c), vertex(next(c))) + 1];
  for (Index v = 0; v < n; ++v) offsets[v + 1] += offsets[v];
  std::vector<Index> corners(std::size_t(3) * m);
  {
    std::vector<Index> cursor(offsets.begin(), offsets.end() - 1);
    for (Index c = 0; c < 3 * m; ++c) corners[cursor[std::min(vertex(c), vertex(next(c)))]++] = c;
  }
  auto other_end = [&](Index c) { return std::max(vertex(c), vertex(next(c))); };

  Index crowded = 0, misoriented = 0;
  std::string first_crowded, first_misoriented;
  for (Index lo = 0; lo < n; ++lo) {
    Index* begin = corners.data() + offsets[lo];
    Index* end = corners.data() + offsets[lo + 1];
    std::sort(begin, end, [&](Index a, Index b) {
      return std::pair(other_end(a), a) < std::pair(other_end(b), b);
    });
    for (Index* run = begin; run != end;) {
      const Index hi = other_end(*run);
      Index* run_end = run;
      while (run_end != end && other_end(*run_end) == hi) ++run_end;
      const auto count = run_end - run;
      if (count > 2) {
        if (crowded++ == 0) {
          std::vector<Index> triangles;
          for (Index* c = run; c != run_end; ++c) triangles.push_back(*c / 3);
          first_crowded = fmt::format("edge {}–{}, triangles {}", lo, hi, TriangleList(triangles));
        }
      } else if (count == 2) {
        const Index a = run[0], b = run[1];  // directed edges vertex(a) → vertex(next(a)), ...
        if (vertex(a) == vertex(b)) {
          if (misoriented++ == 0) {
            first_misoriented =
                fmt::format("edge {}–{}, triangles {} and {}", lo, hi, a / 3, b / 3);
          }
        } else {
          // a: x → y, b: y → x. Corner a and corner next(b) are both at x, next(a) and b at y.
          fans.Unite(a, next(b));
          fans.Unite(next(a), b);
        }
      }
      run = run_end;
    }
  }
  if (crowded > 0 || misoriented > 0) {
    std::vector<std::string> problems;
    if (crowded > 0) {
      problems.push_back(fmt::format("{} edge(s) shared by more than two triangles (first: {})",
                                     crowded, first_crowded));
    }
    if (misoriented > 0) {
      problems.push_back(fmt::format(
          "{} edge(s) whose two triangles traverse it in the same direction, i.e. inconsistent "
          "orientation (first: {})",
          misoriented, first_misoriented));
    }
    throw InputError(fmt::format(
        "the edge_collapse hierarchy needs an edge-manifold, consistently oriented triangle "
        "surface (OpenMesh's halfedge structure cannot hold others), but this mesh has {}; use "
        "the octree hierarchy, which handles such meshes",
        fmt::join(problems, " and ")));
  }
}

Surface BuildSurface(const Mesh& input) {
  const Index n = input.num_vertices();
  const Index m = input.num_elements();
  const Index* e = input.elements.data();
  CornerClasses fans(3 * m);
  JoinFans(input, fans);

  // A vertex's first fan is the class of its lowest corner (its lowest triangle). The first fans
  // become OpenMesh vertices in input order, any further fan (a non-manifold vertex) a copy
  // appended after them.
  Surface surface;
  SurfaceMesh& mesh = surface.mesh;
  surface.vertex_of_input.assign(n, -1);
  std::vector<Index> first_fan(n, -1);
  for (Index c = 0; c < 3 * m; ++c) {
    if (first_fan[e[c]] < 0) first_fan[e[c]] = fans.Find(c);
  }
  std::vector<int> vertex_of_fan(std::size_t(3) * m, -1);  // indexed by the class root
  mesh.reserve(n, std::size_t(3) * m / 2, m);
  auto add_vertex = [&](Index v) {
    return mesh
        .add_vertex(
            SurfaceMesh::Point(input.vertices(v, 0), input.vertices(v, 1), input.vertices(v, 2)))
        .idx();
  };
  for (Index v = 0; v < n; ++v) {
    if (first_fan[v] < 0) continue;  // unreferenced
    surface.vertex_of_input[v] = vertex_of_fan[first_fan[v]] = add_vertex(v);
  }
  for (Index c = 0; c < 3 * m; ++c) {
    const Index fan = fans.Find(c);
    if (vertex_of_fan[fan] < 0) vertex_of_fan[fan] = add_vertex(e[c]);
  }
  for (Index t = 0; t < m; ++t) {
    const auto face = mesh.add_face(SurfaceMesh::VertexHandle(vertex_of_fan[fans.Find(3 * t)]),
                                    SurfaceMesh::VertexHandle(vertex_of_fan[fans.Find(3 * t + 1)]),
                                    SurfaceMesh::VertexHandle(vertex_of_fan[fans.Find(3 * t + 2)]));
    // JoinFans leaves a manifold surface, which OpenMesh builds in any triangle order.
    if (!face.is_valid()) {
      throw InputError(fmt::format(
          "the edge_collapse hierarchy could not build triangle {} (vertices {} {} {}) in "
          "OpenMesh's halfedge structure; use the octree hierarchy",
          t, e[3 * t], e[3 * t + 1], e[3 * t + 2]));
    }
  }
  return surface;
}

/// Gives the vertex count of the next level from the current count (0: no further level).
using NextTarget = std::function<std::size_t(std::size_t remaining)>;

/// One decimation pass over a surface that copies the mesh out as a new level whenever the
/// vertex count reaches the next level's target: OpenMesh's decimater notifies this observer
/// after every collapse, so the pass is never restarted (restarting would rebuild the priority
/// queue over the whole mesh each time) and the levels are exactly the stages of one
/// decimation.
class Decimation final : private OpenMesh::Decimater::Observer {
 public:
  Decimation(SurfaceMesh& mesh, const EdgeCollapseHierarchy::Options& options,
             MeshHierarchy& hierarchy, std::vector<int> finest_vertices, NextTarget next_target)
      : Observer(/*notification interval=*/1),
        mesh_(mesh),
        decimater_(mesh),
        hierarchy_(hierarchy),
        fine_vertices_(std::move(finest_vertices)),
        next_target_(std::move(next_target)),
        collapsed_into_(mesh.n_vertices()) {
    std::iota(collapsed_into_.begin(), collapsed_into_.end(), 0);
    // ModNormalFlippingT compares against the face normals (and complains on omerr if absent).
    mesh_.request_face_normals();
    mesh_.update_face_normals();
    decimater_.add(quadric_);
    decimater_.add(normal_flipping_);
    decimater_.add(recorder_);
    decimater_.module(quadric_).unset_max_err();  // priority only, no error bound
    decimater_.module(normal_flipping_)
        .set_max_normal_deviation(float(options.max_normal_deviation));
    if (options.max_aspect_ratio > 0.0) {
      decimater_.add(aspect_ratio_);
      decimater_.module(aspect_ratio_).set_aspect_ratio(float(options.max_aspect_ratio));
    }
    decimater_.module(recorder_).collapsed_into = &collapsed_into_;
    HARAP_CHECK(decimater_.initialize(), "OpenMesh's decimater did not initialize");
    decimater_.set_observer(this);
  }
  ~Decimation() override { mesh_.release_face_normals(); }
  Decimation(const Decimation&) = delete;
  Decimation& operator=(const Decimation&) = delete;

  /// Decimates until the last level is out or no legal collapse is left; a partly reached
  /// target still gives a (last) level.
  void Run() {
    level_start_ = remaining_ = mesh_.n_vertices();
    target_ = next_target_(remaining_);
    if (target_ == 0 || target_ >= remaining_) return;
    decimater_.decimate(0);  // 0: no collapse limit; notify() and abort() stop it
    if (!done_ && remaining_ < level_start_) AddLevel();
  }

 private:
  // Observer: called after every collapse with the number of collapses so far.
  void notify(std::size_t collapses) override {
    remaining_ = mesh_.n_vertices() - collapses;
    if (remaining_ > target_) return;
    AddLevel();
    target_ = next_target_(remaining_);
    done_ = target_ == 0 || target_ >= remaining_;
  }
  bool abort() const override { return done_; }

  /// The surviving vertex that OpenMesh vertex v was collapsed into (v itself if it survives).
  int Survivor(int v) {
    while (collapsed_into_[v] != v) {
      collapsed_into_[v] = collapsed_into_[collapsed_into_[v]];  // path halving
      v = collapsed_into_[v];
    }
    return v;
  }

  /// Appends the current mesh as the next coarser level and maps the vertices of the level
  /// before it (their OpenMesh vertices in fine_vertices_, -1 for none) to it.
  void AddLevel() {
    std::vector<Index> coarse_index(mesh_.n_vertices(), kNoVertex);
    std::vector<int> coarse_vertices;
    coarse_vertices.reserve(remaining_);
    for (const auto v : mesh_.vertices()) {  // skips deleted vertices
      coarse_index[v.idx()] = Index(coarse_vertices.size());
      coarse_vertices.push_back(v.idx());
    }
    HierarchyLevel coarse_level;
    Mesh& coarse = coarse_level.mesh;
    coarse.planar = hierarchy_.levels.back().mesh.planar;
    coarse.vertices.resize(Index(coarse_vertices.size()), 3);
    for (std::size_t c = 0; c < coarse_vertices.size(); ++c) {
      const auto& p = mesh_.point(SurfaceMesh::VertexHandle(coarse_vertices[c]));
      coarse.vertices.row(Index(c)) << p[0], p[1], p[2];
    }
    std::vector<Index> elements;
    elements.reserve(3 * mesh_.n_faces());
    std::vector<unsigned char> used(coarse_vertices.size(), 0);
    for (const auto face : mesh_.faces()) {  // skips deleted faces
      for (const auto v : mesh_.fv_range(face)) {
        const Index c = coarse_index[v.idx()];
        elements.push_back(c);
        used[c] = 1;
      }
    }
    coarse.elements = Eigen::Map<const Elements>(elements.data(), Index(elements.size() / 3), 3);
    // Legal collapses never leave a vertex without faces.
    HARAP_CHECK(std::find(used.begin(), used.end(), 0) == used.end(),
                "a vertex of the decimated mesh has no triangle");

    HierarchyLevel& fine = hierarchy_.levels.back();
    const std::size_t n = fine_vertices_.size();
    fine.coarse_vertex.assign(n, kNoVertex);
    fine.in_cluster.assign(n, 0);
    for (std::size_t i = 0; i < n; ++i) {
      if (fine_vertices_[i] < 0) continue;
      fine.coarse_vertex[i] = coarse_index[Survivor(fine_vertices_[i])];
      fine.in_cluster[i] = 1;
    }
    hierarchy_.levels.push_back(std::move(coarse_level));
    fine_vertices_ = std::move(coarse_vertices);
    level_start_ = remaining_;
  }

  using Decimater = OpenMesh::Decimater::DecimaterT<SurfaceMesh>;
  SurfaceMesh& mesh_;
  Decimater decimater_;
  OpenMesh::Decimater::ModQuadricT<SurfaceMesh>::Handle quadric_;
  OpenMesh::Decimater::ModNormalFlippingT<SurfaceMesh>::Handle normal_flipping_;
  OpenMesh::Decimater::ModAspectRatioT<SurfaceMesh>::Handle aspect_ratio_;
  ModCollapseRecorderT<SurfaceMesh>::Handle recorder_;
  MeshHierarchy& hierarchy_;
  std::vector<int> fine_vertices_;  ///< OpenMesh vertex of each vertex of the last level
  NextTarget next_target_;
  std::vector<int> collapsed_into_;
  std::size_t remaining_ = 0;    ///< vertices left
  std::size_t level_start_ = 0;  ///< vertices of the last level (OpenMesh's count)
  std::size_t target_ = 0;       ///< vertex count of the next level
  bool done_ = false;
};

/// The octree's vertex counts of levels 1, 2, ... for `mesh` (default octree options otherwise).
std::vector<Index> OctreeLevelCounts(const Mesh& mesh, const EdgeCollapseHierarchy::Options& ours,
                                     const Context& context) {
  OctreeHierarchy::Options options;
  static_cast<LevelLimits&>(options) = ours;
  const MeshHierarchy octree = OctreeHierarchy(options).Build(mesh, context);
  std::vector<Index> counts;
  for (int l = 1; l < octree.num_levels(); ++l) {
    counts.push_back(octree.levels[l].mesh.num_vertices());
  }
  return counts;
}

// Read with these ranges and checked against them by Validate().
constexpr Range kRatioRange = Range::HalfOpen(0.0, 1.0);
constexpr Range kNormalDeviationRange = Range::LeftOpen(0.0, 180.0);

// max_aspect_ratio is 0 (no check) or at least 1: not one range.
bool ValidAspectRatio(double ratio) { return ratio == 0.0 || ratio >= 1.0; }
constexpr std::string_view kAspectRatioRule = "which is not 0 (no check) or >= 1";

}  // namespace

EdgeCollapseHierarchy::Options EdgeCollapseHierarchy::Options::FromConfig(OptionReader node) {
  Options options;
  options.ratio = node.Get("ratio", options.ratio,
                           "vertices kept per level; 0 = the octree's level vertex counts for the "
                           "same mesh",
                           kRatioRange);
  options.ReadLimits(node);
  options.max_normal_deviation = node.Get(
      "max_normal_deviation", options.max_normal_deviation,
      "largest turn of a face normal a collapse may cause, in degrees", kNormalDeviationRange);
  options.max_aspect_ratio =
      node.Get("max_aspect_ratio", options.max_aspect_ratio,
               "largest aspect ratio (longest edge / its height) of a face a collapse may create "
               "unless it improves the worst one around it (>= 1; 0 = no check)");
  if (!ValidAspectRatio(options.max_aspect_ratio)) {
    node.Fail("max_aspect_ratio",
              fmt::format("is {}, {}", options.max_aspect_ratio, kAspectRatioRule));
  }
  node.RejectUnknownKeys();
  return options;
}

void EdgeCollapseHierarchy::Options::Validate() const {
  std::vector<std::string> problems = RangeProblems({{"ratio", ratio, kRatioRange}});
  for (std::string& problem : LimitProblems()) problems.push_back(std::move(problem));
  for (std::string& problem :
       RangeProblems({{"max_normal_deviation", max_normal_deviation, kNormalDeviationRange}})) {
    problems.push_back(std::move(problem));
  }
  if (!ValidAspectRatio(max_aspect_ratio)) {
    problems.push_back(
        fmt::format("max_aspect_ratio is {}, {}", max_aspect_ratio, kAspectRatioRule));
  }
  ThrowIfInvalidOptions(kName, problems);
}

EdgeCollapseHierarchy::EdgeCollapseHierarchy(const Options& options) : options_(options) {
  options_.Validate();
}

MeshHierarchy EdgeCollapseHierarchy::Build(const Mesh& mesh, const Context& context) const {
  MeshHierarchy hierarchy = InputLevelOnly(mesh);
  if (mesh.num_elements() == 0) return hierarchy;
  if (mesh.kind() == ElementKind::kTetrahedron) {
    throw InputError(
        fmt::format("the edge_collapse hierarchy decimates triangle surfaces, but this mesh has {} "
                    "tetrahedra; use the octree hierarchy for volumetric meshes",
                    mesh.num_elements()));
  }
  HARAP_CHECK(mesh.simplex_size() == 3, "elements have {} vertices; edge_collapse needs triangles",
              mesh.simplex_size());
  HARAP_CHECK(mesh.elements.minCoeff() >= 0 && mesh.elements.maxCoeff() < mesh.num_vertices(),
              "element indices must lie in [0, {})", mesh.num_vertices());
  if (mesh.num_vertices() <= options_.min_vertices || options_.max_levels == 1) return hierarchy;

  Surface surface = BuildSurface(mesh);
  const std::vector<Index> octree_counts =
      options_.ratio > 0.0 ? std::vector<Index>() : OctreeLevelCounts(mesh, options_, context);
  auto next_target = [&](std::size_t remaining) -> std::size_t {
    if (options_.max_levels > 0 && hierarchy.num_levels() >= options_.max_levels) return 0;
    if (hierarchy.levels.back().mesh.num_vertices() <= options_.min_vertices) return 0;
    if (options_.ratio > 0.0) {
      const std::size_t target = std::size_t(std::ceil(options_.ratio * double(remaining)));
      return options_.KeepsLevel(Index(target)) ? target : 0;
    }
    const std::size_t level = std::size_t(hierarchy.num_levels());  // the one to build
    return level <= octree_counts.size() ? std::size_t(octree_counts[level - 1]) : 0;
  };
  Decimation(surface.mesh, options_, hierarchy, std::move(surface.vertex_of_input), next_target)
      .Run();
  return hierarchy;
}

}  // namespace harap
