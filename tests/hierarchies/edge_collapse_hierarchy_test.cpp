// SPDX-License-Identifier: MIT
// EdgeCollapseHierarchy: nested, manifold levels from OpenMesh's decimater, the fine → coarse
// maps from the collapse sequence, the octree's level counts, input it cannot take, and a
// hierarchical optimization on it.
#include "hierarchies/builders/edge_collapse_hierarchy.h"

#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <numeric>
#include <set>
#include <string>
#include <vector>

#include "api/builtins.h"
#include "framework/disjoint_sets.h"
#include "framework/error.h"
#include "hierarchies/builders/octree_hierarchy.h"
#include "io/mesh_io.h"
#include "tests/support/shared_data.h"
#include "tests/support/test_factory.h"
#include "tests/support/test_meshes.h"

using namespace harap;
using namespace harap::testing;

namespace {

EdgeCollapseHierarchy::Options WithMinVertices(int min_vertices, double ratio = 0.0) {
  EdgeCollapseHierarchy::Options options;
  options.min_vertices = min_vertices;
  options.ratio = ratio;
  return options;
}

MeshHierarchy BuildEdgeCollapse(const Mesh& mesh, const EdgeCollapseHierarchy::Options& options,
                                int threads = 0) {
  return EdgeCollapseHierarchy(options).Build(mesh, Context::WithThreads(threads));
}

std::vector<Index> LevelCounts(const MeshHierarchy& h) {
  std::vector<Index> counts;
  for (const auto& level : h.levels) counts.push_back(level.mesh.num_vertices());
  return counts;
}

/// Σ over the vertices of (number of fans − 1), a fan being a set of triangles at the vertex
/// connected through edges at the vertex (components of the vertex's link): the copies edge
/// collapse makes of non-manifold vertices.
Index ExtraFans(const Mesh& mesh) {
  std::vector<std::vector<std::pair<Index, Index>>> link(mesh.num_vertices());
  for (Index t = 0; t < mesh.num_elements(); ++t) {
    for (int k = 0; k < 3; ++k) {
      link[mesh.elements(t, k)].emplace_back(mesh.elements(t, (k + 1) % 3),
                                             mesh.elements(t, (k + 2) % 3));
    }
  }
  Index extra = 0;
  for (const auto& edges : link) {
    std::map<Index, Index> local;
    for (const auto& [b, c] : edges) {
      local.emplace(b, Index(local.size()));
      local.emplace(c, Index(local.size()));
    }
    DisjointSets<Index> classes(Index(local.size()));
    for (const auto& [b, c] : edges) classes.Unite(local[b], local[c]);
    Index components = 0;
    for (Index i = 0; i < Index(local.size()); ++i) components += classes.Find(i) == i;
    extra += std::max<Index>(components - 1, 0);
  }
  return extra;
}

/// A manifold triangle surface: no repeated vertex in a triangle, every edge in at most two
/// triangles that traverse it in opposite directions, every vertex's triangles one fan. Returns
/// the Euler characteristic V − E + F.
Index CheckManifold(const Mesh& mesh) {
  std::map<std::pair<Index, Index>, std::vector<std::pair<Index, Index>>> edges;  // → directed
  for (Index t = 0; t < mesh.num_elements(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const Index a = mesh.elements(t, k), b = mesh.elements(t, (k + 1) % 3);
      REQUIRE(a != b);
      edges[std::minmax(a, b)].emplace_back(a, b);
    }
  }
  Index bad_edges = 0;
  for (const auto& [edge, directed] : edges) {
    if (directed.size() > 2 || (directed.size() == 2 && directed[0] == directed[1])) ++bad_edges;
  }
  CHECK(bad_edges == 0);
  CHECK(ExtraFans(mesh) == 0);
  return mesh.num_vertices() - Index(edges.size()) + mesh.num_elements();
}

/// The largest aspect ratio (longest edge / its height) of the triangles.
double MaxAspectRatio(const Mesh& mesh) {
  double worst = 0.0;
  for (Index t = 0; t < mesh.num_elements(); ++t) {
    const Eigen::Vector3d a = mesh.vertices.row(mesh.elements(t, 0));
    const Eigen::Vector3d b = mesh.vertices.row(mesh.elements(t, 1));
    const Eigen::Vector3d c = mesh.vertices.row(mesh.elements(t, 2));
    const double longest =
        std::max({(a - b).squaredNorm(), (b - c).squaredNorm(), (c - a).squaredNorm()});
    worst = std::max(worst, longest / (b - a).cross(c - a).norm());
  }
  return worst;
}

/// The contract of every level, plus what edge collapse promises: nested levels (coarse vertices
/// at the rest positions of fine vertices of their own cluster), strictly fewer vertices,
/// manifold levels, every referenced vertex in the cluster of a valid coarse vertex, clusters
/// connected in the fine mesh.
void CheckLevels(const Mesh& input, const MeshHierarchy& h) {
  REQUIRE(h.num_levels() >= 1);
  const Index copies = ExtraFans(input);
  CHECK(h.levels[0].mesh.vertices == input.vertices);
  CHECK(h.levels[0].mesh.elements == input.elements);
  const std::vector<bool> referenced = ReferencedVertices(input);
  for (int l = 0; l < h.num_levels(); ++l) {
    INFO("level " << l);
    const HierarchyLevel& level = h.levels[l];
    const Mesh& fine = level.mesh;
    CHECK(fine.simplex_size() == 3);
    CHECK(fine.planar == input.planar);
    REQUIRE(fine.num_elements() > 0);
    CHECK(fine.elements.minCoeff() >= 0);
    CHECK(fine.elements.maxCoeff() < fine.num_vertices());
    if (l > 0) {
      CheckManifold(fine);
      const std::vector<bool> used = ReferencedVertices(fine);
      CHECK(std::count(used.begin(), used.end(), false) == 0);
    }
    if (l == h.num_levels() - 1) {
      CHECK(level.coarse_vertex.empty());
      CHECK(level.in_cluster.empty());
      continue;
    }
    const Mesh& coarse = h.levels[l + 1].mesh;
    const Index n = fine.num_vertices();
    CHECK(coarse.num_vertices() <
          (l == 0 ? Index(std::count(referenced.begin(), referenced.end(), true)) : n));
    REQUIRE(level.coarse_vertex.size() == size_t(n));
    REQUIRE(level.in_cluster.size() == size_t(n));

    // Each referenced fine vertex lies in the cluster of a valid coarse vertex; each coarse
    // vertex sits exactly where one of its members is (the collapses' survivor).
    std::vector<bool> at_member(coarse.num_vertices(), false);
    Index unmapped = 0;
    for (Index i = 0; i < n; ++i) {
      const Index c = level.coarse_vertex[i];
      const bool used = l > 0 || referenced[i];
      if (!used) {
        CHECK(c == kNoVertex);
        CHECK(level.in_cluster[i] == 0);
        continue;
      }
      if (c == kNoVertex || c >= coarse.num_vertices() || !level.in_cluster[i]) {
        ++unmapped;
        continue;
      }
      if (fine.vertices.row(i) == coarse.vertices.row(c)) at_member[c] = true;
    }
    CHECK(unmapped == 0);
    const auto coarse_at_member = std::count(at_member.begin(), at_member.end(), true);
    // A copy made of a non-manifold vertex may survive without any input vertex mapped to it.
    CHECK(coarse_at_member >= coarse.num_vertices() - (l == 0 ? copies : 0));

    // Clusters are connected through fine edges inside the cluster (on level 0, a cluster
    // holding a copy may be connected only through the copy, which is not a level-0 vertex).
    DisjointSets<Index> classes(n);
    for (Index t = 0; t < fine.num_elements(); ++t) {
      for (int k = 0; k < 3; ++k) {
        const Index a = fine.elements(t, k), b = fine.elements(t, (k + 1) % 3);
        if (level.coarse_vertex[a] == level.coarse_vertex[b]) classes.Unite(a, b);
      }
    }
    std::map<Index, std::set<Index>> pieces;  // coarse vertex → components of its cluster
    for (Index i = 0; i < n; ++i) {
      if (level.coarse_vertex[i] != kNoVertex)
        pieces[level.coarse_vertex[i]].insert(classes.Find(i));
    }
    Index split_clusters = 0;
    for (const auto& [c, components] : pieces) split_clusters += components.size() > 1;
    CHECK(split_clusters <= (l == 0 ? copies : 0));
  }
  // Composed maps reach every level.
  for (int l = 1; l < h.num_levels(); ++l) {
    Index unmapped = 0;
    for (Index i = 0; i < input.num_vertices(); ++i) {
      const Index v = h.MapFinestVertex(i, l);
      if (referenced[i] && (v == kNoVertex || v >= h.levels[l].mesh.num_vertices())) ++unmapped;
      if (!referenced[i] && v != kNoVertex) ++unmapped;
    }
    INFO("level " << l);
    CHECK(unmapped == 0);
  }
}

/// Two icospheres sharing one vertex: closed, edge-manifold, one pinched vertex (like the cow).
Mesh PinchedSpheres(int subdivisions) {
  const Mesh sphere = Icosphere(subdivisions);
  Mesh other = sphere;
  // Put the second sphere's vertex 0 onto the first's vertex 0, then identify the two.
  const Eigen::RowVector3d p = sphere.vertices.row(0);
  other.vertices = (-other.vertices).rowwise() + 2.0 * p;
  for (Index t = 0; t < other.num_elements(); ++t)
    std::swap(other.elements(t, 1), other.elements(t, 2));
  Mesh both = Concatenate(sphere, other);
  const Index shift = sphere.num_vertices();
  for (Index t = sphere.num_elements(); t < both.num_elements(); ++t) {
    for (int k = 0; k < 3; ++k) {
      if (both.elements(t, k) == shift) both.elements(t, k) = 0;
    }
  }
  return both;  // vertex `shift` is now unreferenced
}

}  // namespace

