// SPDX-License-Identifier: MIT
// Scenarios generated from a mesh alone (scenario_generator.h): parseable, both handles
// non-empty, disjoint and on the largest component, the same for a rotated copy of the mesh,
// and clear errors for meshes that cannot hold two handles.
#include "io/scenario_generator.h"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <catch2/catch.hpp>
#include <cmath>
#include <set>

#include "framework/error.h"
#include "io/mesh_writers.h"
#include "io/scenario.h"
#include "tests/support/temp_folder.h"
#include "tests/support/test_meshes.h"

using namespace harap;
using Catch::Matchers::Contains;

namespace {

// A tube of length 3 along z: its longest principal axis is z.
Mesh LongTube() {
  Mesh mesh = testing::Tube(31, 12);
  mesh.vertices.col(2) *= 3.0;
  return mesh;
}

Scenario Parse(const std::string& text, const Mesh& mesh, const testing::TempFolder& folder) {
  WriteMesh(folder.dir / "mesh.ply", mesh.vertices, mesh.elements);
  return ParseScenario(text, "generated.toml", folder.dir);
}

}  // namespace

TEST_CASE("scenario generator: every kind gives two disjoint non-empty handles at the ends",
          "[io][scenario_generator]") {
  testing::TempFolder folder("scenario-generator-kinds");
  const Mesh mesh = LongTube();
  for (const std::string& kind : ScenarioKindNames()) {
    CAPTURE(kind);
    ScenarioGeneratorOptions options;
    options.kind = ParseScenarioKind(kind);
    const std::string text = GenerateScenarioToml(mesh, "mesh.ply", options, "tube");
    CHECK(text == GenerateScenarioToml(mesh, "mesh.ply", options, "tube"));  // deterministic
    const Scenario scenario = Parse(text, mesh, folder);
    REQUIRE(scenario.handles.size() == 2);
    const ScenarioHandle& held = scenario.handles[0];
    const ScenarioHandle& moved = scenario.handles[1];
    CHECK(held.name == "held");
    CHECK(moved.name == kind);
    // 5% of 372 vertices each, rounded up.
    CHECK(held.vertices.size() == 19);
    CHECK(moved.vertices.size() == 19);
    // The held handle is at one end (z near 0), the moved one at the other (z near 3).
    for (const Index v : held.vertices) CHECK(mesh.vertices(v, 2) < 0.5);
    for (const Index v : moved.vertices) CHECK(mesh.vertices(v, 2) > 2.5);
    // Held vertices stay; the moved ones move.
    for (size_t i = 0; i < held.vertices.size(); ++i) {
      CHECK((held.targets.row(i) - mesh.vertices.row(held.vertices[i])).norm() == 0.0);
    }
    CHECK((moved.targets - mesh.vertices(moved.vertices, Eigen::all)).norm() > 0.1);
  }
  CHECK_THROWS_WITH(ParseScenarioKind("squash"), Contains("bend, twist, lift, stretch"));
}

TEST_CASE("scenario generator: a rotated and shifted copy of a mesh gets the same handles",
          "[io][scenario_generator]") {
  testing::TempFolder folder("scenario-generator-rotated");
  // Jittered, so that the extreme vertices and the nearest ones are unique (a regular tube's end
  // ring is a tie that rounding would break differently in the two copies).
  const Mesh mesh = testing::Jittered(LongTube(), 31, 0.2, 7);
  Mesh turned = mesh;
  const Eigen::Matrix3d rotation =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1.0, 2.0, 0.5).normalized()).toRotationMatrix();
  turned.vertices =
      (mesh.vertices * rotation.transpose()).rowwise() + Eigen::RowVector3d(5.0, -2.0, 1.0);
  ScenarioGeneratorOptions options;
  options.kind = ScenarioKind::kTwist;
  const Scenario a = Parse(GenerateScenarioToml(mesh, "mesh.ply", options, "a"), mesh, folder);
  const Scenario b = Parse(GenerateScenarioToml(turned, "mesh.ply", options, "b"), turned, folder);
  // The held and moved ends may swap with the axis sign; the two patches are the same.
  const std::set<std::vector<Index>> patches_a = {a.handles[0].vertices, a.handles[1].vertices};
  const std::set<std::vector<Index>> patches_b = {b.handles[0].vertices, b.handles[1].vertices};
  CHECK(patches_a == patches_b);
}

TEST_CASE("scenario generator: handles lie on the largest component", "[io][scenario_generator]") {
  testing::TempFolder folder("scenario-generator-components");
  // A long tube and, far out along its axis, a small grid: a slab or an axis extreme of the
  // whole mesh would land on the grid.
  const Mesh tube = LongTube();
  Mesh grid = testing::Grid(4, 4);
  Mesh mesh;
  mesh.vertices.resize(tube.num_vertices() + grid.num_vertices(), 3);
  mesh.vertices << tube.vertices, (grid.vertices.rowwise() + Eigen::RowVector3d(0.0, 0.0, 10.0));
  mesh.elements.resize(tube.num_elements() + grid.num_elements(), 3);
  mesh.elements << tube.elements, (grid.elements.array() + tube.num_vertices()).matrix();
  const Scenario scenario =
      Parse(GenerateScenarioToml(mesh, "mesh.ply", {}, "two pieces"), mesh, folder);
  for (const ScenarioHandle& handle : scenario.handles) {
    for (const Index v : handle.vertices) CHECK(v < tube.num_vertices());
  }
}

TEST_CASE("scenario generator: meshes that cannot hold two handles are errors naming them",
          "[io][scenario_generator]") {
  Mesh triangle;
  triangle.vertices.resize(3, 3);
  triangle.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  triangle.elements.resize(1, 3);
  triangle.elements << 0, 1, 2;
  CHECK_THROWS_AS(GenerateScenarioToml(triangle, "t.ply", {}, "t.ply"), InputError);
  CHECK_THROWS_WITH(GenerateScenarioToml(triangle, "t.ply", {}, "t.ply"),
                    Contains("t.ply: cannot place handles") && Contains("3 vertices"));
  testing::TempFolder folder("scenario-generator-files");
  CHECK_THROWS_WITH(GenerateScenarioForFile(folder.dir / "none.obj", "none.obj", {}),
                    Contains("none.obj"));
}

TEST_CASE("scenario generator: with refine the handles are chosen on the refined mesh",
          "[io][scenario_generator]") {
  testing::TempFolder folder("scenario-generator-refine");
  const Mesh mesh = LongTube();
  WriteMesh(folder.dir / "tube.ply", mesh.vertices, mesh.elements);
  ScenarioGeneratorOptions options;
  options.kind = ScenarioKind::kLift;
  options.refine = 1;
  const std::string text = GenerateScenarioForFile(folder.dir / "tube.ply", "tube.ply", options);
  CHECK_THAT(text, Contains("refine = 1"));
  const Scenario scenario = ParseScenario(text, "refined.toml", folder.dir);
  CHECK(scenario.mesh.num_vertices() > 3 * mesh.num_vertices());
  const size_t expected = static_cast<size_t>(std::ceil(0.05 * scenario.mesh.num_vertices()));
  CHECK(scenario.handles[0].vertices.size() == expected);
}
