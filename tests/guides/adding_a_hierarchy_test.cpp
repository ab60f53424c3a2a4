// SPDX-License-Identifier: MIT
// The example of docs/adding-a-hierarchy.md, built and run by the suite: a hierarchy written as
// the guide says, registered by name and used by the hierarchical optimizer through the normal
// machinery. The guide quotes the marked regions word for word (checked below).
#include <catch2/catch.hpp>
#include <cmath>

#include "api/builtins.h"
#include "tests/guides/guide_support.h"
#include "tests/support/test_meshes.h"

// [guide:hierarchy-header]
#include <string_view>

#include "framework/config.h"
#include "framework/hierarchy.h"

namespace harap {

/// Vertex clustering on regular grids: level l + 1 merges the vertices of level l that fall in
/// one cell of a grid whose cells are `growth` times larger than the last one's, at the mean of
/// their positions; elements whose corners land in fewer distinct clusters than corners vanish.
/// (The octree hierarchy is this idea with a topology check and nested cells.)
class GridClusteringHierarchy final : public Hierarchy {
 public:
  static constexpr std::string_view kName = "grid_clustering";

  struct Options {
    /// Cells along the bounding box's longest side on level 1.
    int cells = 16;
    /// Each coarser level's cells are this many times larger.
    double growth = 2.0;
    /// Stop once a level has at most this many vertices.
    int min_vertices = 50;
    static Options FromConfig(OptionReader node);
  };

  explicit GridClusteringHierarchy(const Options& options) : options_(options) {}

  MeshHierarchy Build(const Mesh& mesh, const Context& context) const override;

 private:
  Options options_;
};

}  // namespace harap
// [/guide:hierarchy-header]

// [guide:hierarchy-source]
#include <algorithm>
#include <array>
#include <map>
#include <set>

namespace harap {

GridClusteringHierarchy::Options GridClusteringHierarchy::Options::FromConfig(OptionReader node) {
  Options options;
  options.cells = node.Get("cells", options.cells, "grid cells along the longest side on level 1",
                           Range::AtLeast(1));
  options.growth =
      node.Get("growth", options.growth, "cell size factor from level to level", Range::Above(1.0));
  options.min_vertices =
      node.Get("min_vertices", options.min_vertices,
               "stop once a level has at most this many vertices", Range::AtLeast(1));
  node.RejectUnknownKeys();
  return options;
}

MeshHierarchy GridClusteringHierarchy::Build(const Mesh& mesh, const Context& /*context*/) const {
  MeshHierarchy hierarchy;
  hierarchy.levels.push_back(HierarchyLevel{mesh, {}, {}});  // level 0 is the input
  const Eigen::RowVector3d low = mesh.vertices.colwise().minCoeff();
  double cell = BoundingBoxDiagonal(mesh) / options_.cells;
  while (hierarchy.levels.back().mesh.num_vertices() > options_.min_vertices) {
    HierarchyLevel& fine = hierarchy.levels.back();
    const Mesh& fine_mesh = fine.mesh;
    // Cluster: one coarse vertex per occupied cell, at the mean of its fine vertices.
    std::map<std::array<long, 3>, Index> cluster_of_cell;
    std::vector<Index> coarse_vertex(fine_mesh.num_vertices());
    std::vector<Eigen::RowVector3d> sum;
    std::vector<int> count;
    for (Index v = 0; v < fine_mesh.num_vertices(); ++v) {
      const Eigen::RowVector3d p = (fine_mesh.vertices.row(v) - low) / cell;
      const std::array<long, 3> key = {std::lround(std::floor(p.x())),
                                       std::lround(std::floor(p.y())),
                                       std::lround(std::floor(p.z()))};
      const auto [it, added] = cluster_of_cell.emplace(key, Index(sum.size()));
      if (added) {
        sum.push_back(Eigen::RowVector3d::Zero());
        count.push_back(0);
      }
      coarse_vertex[v] = it->second;
      sum[it->second] += fine_mesh.vertices.row(v);
      ++count[it->second];
    }
    if (sum.size() >= std::size_t(fine_mesh.num_vertices())) break;  // nothing merged: stop
    Mesh coarse;
    coarse.planar = fine_mesh.planar;
    coarse.vertices.resize(Index(sum.size()), 3);
    for (Index c = 0; c < Index(sum.size()); ++c) coarse.vertices.row(c) = sum[c] / count[c];
    // Elements keep their corners' clusters if those are distinct; duplicates are dropped.
    const int k = fine_mesh.simplex_size();
    std::set<std::vector<Index>> seen;
    std::vector<Index> kept;
    for (Index e = 0; e < fine_mesh.num_elements(); ++e) {
      std::vector<Index> corners(k);
      for (int a = 0; a < k; ++a) corners[a] = coarse_vertex[fine_mesh.elements(e, a)];
      std::vector<Index> sorted = corners;
      std::sort(sorted.begin(), sorted.end());
      if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) continue;
      if (seen.insert(sorted).second) kept.insert(kept.end(), corners.begin(), corners.end());
    }
    coarse.elements = Eigen::Map<const Elements>(kept.data(), Index(kept.size()) / k, k);
    fine.coarse_vertex = std::move(coarse_vertex);
    fine.in_cluster.assign(fine.coarse_vertex.size(), 1);  // every vertex is in its own cluster
    hierarchy.levels.push_back(HierarchyLevel{std::move(coarse), {}, {}});
    cell *= options_.growth;
  }
  return hierarchy;
}

}  // namespace harap
// [/guide:hierarchy-source]