TEST_CASE("edge_collapse: nested manifold levels on generated meshes",
          "[hierarchies][edge_collapse]") {
  const std::vector<std::pair<std::string, Mesh>> meshes = {
      {"icosphere", Icosphere(4)}, {"tube", Tube(60, 40)}, {"grid", Grid(60, 45)}};
  for (const auto& [name, mesh] : meshes) {
    for (double ratio : {0.0, 0.3}) {
      DYNAMIC_SECTION(name << " ratio " << ratio) {
        const MeshHierarchy h = BuildEdgeCollapse(mesh, WithMinVertices(20, ratio));
        CHECK(h.num_levels() >= 4);
        CheckLevels(mesh, h);
        CHECK(h.levels.back().mesh.num_vertices() <= 20);
        // Collapses keep the topology: the Euler characteristic of every level is the input's.
        const Index euler = CheckManifold(mesh);
        for (const auto& level : h.levels) CHECK(CheckManifold(level.mesh) == euler);
      }
    }
  }
}

TEST_CASE("edge_collapse: by default the octree's vertex counts, else the ratio",
          "[hierarchies][edge_collapse]") {
  const Mesh mesh = Concatenate(Tube(60, 48), Icosphere(4));
  for (int min_vertices : {100, 750}) {
    DYNAMIC_SECTION("min_vertices " << min_vertices) {
      OctreeHierarchy::Options octree;
      octree.min_vertices = min_vertices;
      const MeshHierarchy reference = OctreeHierarchy(octree).Build(mesh, Context());
      REQUIRE(reference.num_levels() >= 2);
      const MeshHierarchy h = BuildEdgeCollapse(mesh, WithMinVertices(min_vertices));
      CHECK(LevelCounts(h) == LevelCounts(reference));
    }
  }
  SECTION("coarsest = at_least: the octree's counts, and no ratio level below the bound") {
    EdgeCollapseHierarchy::Options options = WithMinVertices(750);
    options.coarsest = LevelLimits::Coarsest::kAtLeast;
    OctreeHierarchy::Options octree;
    octree.coarsest = LevelLimits::Coarsest::kAtLeast;
    const MeshHierarchy reference = OctreeHierarchy(octree).Build(mesh, Context());
    CHECK(LevelCounts(BuildEdgeCollapse(mesh, options)) == LevelCounts(reference));
    options.ratio = 0.25;
    const MeshHierarchy h = BuildEdgeCollapse(mesh, options);
    REQUIRE(h.num_levels() >= 2);
    CHECK(h.levels.back().mesh.num_vertices() >= 750);
    CHECK(std::ceil(0.25 * h.levels.back().mesh.num_vertices()) < 750);
  }
  SECTION("max_levels limits both") {
    EdgeCollapseHierarchy::Options options = WithMinVertices(40);
    options.max_levels = 3;
    CHECK(BuildEdgeCollapse(mesh, options).num_levels() == 3);
    options.max_levels = 1;
    CHECK(BuildEdgeCollapse(mesh, options).num_levels() == 1);
  }
  SECTION("ratio") {
    const MeshHierarchy h = BuildEdgeCollapse(mesh, WithMinVertices(100, 0.25));
    REQUIRE(h.num_levels() >= 3);
    for (int l = 1; l < h.num_levels(); ++l) {
      const Index fine = h.levels[l - 1].mesh.num_vertices();
      CHECK(h.levels[l].mesh.num_vertices() == Index(std::ceil(0.25 * double(fine))));
    }
    CHECK(h.levels[h.num_levels() - 2].mesh.num_vertices() > 100);
    CHECK(h.levels.back().mesh.num_vertices() <= 100);
  }
  SECTION("small enough already: one level") {
    CHECK(BuildEdgeCollapse(Icosphere(2), EdgeCollapseHierarchy::Options{}).num_levels() == 1);
  }
}

