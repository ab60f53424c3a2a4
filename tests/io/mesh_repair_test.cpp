// SPDX-License-Identifier: MIT
#include "io/mesh_repair.h"

#include <array>
#include <catch2/catch.hpp>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include "framework/error.h"
#include "io/mesh_io.h"
#include "tests/support/shared_data.h"
#include "tests/support/test_meshes.h"

namespace harap {
namespace {

using Catch::Matchers::Contains;

Mesh MakeMesh(const std::vector<std::array<double, 3>>& points,
              const std::vector<std::array<Index, 3>>& faces) {
  Mesh mesh;
  mesh.vertices.resize(static_cast<Index>(points.size()), 3);
  for (size_t v = 0; v < points.size(); ++v) {
    for (int d = 0; d < 3; ++d) mesh.vertices(static_cast<Index>(v), d) = points[v][d];
  }
  mesh.elements.resize(static_cast<Index>(faces.size()), 3);
  for (size_t f = 0; f < faces.size(); ++f) {
    for (int a = 0; a < 3; ++a) mesh.elements(static_cast<Index>(f), a) = faces[f][a];
  }
  return mesh;
}

// The message of the InputError `action` throws ("" and a failed check if it throws nothing).
template <class Action>
std::string InputErrorMessage(Action&& action) {
  try {
    action();
  } catch (const InputError& error) {
    return error.what();
  }
  FAIL_CHECK("no InputError thrown");
  return "";
}

// A closed tetrahedron surface, consistently oriented.
Mesh ClosedTetrahedron() {
  return MakeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
                  {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});
}

TEST_CASE("CheckMesh: a clean closed surface has no findings", "[mesh_checks]") {
  const MeshCheckReport report = CheckMesh(ClosedTetrahedron(), {0});
  for (const MeshFinding* finding : report.Findings()) {
    INFO(finding->name);
    CHECK(finding->count == 0);
    CHECK(finding->examples.empty());
  }
  REQUIRE(report.components.size() == 1);
  CHECK(report.components[0].elements == 4);
  CHECK(report.components[0].vertices == 4);
  CHECK(report.components[0].constrained_vertices == 1);
  CHECK(report.components_without_constraints == 0);
}

TEST_CASE("CheckMesh finds each defect and names the element", "[mesh_checks]") {
  SECTION("unreferenced and duplicate vertices") {
    Mesh mesh = MakeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {5, 5, 5}, {1, 0, 0}, {1, 1, 0}},
                         {{0, 1, 2}, {4, 5, 2}});
    const MeshCheckReport report = CheckMesh(mesh, {});
    CHECK(report.unreferenced_vertices.count == 1);
    CHECK(report.unreferenced_vertices.examples[0] == std::vector<Index>{3});
    CHECK(report.duplicate_vertices.count == 1);
    CHECK(report.duplicate_vertices.examples[0] == std::vector<Index>{4, 1});
    CHECK(report.boundary_edges.count == 6);  // the triangles share vertex 2, no edge
  }
  SECTION("an unreferenced vertex at a used position is not a duplicate") {
    Mesh mesh = MakeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 0, 0}}, {{0, 1, 2}});
    const MeshCheckReport report = CheckMesh(mesh, {});
    CHECK(report.unreferenced_vertices.count == 1);
    CHECK(report.duplicate_vertices.count == 0);
  }
  SECTION("zero-area and duplicated faces") {
    Mesh mesh = MakeMesh({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}},
                         {{0, 1, 3}, {0, 1, 2}, {3, 1, 0}, {1, 0, 3}});
    const MeshCheckReport report = CheckMesh(mesh, {});
    CHECK(report.degenerate_elements.name == "zero_area_faces");
    CHECK(report.degenerate_elements.count == 1);
    CHECK(report.degenerate_elements.examples[0] == std::vector<Index>{1});
    CHECK(report.duplicate_elements.count == 2);
    CHECK(report.duplicate_elements.examples[0] == std::vector<Index>{2, 0});
    CHECK(report.duplicate_elements.examples[1] == std::vector<Index>{3, 0});
    CHECK(report.non_manifold_edges.count == 3);  // 0-1 is in four faces, 0-3 and 1-3 in three
  }
  SECTION("a non-manifold edge: three faces on one edge") {
    Mesh mesh = MakeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}},
                         {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}});
    const MeshCheckReport report = CheckMesh(mesh, {});
    CHECK(report.non_manifold_edges.count == 1);
    CHECK(report.non_manifold_edges.examples[0] == std::vector<Index>{0, 1});
    CHECK(report.non_manifold_vertices.count == 0);
  }
  SECTION("a non-manifold vertex: two fans meet at one vertex (bow tie)") {
    Mesh mesh = MakeMesh({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}},
                         {{0, 1, 2}, {0, 3, 4}});
    const MeshCheckReport report = CheckMesh(mesh, {});
    CHECK(report.non_manifold_vertices.count == 1);
    CHECK(report.non_manifold_vertices.examples[0] == std::vector<Index>{0});
    CHECK(report.non_manifold_edges.count == 0);
    CHECK(report.components.size() == 1);  // connected through the shared vertex
  }
  SECTION("a closed fan around a vertex, listed in scrambled order, is one fan") {
    // An octahedron: every vertex has a closed fan of four triangles.
    Mesh mesh = MakeMesh(
        {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}},
        {{0, 2, 4}, {1, 3, 5}, {2, 1, 4}, {3, 0, 5}, {1, 2, 5}, {0, 3, 4}, {2, 0, 5}, {3, 1, 4}});
    const MeshCheckReport report = CheckMesh(mesh, {});
    CHECK(report.non_manifold_vertices.count == 0);
    CHECK(report.boundary_edges.count == 0);
    CHECK(report.non_manifold_edges.count == 0);
  }
  SECTION("a face that lists a vertex twice makes it non-manifold") {
    // Its second corner at vertex 1 shares no edge with anything: a fan of its own.
    Mesh mesh = MakeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}, {1, 1, 2}});
    const MeshCheckReport report = CheckMesh(mesh, {});
    CHECK(report.non_manifold_vertices.count == 1);
    CHECK(report.non_manifold_vertices.examples[0] == std::vector<Index>{1});
    CHECK(report.degenerate_elements.count == 1);
  }
  SECTION("inconsistent orientation across an edge") {
    Mesh mesh = ClosedTetrahedron();
    mesh.elements(3, 1) = 3;  // 1 2 3 flipped to 1 3 2
    mesh.elements(3, 2) = 2;
    const MeshCheckReport report = CheckMesh(mesh, {});
    CHECK(report.inconsistent_orientation.count == 3);  // all three edges of the flipped face
    CHECK(report.boundary_edges.count == 0);
  }
  SECTION("components and which have handles") {
    Mesh mesh = testing::Concatenate(testing::Grid(3, 3), ClosedTetrahedron());
    const Index tetrahedron_first_face = testing::Grid(3, 3).num_elements();
    const MeshCheckReport report = CheckMesh(mesh, {0, 1});
    REQUIRE(report.components.size() == 2);
    CHECK(report.components[0].elements == 8);  // largest first
    CHECK(report.components[0].constrained_vertices == 2);
    CHECK(report.components[1].first_element == tetrahedron_first_face);
    CHECK(report.components[1].constrained_vertices == 0);
    CHECK(report.components_without_constraints == 1);
  }
  SECTION("non-finite coordinates") {
    Mesh mesh = ClosedTetrahedron();
    mesh.vertices(2, 1) = std::numeric_limits<double>::quiet_NaN();
    const MeshCheckReport report = CheckMesh(mesh, {});
    CHECK(report.non_finite_vertices.count == 1);
    CHECK(report.non_finite_vertices.examples[0] == std::vector<Index>{2});
  }
}