using namespace harap;
using namespace harap::testing;

namespace {

// As hierarchies/builders/register_hierarchies.cpp's RegisterHierarchies.
void RegisterExampleHierarchy(Registry<Hierarchy>& registry) {
  // [guide:hierarchy-register]
  registry.Add<GridClusteringHierarchy>("vertex clustering on regular grids (the guide's example)");
  // [/guide:hierarchy-register]
}

Registries RegistriesWithExample() {
  Registries registries = MakeBuiltinRegistries();
  RegisterExampleHierarchy(registries.hierarchies);
  return registries;
}

}  // namespace

TEST_CASE("guide adding-a-hierarchy: the example meets the hierarchy contract", "[guides]") {
  const Registries registries = RegistriesWithExample();
  REQUIRE(registries.hierarchies.Contains("grid_clustering"));
  const Mesh mesh = Tube(24, 16);
  const MeshHierarchy hierarchy =
      registries.hierarchies.Create("grid_clustering", ConfigNode())->Build(mesh, Context());
  REQUIRE(hierarchy.num_levels() >= 3);
  CHECK(hierarchy.levels[0].mesh.vertices == mesh.vertices);
  CHECK(hierarchy.levels[0].mesh.elements == mesh.elements);
  for (int l = 0; l + 1 < hierarchy.num_levels(); ++l) {
    const HierarchyLevel& level = hierarchy.levels[l];
    const Index coarse_vertices = hierarchy.levels[l + 1].mesh.num_vertices();
    REQUIRE(Index(level.coarse_vertex.size()) == level.mesh.num_vertices());
    CHECK(coarse_vertices < level.mesh.num_vertices());
    for (Index c : level.coarse_vertex) CHECK((c >= 0 && c < coarse_vertices));
    ValidateMesh(hierarchy.levels[l + 1].mesh, "coarse level");
  }
  const ConfigNode bad = ConfigNode::Parse("[hierarchy]\ngrowth = 1\n", "t");
  CHECK_THROWS_WITH(registries.hierarchies.Create("grid_clustering", bad.Child("hierarchy")),
                    Catch::Contains("option 'hierarchy.growth' is 1, which is not > 1"));
}

TEST_CASE("guide adding-a-hierarchy: the hierarchical optimizer runs on the example", "[guides]") {
  const Registries registries = RegistriesWithExample();
  const BentTube tube(24, 16, 2.0, M_PI / 4, Eigen::Vector3d(0.0, 0.4, -0.2));
  std::map<int, std::vector<double>> energies;
  const OptimizeResult result =
      RunConfigured(registries, tube.problem,
                    "[optimizer]\ntype = \"hierarchical\"\ntargets_follow_rotations = "
                    "false\nmax_iterations = 300\n"
                    "[hierarchy]\ntype = \"grid_clustering\"\n",
                    &energies);
  CHECK(result.levels.size() >= 3);
  CHECK(MonotonePerLevel(energies));  // fixed coarse targets: plain local/global on each level
  CHECK(std::isfinite(result.energy));
  const Constraints& constraints = tube.problem.constraints;
  for (size_t k = 0; k < constraints.indices.size(); ++k) {
    CHECK(result.positions.row(constraints.indices[k]) == constraints.targets.row(k));
  }
}

TEST_CASE("guide adding-a-hierarchy: the guide quotes the example as it is", "[guides]") {
  const std::string doc = "docs/adding-a-hierarchy.md";
  const std::string example = "tests/guides/adding_a_hierarchy_test.cpp";
  for (const char* region : {"hierarchy-header", "hierarchy-source", "hierarchy-register"}) {
    DYNAMIC_SECTION(region) { CheckGuideQuotes(doc, example, region); }
  }
}