TEST_CASE("edge_collapse: unreferenced vertices map to no coarse vertex",
          "[hierarchies][edge_collapse]") {
  Mesh mesh = Icosphere(4);
  const Index n = mesh.num_vertices();
  mesh.vertices.conservativeResize(n + 2, 3);
  mesh.vertices.row(n) << 0.0, 0.0, 0.0;
  mesh.vertices.row(n + 1) = mesh.vertices.row(5);
  const MeshHierarchy h = BuildEdgeCollapse(mesh, WithMinVertices(30, 0.3));
  REQUIRE(h.num_levels() >= 3);
  CheckLevels(mesh, h);
  for (Index i = n; i < n + 2; ++i) {
    CHECK(h.levels[0].coarse_vertex[i] == kNoVertex);
    CHECK(h.levels[0].in_cluster[i] == 0);
  }
  // The coarse levels do not see them.
  Mesh referenced_only = mesh;
  referenced_only.vertices.conservativeResize(n, 3);
  const MeshHierarchy reference = BuildEdgeCollapse(referenced_only, WithMinVertices(30, 0.3));
  REQUIRE(reference.num_levels() == h.num_levels());
  for (int l = 1; l < h.num_levels(); ++l) {
    CHECK(reference.levels[l].mesh.vertices == h.levels[l].mesh.vertices);
    CHECK(reference.levels[l].mesh.elements == h.levels[l].mesh.elements);
  }
}