TEST_CASE("CheckMesh on tetrahedra: sides, inverted, zero-volume and repeated elements",
          "[mesh_checks]") {
  Mesh mesh;
  mesh.vertices.resize(6, 3);
  mesh.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1, 2, 0, 0;
  mesh.elements.resize(4, 4);
  mesh.elements << 0, 1, 2, 3,  // positive volume
      1, 3, 2, 4,               // negative volume (the minority sign)
      0, 1, 5, 2,               // flat: all four in z = 0
      3, 2, 1, 0;               // the first one again (an even permutation: positive)
  const MeshCheckReport report = CheckMesh(mesh, {});
  CHECK(report.degenerate_elements.name == "zero_volume_tetrahedra");
  CHECK(report.degenerate_elements.examples == std::vector<std::vector<Index>>{{2}});
  CHECK(report.inconsistent_orientation.name == "inverted_tetrahedra");
  CHECK(report.inconsistent_orientation.examples == std::vector<std::vector<Index>>{{1}});
  CHECK(report.duplicate_elements.examples == std::vector<std::vector<Index>>{{3, 0}});
  // Faces 0-1-2 and 1-2-3 are each in three tetrahedra; six faces are in one.
  CHECK(report.non_manifold_edges.name == "non_manifold_faces");
  CHECK(report.non_manifold_edges.examples ==
        std::vector<std::vector<Index>>{{0, 1, 2}, {1, 2, 3}});
  CHECK(report.boundary_edges.count == 6);
  CHECK(report.components.size() == 1);
}