TEST_CASE("edge_collapse: several components, planar meshes, determinism",
          "[hierarchies][edge_collapse]") {
  SECTION("components are decimated together and each keeps its topology") {
    const Mesh mesh = Concatenate(Concatenate(Tube(40, 32), Icosphere(3)), Icosphere(0));
    const MeshHierarchy h = BuildEdgeCollapse(mesh, WithMinVertices(0, 0.5));
    REQUIRE(h.num_levels() >= 4);
    CheckLevels(mesh, h);
    // Tube (χ = 0) + two spheres (χ = 2 each); a sphere stops at a tetrahedron (4 vertices).
    for (const auto& level : h.levels) CHECK(CheckManifold(level.mesh) == 4);
  }
  SECTION("planar meshes stay in the plane, without needles") {
    Mesh mesh = Grid(64, 40);
    mesh.planar = true;
    const MeshHierarchy h = BuildEdgeCollapse(mesh, WithMinVertices(20));
    REQUIRE(h.num_levels() >= 3);
    CheckLevels(mesh, h);
    for (const auto& level : h.levels) {
      CHECK(level.mesh.planar);
      CHECK(level.mesh.vertices.col(2).cwiseAbs().maxCoeff() == 0.0);
      // Every quadric error is 0 here; the aspect-ratio check keeps the faces usable.
      CHECK(MaxAspectRatio(level.mesh) <= 20.0);
    }
    EdgeCollapseHierarchy::Options unchecked = WithMinVertices(20);
    unchecked.max_aspect_ratio = 0.0;
    const MeshHierarchy needles = BuildEdgeCollapse(mesh, unchecked);
    REQUIRE(needles.num_levels() >= 2);
    CHECK(MaxAspectRatio(needles.levels[1].mesh) > 20.0);
  }
  SECTION("the same hierarchy whatever the thread count") {
    const Mesh mesh = Concatenate(Tube(60, 48), Icosphere(4));
    const MeshHierarchy a = BuildEdgeCollapse(mesh, WithMinVertices(40), 1);
    const MeshHierarchy b = BuildEdgeCollapse(mesh, WithMinVertices(40), 2);
    REQUIRE(a.num_levels() == b.num_levels());
    for (int l = 0; l < a.num_levels(); ++l) {
      CHECK(a.levels[l].mesh.vertices == b.levels[l].mesh.vertices);
      CHECK(a.levels[l].mesh.elements == b.levels[l].mesh.elements);
      CHECK(a.levels[l].coarse_vertex == b.levels[l].coarse_vertex);
    }
  }
}

TEST_CASE("edge_collapse: a non-manifold vertex is split, non-manifold edges are rejected",
          "[hierarchies][edge_collapse]") {
  SECTION("pinched vertex: decimated as two surfaces") {
    const Mesh mesh = PinchedSpheres(3);
    const MeshHierarchy h = BuildEdgeCollapse(mesh, WithMinVertices(30, 0.4));
    REQUIRE(h.num_levels() >= 3);
    CHECK(ExtraFans(mesh) == 1);
    CheckLevels(mesh, h);
    // The pinched vertex is cut open: the coarse levels hold two closed spheres.
    for (int l = 1; l < h.num_levels(); ++l) CHECK(CheckManifold(h.levels[l].mesh) == 4);
  }
  auto error = [](const Mesh& mesh) -> std::string {
    try {
      BuildEdgeCollapse(mesh, WithMinVertices(0));
    } catch (const InputError& e) {
      return e.what();
    }
    return "no InputError";
  };
  using Catch::Matchers::Contains;
  SECTION("an edge of three triangles") {
    Mesh mesh = Grid(10, 10);
    const Index tip = mesh.num_vertices();
    mesh.vertices.conservativeResize(tip + 1, 3);
    mesh.vertices.row(tip) << 0.5, 0.5, 1.0;
    const Index t = mesh.num_elements();
    mesh.elements.conservativeResize(t + 1, 3);
    mesh.elements.row(t) << mesh.elements(40, 0), mesh.elements(40, 1), tip;  // a fin
    // Triangle 40's first edge 22 → 23 is also the edge of triangle 23 (the quad below).
    REQUIRE(t == 162);
    CHECK_THAT(error(mesh), Contains("1 edge(s) shared by more than two triangles") &&
                                Contains("edge 22–23, triangles 23, 40, 162") &&
                                Contains("octree"));
  }
  SECTION("inconsistent orientation") {
    Mesh mesh = Grid(10, 10);
    // Triangle 17 = (8, 19, 18) turned over: each of its three edges now runs like its
    // neighbour's; the first (by smaller vertex, then larger) is 8–18, shared with triangle 14.
    std::swap(mesh.elements(17, 1), mesh.elements(17, 2));
    CHECK_THAT(error(mesh), Contains("3 edge(s) whose two triangles traverse it in the same "
                                     "direction") &&
                                Contains("edge 8–18, triangles 14 and 17"));
  }
  SECTION("a triangle repeating a vertex") {
    Mesh mesh = Grid(10, 10);
    mesh.elements(5, 2) = mesh.elements(5, 0);
    CHECK_THAT(error(mesh), Contains("repeat a vertex") && Contains("triangle 5"));
  }
  SECTION("tetrahedra") {
    Mesh mesh;
    mesh.vertices.resize(4, 3);
    mesh.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
    mesh.elements.resize(1, 4);
    mesh.elements << 0, 1, 2, 3;
    CHECK_THAT(error(mesh), Contains("tetrahedra") && Contains("octree"));
  }
}