TEST_CASE("PreparedProblem: nothing to repair leaves the problem as it is", "[mesh_checks]") {
  const Mesh mesh = testing::Grid(4, 4);
  DeformationProblem problem;
  problem.mesh = &mesh;
  problem.constraints.indices = {0, 3};
  problem.constraints.targets = Positions::Zero(2, 3);
  const PreparedProblem prepared(problem, MeshRepairOptions{});
  CHECK_FALSE(prepared.changed());
  CHECK(prepared.problem().mesh == &mesh);
  CHECK(prepared.Summary().size() == 1);  // boundary edges only
  const Positions positions = Positions::Random(mesh.num_vertices(), 3);
  CHECK(prepared.ToInputVertices(positions) == positions);
}

TEST_CASE("PreparedProblem welds duplicates and maps results back to every input vertex",
          "[mesh_checks]") {
  std::vector<std::pair<Index, Index>> seam;
  const Mesh mesh = testing::SeamedGrid(5, seam);
  DeformationProblem problem;
  problem.mesh = &mesh;
  // Constrain the duplicate of the first seam vertex (and the original of the last one).
  problem.constraints.indices = {seam.front().first, seam.back().second};
  problem.constraints.targets = Positions::Ones(2, 3);
  problem.initial = mesh.vertices;

  const PreparedProblem as_is(problem, MeshRepairOptions{});
  CHECK_FALSE(as_is.changed());
  CHECK(as_is.checks().duplicate_vertices.count == static_cast<Index>(seam.size()));
  CHECK(as_is.checks().components.size() == 2);
  CHECK_THAT(as_is.checks().duplicate_vertices.action, Contains("mesh.weld_duplicates"));

  MeshRepairOptions weld;
  weld.weld_duplicates = true;
  const PreparedProblem welded(problem, weld);
  REQUIRE(welded.changed());
  const Mesh& solved = *welded.problem().mesh;
  CHECK(solved.num_vertices() == mesh.num_vertices() - static_cast<Index>(seam.size()));
  CHECK(solved.num_elements() == mesh.num_elements());
  CHECK(CheckMesh(solved, {}).components.size() == 1);
  CHECK(CheckMesh(solved, {}).duplicate_vertices.count == 0);
  // Both constraints survive, on the merged vertices.
  REQUIRE(welded.problem().constraints.indices.size() == 2);
  REQUIRE(welded.problem().initial);
  CHECK(welded.problem().initial->rows() == solved.num_vertices());
  // Results per solved vertex come back per input vertex; seam copies share their result.
  Positions result(solved.num_vertices(), 3);
  for (Index v = 0; v < solved.num_vertices(); ++v) result.row(v).setConstant(v);
  const Positions back = welded.ToInputVertices(result);
  REQUIRE(back.rows() == mesh.num_vertices());
  for (const auto& [copy, original] : seam) CHECK(back.row(copy) == back.row(original));
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    CHECK(solved.vertices.row(static_cast<Index>(back(v, 0))) == mesh.vertices.row(v));
  }
}

TEST_CASE("PreparedProblem rejects what it cannot solve, naming the vertices", "[mesh_checks]") {
  SECTION("non-finite coordinates") {
    Mesh mesh = ClosedTetrahedron();
    mesh.vertices(3, 2) = std::numeric_limits<double>::infinity();
    DeformationProblem problem;
    problem.mesh = &mesh;
    CHECK_THAT(InputErrorMessage([&] { PreparedProblem(problem, MeshRepairOptions{}); }),
               Contains("vertex 3 (0-based)") && Contains("inf"));
  }
  SECTION("welding two vertices the handles move apart") {
    std::vector<std::pair<Index, Index>> seam;
    const Mesh mesh = testing::SeamedGrid(5, seam);
    DeformationProblem problem;
    problem.mesh = &mesh;
    problem.constraints.indices = {seam[1].second, seam[1].first};
    problem.constraints.targets = Positions::Zero(2, 3);
    problem.constraints.targets(1, 2) = 1.0;
    MeshRepairOptions weld;
    weld.weld_duplicates = true;
    CHECK_THAT(InputErrorMessage([&] { PreparedProblem(problem, weld); }),
               Contains(fmt::format("vertices {} and {}", seam[1].second, seam[1].first)) &&
                   Contains("mesh.weld_duplicates = false"));
  }
}