TEST_CASE("edge_collapse: options from config", "[hierarchies][edge_collapse]") {
  const Registries registries = MakeBuiltinRegistries();
  REQUIRE(registries.hierarchies.Contains("edge_collapse"));
  SECTION("defaults and listing") {
    const auto options = EdgeCollapseHierarchy::Options::FromConfig(OptionReader(ConfigNode()));
    CHECK(options.ratio == 0.0);
    CHECK(options.min_vertices == 750);
    CHECK(options.max_levels == 0);
    CHECK(options.max_normal_deviation == 90.0);
    std::vector<std::string> keys;
    for (const auto& option : registries.hierarchies.DescribeOptions("edge_collapse")) {
      keys.push_back(option.key);
    }
    CHECK(options.max_aspect_ratio == 20.0);
    CHECK(keys == std::vector<std::string>{"ratio", "min_vertices", "coarsest", "max_levels",
                                           "max_normal_deviation", "max_aspect_ratio"});
  }
  SECTION("values are read") {
    const ConfigNode config = ConfigNode::Parse(
        "[hierarchy]\nratio = 0.5\nmin_vertices = 100\nmax_levels = 4\n"
        "max_normal_deviation = 45\nmax_aspect_ratio = 0\n",
        "test");
    const auto options =
        EdgeCollapseHierarchy::Options::FromConfig(OptionReader(config.Child("hierarchy")));
    CHECK(options.ratio == 0.5);
    CHECK(options.min_vertices == 100);
    CHECK(options.max_levels == 4);
    CHECK(options.max_normal_deviation == 45.0);
    CHECK(options.max_aspect_ratio == 0.0);
  }
  SECTION("unknown keys and bad values are rejected") {
    auto error = [&](const std::string& table) -> std::string {
      try {
        const ConfigNode config = ConfigNode::Parse("[hierarchy]\n" + table, "test");
        registries.hierarchies.Create("edge_collapse", config.Child("hierarchy"));
      } catch (const ConfigError& e) {
        return e.what();
      }
      return "no ConfigError";
    };
    using Catch::Matchers::Contains;
    CHECK_THAT(error("ratios = 0.5\n"), Contains("ratios") && Contains("ratio") &&
                                            Contains("min_vertices") &&
                                            Contains("max_normal_deviation"));
    CHECK_THAT(error("ratio = 1.0\n"), Contains("'hierarchy.ratio' is 1, which is not in [0, 1)"));
    CHECK_THAT(error("ratio = -0.5\n"), Contains("ratio"));
    CHECK_THAT(error("min_vertices = -1\n"), Contains("min_vertices"));
    CHECK_THAT(error("max_levels = -2\n"), Contains("max_levels"));
    CHECK_THAT(error("max_normal_deviation = 0\n"), Contains("max_normal_deviation"));
    CHECK_THAT(error("max_normal_deviation = 181\n"), Contains("max_normal_deviation"));
    CHECK_THAT(error("max_aspect_ratio = 0.5\n"), Contains("max_aspect_ratio"));
  }
}