TEST_CASE("PreparedProblem drops repeated faces and faces welding collapses", "[mesh_checks]") {
  // Two triangles plus a copy of the first, and a sliver whose two corners coincide.
  const Mesh mesh = MakeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}},
                             {{0, 1, 2}, {1, 3, 2}, {2, 1, 0}, {1, 4, 3}});
  DeformationProblem problem;
  problem.mesh = &mesh;
  {
    const PreparedProblem prepared(problem, MeshRepairOptions{});
    CHECK(prepared.problem().mesh->num_elements() == 3);  // the copy is gone
    CHECK(prepared.problem().mesh->num_vertices() == 5);
    CHECK(prepared.checks().degenerate_elements.count == 1);
  }
  SECTION("repeats that only welding makes are dropped too") {
    // Two copies of one triangle on unwelded seam vertices: different faces until welded.
    const Mesh seam =
        MakeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 0}, {1, 0, 0}}, {{0, 1, 2}, {3, 4, 2}});
    DeformationProblem seam_problem;
    seam_problem.mesh = &seam;
    MeshRepairOptions weld;
    weld.weld_duplicates = true;
    const PreparedProblem prepared(seam_problem, weld);
    CHECK(prepared.checks().duplicate_elements.count == 0);
    CHECK(prepared.problem().mesh->num_elements() == 1);
    CHECK(prepared.problem().mesh->num_vertices() == 3);
  }
  MeshRepairOptions options;
  options.weld_duplicates = true;
  options.drop_duplicate_elements = false;
  const PreparedProblem prepared(problem, options);
  CHECK(prepared.problem().mesh->num_elements() == 3);  // the sliver collapsed
  CHECK(prepared.problem().mesh->num_vertices() == 4);
  CHECK_THAT(prepared.checks().duplicate_vertices.action, Contains("collapsed"));
}

// Reads ../shared/meshes/MANIFEST.tsv: file -> column -> value.
std::map<std::string, std::map<std::string, std::string>> ReadManifest(
    const std::filesystem::path& file) {
  std::ifstream stream(file);
  std::string line;
  std::getline(stream, line);
  std::vector<std::string> header;
  std::istringstream names(line);
  for (std::string name; std::getline(names, name, '\t');) header.push_back(name);
  std::map<std::string, std::map<std::string, std::string>> rows;
  while (std::getline(stream, line)) {
    std::istringstream fields(line);
    std::map<std::string, std::string> row;
    size_t column = 0;
    for (std::string field; std::getline(fields, field, '\t') && column < header.size();) {
      row[header[column++]] = field;
    }
    rows[row["file"]] = row;
  }
  return rows;
}

TEST_CASE("CheckMesh agrees with the shared meshes' MANIFEST", "[mesh_checks][shared]") {
  HARAP_REQUIRE_SHARED(manifest_file, "meshes/MANIFEST.tsv");
  const auto manifest = ReadManifest(manifest_file);
  // The surface meshes below 150K faces (dragon, 871K faces, is in
  // experiments/scripts/run_shared_meshes.py).
  for (const char* name : {"teapot.ply.xz", "cow.ply.xz", "stanford-bunny.obj.xz",
                           "dragon-res2.obj.xz", "cylinder.ply.xz", "spot.ply.xz"}) {
    DYNAMIC_SECTION(name) {
      const auto& row = manifest.at(name);
      const Mesh mesh = ReadMesh(manifest_file.parent_path() / name);
      const MeshCheckReport report = CheckMesh(mesh, {});
      auto expected = [&](const char* column) { return std::stoi(row.at(column)); };
      CHECK(report.components.size() == static_cast<size_t>(expected("connected_components")));
      CHECK(report.unreferenced_vertices.count == expected("unreferenced_vertices"));
      CHECK(report.duplicate_vertices.count == expected("duplicate_vertices"));
      CHECK(report.duplicate_elements.count == expected("duplicate_faces"));
      CHECK(report.degenerate_elements.count == expected("zero_area_faces"));
      CHECK(report.boundary_edges.count == expected("boundary_edges"));
      CHECK(report.non_manifold_edges.count == expected("nonmanifold_edges"));
      CHECK(report.non_manifold_vertices.count == expected("nonmanifold_vertices"));
      CHECK((report.inconsistent_orientation.count == 0) ==
            (row.at("consistently_oriented") == "yes"));
    }
  }
}

}  // namespace
}  // namespace harap