TEST_CASE("edge_collapse: hierarchical ARAP on it lowers the energy level by level",
          "[hierarchies][edge_collapse]") {
  // A tube (4000 vertices) with its bottom ring fixed and its top ring turned and shifted.
  constexpr int kRings = 100, kSegments = 40;
  Mesh mesh = Tube(kRings, kSegments);
  mesh.vertices.col(2) *= 4.0;
  DeformationProblem problem;
  problem.mesh = &mesh;
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
  for (int s = 0; s < kSegments; ++s) problem.constraints.indices.push_back(s);
  for (int s = 0; s < kSegments; ++s) {
    problem.constraints.indices.push_back((kRings - 1) * kSegments + s);
  }
  problem.constraints.targets.resize(problem.constraints.indices.size(), 3);
  for (size_t k = 0; k < problem.constraints.indices.size(); ++k) {
    Eigen::Vector3d p = mesh.vertices.row(problem.constraints.indices[k]);
    if (k >= kSegments) p = turn * p + Eigen::Vector3d(0.0, 1.0, -1.5);
    problem.constraints.targets.row(k) = p.transpose();
  }
  for (const char* upsampler : {"rotations", "positions"}) {
    DYNAMIC_SECTION("upsampler " << upsampler) {
      // Fixed coarse targets make every level a plain local/global run, which must be monotone.
      TestSetup setup(
          fmt::format("[optimizer]\ntype = \"hierarchical\"\ntolerance = "
                      "1e-7\ntargets_follow_rotations = false\n"
                      "[hierarchy]\ntype = \"edge_collapse\"\nmin_vertices = 100\n"
                      "[upsampler]\ntype = \"{}\"\n",
                      upsampler));
      std::map<int, std::vector<double>> energies;
      Context context;
      context.iteration_callback = [&](const IterationSummary& s) {
        energies[s.level].push_back(s.energy);
        return CallbackAction::kContinue;
      };
      const OptimizeResult result =
          setup.MakeOptimizer()->Optimize(problem, setup.factory, context);
      REQUIRE(result.levels.size() >= 3);
      for (const auto& [level, trace] : energies) {
        REQUIRE(!trace.empty());
        for (size_t i = 1; i < trace.size(); ++i) {
          CHECK(trace[i] <= trace[i - 1] * (1.0 + 1e-12) + 1e-15);
        }
      }
      CHECK(energies[0].back() < energies[0].front());
      CHECK(result.converged);
      // The same problem with classic ARAP stops higher (the reason for a hierarchy).
      TestSetup classic("[optimizer]\ntype = \"classic\"\ntolerance = 1e-7\n");
      const OptimizeResult flat =
          classic.MakeOptimizer()->Optimize(problem, classic.factory, Context());
      CHECK(result.energy < flat.energy);
    }
  }
}

TEST_CASE("edge_collapse: shared meshes with non-manifold vertices and edges",
          "[hierarchies][edge_collapse][shared]") {
  // The cow has one pinched vertex; the teapot 38 non-manifold vertices and 4 open parts.
  for (const char* name : {"cow.ply.xz", "teapot.ply.xz"}) {
    DYNAMIC_SECTION(name) {
      HARAP_REQUIRE_SHARED(file, std::string("meshes/") + name);
      const Mesh mesh = ReadMesh(file);
      CHECK(ExtraFans(mesh) > 0);
      const MeshHierarchy h = BuildEdgeCollapse(mesh, EdgeCollapseHierarchy::Options{});
      INFO("levels " << h.num_levels());
      CHECK(h.num_levels() >= 3);
      CheckLevels(mesh, h);
      CHECK(h.levels.back().mesh.num_vertices() <= 750);
    }
  }
  SECTION("dragon-res2: 2,534 edges with more than two triangles") {
    HARAP_REQUIRE_SHARED(file, "meshes/dragon-res2.obj.xz");
    try {
      BuildEdgeCollapse(ReadMesh(file), EdgeCollapseHierarchy::Options{});
      FAIL("no InputError");
    } catch (const InputError& e) {
      CHECK_THAT(e.what(), Catch::Matchers::Contains("2534 edge(s) shared by more than two "
                                                     "triangles"));
    }
  }
}
