// SPDX-License-Identifier: MIT
#include "io/scenario.h"

#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>

#include "framework/error.h"
#include "io/builtin_meshes.h"
#include "io/mesh_io.h"
#include "io/mesh_writers.h"
#include "tests/io/io_test_util.h"
#include "tests/support/shared_data.h"

namespace harap {
namespace {

using Catch::Matchers::Contains;
using testing::ScratchDir;

// A small closed cylinder: z in [0, 4], diameter 1.
const std::string kMesh = "mesh = { builtin = \"cylinder\", vertices = 500 }\n";

Scenario Parse(const std::string& text, const std::filesystem::path& base = ".") {
  return ParseScenario(text, "errors.toml", base);
}

template <class ErrorType>
void ExpectError(const std::string& text, const std::vector<std::string>& phrases,
                 const std::filesystem::path& base = ".") {
  INFO("scenario:\n" << text);
  try {
    Parse(text, base);
    FAIL("no exception");
  } catch (const ErrorType& error) {
    const std::string message = error.what();
    INFO("message: " << message);
    CHECK_THAT(message, Contains("errors.toml"));
    for (const std::string& phrase : phrases) CHECK_THAT(message, Contains(phrase));
  }
}

// Rotation by `degrees` about unit `axis` (Rodrigues), independent of Eigen::AngleAxis.
Eigen::Matrix3d Rodrigues(Eigen::Vector3d axis, double degrees) {
  axis.normalize();
  const double angle = degrees * M_PI / 180.0;
  Eigen::Matrix3d k;
  k << 0, -axis.z(), axis.y(), axis.z(), 0, -axis.x(), -axis.y(), axis.x(), 0;
  return Eigen::Matrix3d::Identity() + std::sin(angle) * k + (1.0 - std::cos(angle)) * k * k;
}

// -----------------------------------------------------------------------------------------------
// Errors: each names the file (with line:column), the handle and the problem.

TEST_CASE("scenario errors: unknown keys at every level", "[io][scenario]") {
  ExpectError<ConfigError>(kMesh + "refinee = 1\n",
                           {"errors.toml:2:1", "unknown key 'refinee'", "the top level"});
  ExpectError<ConfigError>(
      kMesh +
          "[[handle]]\nname = \"top\"\nselect.slab = { axis = \"z\", from = 0.9, to = 1.0 }\n"
          "rotat = { axis = [1, 0, 0], degrees = 10 }\n",
      {"errors.toml:5:1", "handle 'top'", "unknown key 'rotat'", "rotate"});
  ExpectError<ConfigError>(
      kMesh + "[[handle]]\nname = \"top\"\nselect.slabs = { axis = \"z\", from = 0.9, to = 1 }\n",
      {"handle 'top'", "unknown key 'slabs'", "slab, ball, indices, index_file"});
  ExpectError<ConfigError>(
      kMesh +
          "[[handle]]\nname = \"top\"\nselect.slab = { axis = \"z\", from = 0.9, to = 1.0 }\n"
          "rotate = { axis = [1, 0, 0], angle = 10 }\n",
      {"handle 'top'", "unknown key 'angle'", "degrees"});
  ExpectError<ConfigError>(
      kMesh + "[[handle]]\nselect.slab = { axis = \"z\", from = 0.9, upto = 1.0 }\n",
      {"handle 1", "unknown key 'upto'"});
  ExpectError<ConfigError>("mesh = { builtin = \"cylinder\", vertexes = 500 }\n",
                           {"errors.toml:1", "unknown option 'mesh.vertexes'"});
  ExpectError<ConfigError>("mesh = { builtin = \"donut\" }\n",
                           {"donut", "cylinder, plane, disk, rectangle"});
}

TEST_CASE("scenario errors: selections", "[io][scenario]") {
  ExpectError<ConfigError>(
      kMesh + "[[handle]]\nname = \"air\"\nselect.slab = { axis = \"z\", from = 2.0, to = 3.0 }\n",
      {"errors.toml:4", "handle 'air'", "matches no vertex", "slab z in [2, 3]"});
  ExpectError<ConfigError>(
      kMesh + "[[handle]]\nname = \"far\"\nselect.ball = { center = [5, 5, 5], radius = 0.1 }\n",
      {"handle 'far'", "matches no vertex"});
  ExpectError<ConfigError>(kMesh + "[[handle]]\nname = \"ids\"\nselect.indices = [0, 99999]\n",
                           {"errors.toml:4", "handle 'ids'", "index 99999 out of range"});
  ExpectError<ConfigError>(kMesh + "[[handle]]\nname = \"ids\"\nselect.indices = [-1]\n",
                           {"handle 'ids'", "index -1 out of range"});
  ExpectError<ConfigError>(kMesh + "[[handle]]\nname = \"none\"\nselect.indices = []\n",
                           {"handle 'none'", "matches no vertex"});
  ExpectError<ConfigError>(
      kMesh +
          "[[handle]]\nname = \"both\"\nselect.slab = { axis = \"z\", from = 0, to = 1 }\n"
          "select.ball = { center = [0.5, 0.5, 0.5], radius = 0.1 }\n",
      {"handle 'both'", "2 selections (slab, ball)", "exactly one"});
  ExpectError<ConfigError>(kMesh + "[[handle]]\nname = \"nothing\"\ntranslate = [0, 0, 1]\n",
                           {"handle 'nothing'", "no selection"});
  ExpectError<ConfigError>(
      kMesh + "[[handle]]\nname = \"w\"\nselect.slab = { axis = \"w\", from = 0, to = 1 }\n",
      {"handle 'w'", "\"x\", \"y\" or \"z\""});
  ExpectError<ConfigError>(
      kMesh + "[[handle]]\nname = \"rev\"\nselect.slab = { axis = \"z\", from = 0.5, to = 0.1 }\n",
      {"handle 'rev'", "from = 0.5 > to = 0.1"});
}

TEST_CASE("scenario errors: motion and numbers", "[io][scenario]") {
  const std::string select =
      kMesh + "[[handle]]\nname = \"top\"\nselect.slab = { axis = \"z\", from = 0.9, to = 1 }\n";
  ExpectError<ConfigError>(select + "rotate = { axis = [0, 0, 0], degrees = 90 }\n",
                           {"errors.toml:5", "handle 'top'", "rotation axis is zero"});
  ExpectError<ConfigError>(select + "rotate = { axis = [0, 0, 1], degrees = nan }\n",
                           {"handle 'top'", "non-finite number"});
  ExpectError<ConfigError>(select + "translate = [0.0, inf, 0.0]\n",
                           {"errors.toml:5", "handle 'top'", "translate", "non-finite number"});
  ExpectError<ConfigError>(
      kMesh + "[[handle]]\nname = \"b\"\nselect.ball = { center = [0.5, 0.5, -inf], radius = 1 }\n",
      {"handle 'b'", "non-finite number"});
  ExpectError<ConfigError>(select + "translate = [0.0, 1.0]\n",
                           {"handle 'top'", "array of three numbers"});
  ExpectError<ConfigError>(select + "rotate = { axis = [0, 0, 1] }\n",
                           {"handle 'top'", "needs 'degrees'"});
  ExpectError<ConfigError>(select + "target = \"initial\"\n",
                           {"handle 'top'", "needs a top-level initial"});
  ExpectError<ConfigError>(select + "target = \"rest\"\n", {"handle 'top'", "\"initial\""});
  ExpectError<ConfigError>(kMesh + "refine = -1\n", {"errors.toml:2", "'refine'"});
  ExpectError<ConfigError>(kMesh + "refine = 1.5\n", {"'refine'"});
}

TEST_CASE("scenario errors: mesh, files and syntax", "[io][scenario]") {
  ScratchDir dir;
  ExpectError<ConfigError>("[[handle]]\nselect.indices = [0]\n", {"no 'mesh'"});
  ExpectError<InputError>("mesh = \"missing.obj\"\n",
                          {"errors.toml:1:8", "missing.obj", "not found"}, dir.path());
  ExpectError<InputError>("mesh = \"bunny.mesh.xz\"\n", {"bunny.mesh.xz", "not found"}, dir.path());
  dir.Write("rabbit.node", "1 3 0 0\n0 0 0 0\n");
  ExpectError<InputError>("mesh = \"rabbit.node\"\n", {"errors.toml:1", "rabbit.ele", "is missing"},
                          dir.path());
  dir.Write("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n");
  ExpectError<InputError>("mesh = \"bad.obj\"\n", {"errors.toml:1", "bad.obj", "out of range"},
                          dir.path());
  ExpectError<ConfigError>("mesh = 3\n", {"'mesh' must be"});
  ExpectError<ConfigError>(kMesh + "[[handle]\n", {"errors.toml:2", "TOML syntax error"});

  // Index files: missing, malformed, out of range.
  const std::string handle = "[[handle]]\nname = \"file\"\nselect.index_file = ";
  ExpectError<InputError>(kMesh + handle + "\"none.txt\"\n",
                          {"errors.toml:4", "handle 'file'", "none.txt", "not found"}, dir.path());
  dir.Write("bad.txt", "0 1\n2 x\n");
  ExpectError<InputError>(kMesh + handle + "\"bad.txt\"\n",
                          {"handle 'file'", "bad.txt", "line 2", "'x' is not a vertex index"},
                          dir.path());
  dir.Write("big.txt", "0 1\n\n 2 123456\n");
  ExpectError<InputError>(kMesh + handle + "\"big.txt\"\n",
                          {"handle 'file'", "big.txt", "line 3", "index 123456 out of range"},
                          dir.path());
  // Initial configuration with the wrong vertex count.
  Positions three(3, 3);
  three << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  Elements one(1, 3);
  one << 0, 1, 2;
  WritePly(dir.path() / "small.ply", three, one);
  ExpectError<InputError>(kMesh + "initial = \"small.ply\"\n",
                          {"errors.toml:2", "small.ply", "has 3 vertices"}, dir.path());
}

// -----------------------------------------------------------------------------------------------
// Semantics.

TEST_CASE("scenario motion: rotate about the centroid or a centre, then translate by t*D",
          "[io][scenario]") {
  const std::string text = kMesh +
                           "[[handle]]\nname = \"bottom\"\n"
                           "select.slab = { axis = \"z\", from = 0.0, to = 0.1 }\n"
                           "[[handle]]\nname = \"top\"\n"
                           "select.slab = { axis = \"z\", from = 0.8, to = 1.0 }\n"
                           "rotate = { axis = [1.0, 1.0, 0.0], degrees = 30.0 }\n"
                           "translate = [0.1, -0.2, 0.3]\n"
                           "[[handle]]\n"
                           "select.ball = { center = [0.5, 0.5, 0.5], radius = 0.15 }\n"
                           "rotate = { axis = [0, 0, 2], degrees = -90, center = [0, 0, 0.5] }\n";
  const Scenario scenario = Parse(text);
  const Mesh& mesh = scenario.mesh;
  REQUIRE(scenario.handles.size() == 3);
  CHECK(scenario.handles[0].name == "bottom");
  CHECK(scenario.handles[2].name == "handle 3");
  CHECK(scenario.file.empty());
  CHECK_THAT(scenario.mesh_source, Contains("cylinder"));

  const Eigen::Vector3d lo = mesh.vertices.colwise().minCoeff().transpose();
  const Eigen::Vector3d hi = mesh.vertices.colwise().maxCoeff().transpose();
  const double diagonal = (hi - lo).norm();
  CHECK(diagonal == Approx(std::sqrt(1.0 + 1.0 + 16.0)).epsilon(1e-3));

  // Fixed handle: exactly the rest positions of the vertices with z <= 0.1 * 4.
  const ScenarioHandle& bottom = scenario.handles[0];
  Index expected_bottom = 0;
  for (Index v = 0; v < mesh.num_vertices(); ++v) expected_bottom += mesh.vertices(v, 2) <= 0.4;
  CHECK(static_cast<Index>(bottom.vertices.size()) == expected_bottom);
  CHECK(std::is_sorted(bottom.vertices.begin(), bottom.vertices.end()));
  for (size_t i = 0; i < bottom.vertices.size(); ++i) {
    REQUIRE(bottom.targets.row(static_cast<Index>(i)) == mesh.vertices.row(bottom.vertices[i]));
  }

  // Rotated about the centroid of its vertices, then moved by t * D.
  const ScenarioHandle& top = scenario.handles[1];
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const Index v : top.vertices) centroid += mesh.vertices.row(v).transpose();
  centroid /= static_cast<double>(top.vertices.size());
  const Eigen::Matrix3d r = Rodrigues(Eigen::Vector3d(1, 1, 0), 30.0);
  const Eigen::Vector3d shift = Eigen::Vector3d(0.1, -0.2, 0.3) * diagonal;
  for (size_t i = 0; i < top.vertices.size(); ++i) {
    const Eigen::Vector3d p = mesh.vertices.row(top.vertices[i]).transpose();
    const Eigen::Vector3d expected = centroid + r * (p - centroid) + shift;
    REQUIRE((top.targets.row(static_cast<Index>(i)).transpose() - expected).norm() < 1e-12);
    REQUIRE(p.z() >= lo.z() + 0.8 * (hi.z() - lo.z()));
  }
  // Rigid: distances between handle vertices are kept.
  const Eigen::Vector3d d0 =
      mesh.vertices.row(top.vertices.front()) - mesh.vertices.row(top.vertices.back());
  const Eigen::Vector3d d1 = top.targets.row(0) - top.targets.row(top.targets.rows() - 1);
  CHECK(d1.norm() == Approx(d0.norm()));

  // Explicit centre in box fractions: (lo.x, lo.y, mid z); -90 degrees about +z maps
  // (x, y) - c to (y, -x).
  const ScenarioHandle& ball = scenario.handles[2];
  REQUIRE(!ball.vertices.empty());
  const Eigen::Vector3d center(lo.x(), lo.y(), lo.z() + 0.5 * (hi.z() - lo.z()));
  for (size_t i = 0; i < ball.vertices.size(); ++i) {
    const Eigen::Vector3d p = mesh.vertices.row(ball.vertices[i]).transpose();
    const Eigen::Vector3d q = p - center;
    const Eigen::Vector3d expected = center + Eigen::Vector3d(q.y(), -q.x(), q.z());
    REQUIRE((ball.targets.row(static_cast<Index>(i)).transpose() - expected).norm() < 1e-12);
    REQUIRE((p - (lo + hi) / 2).norm() <= 0.15 * diagonal);
  }
}

TEST_CASE("scenario: merged constraints, first handle wins", "[io][scenario]") {
  const Scenario scenario = Parse(kMesh +
                                  "[[handle]]\nselect.slab = { axis = \"z\", from = 0, to = 0.6 }\n"
                                  "[[handle]]\nselect.slab = { axis = \"z\", from = 0.4, to = 1 }\n"
                                  "translate = [1, 0, 0]\n"
                                  "[[handle]]\nselect.indices = [3, 2, 3]\n"
                                  "translate = [0, 9, 0]\n");
  const Mesh& mesh = scenario.mesh;
  REQUIRE(scenario.handles[2].vertices == std::vector<Index>{2, 3});
  const Constraints constraints = scenario.MergedConstraints();
  // The two slabs cover everything; their overlap and vertices 2, 3 stay with earlier handles.
  REQUIRE(static_cast<Index>(constraints.indices.size()) == mesh.num_vertices());
  REQUIRE(std::is_sorted(constraints.indices.begin(), constraints.indices.end()));
  const double height = 4.0;
  for (size_t k = 0; k < constraints.indices.size(); ++k) {
    const Index v = constraints.indices[k];
    const Eigen::RowVector3d rest = mesh.vertices.row(v);
    const Eigen::RowVector3d target = constraints.targets.row(static_cast<Index>(k));
    if (rest.z() <= 0.6 * height) {
      REQUIRE(target == rest);
    } else {
      REQUIRE(target.x() > rest.x());
      REQUIRE(target.y() == rest.y());
    }
  }
}

TEST_CASE("scenario: box of referenced vertices, index files, initial, relative paths",
          "[io][scenario]") {
  ScratchDir dir;
  // A unit square in the plane z = 0 plus a stray vertex far away (unreferenced).
  dir.Write("meshes/square.obj",
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 100 100 100\nf 1 2 3\nf 1 3 4\n");
  dir.Write("handles.txt", "0\n 1 1\n");
  Positions initial(5, 3);
  initial << 0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1, 7, 7, 7;
  Elements faces(2, 3);
  faces << 0, 1, 2, 0, 2, 3;
  WritePly(dir.path() / "initial.ply", initial, faces);
  const auto scenario_file = dir.Write("scene.toml",
                                       "mesh = \"meshes/square.obj\"\ninitial = \"initial.ply\"\n"
                                       "[[handle]]\nname = \"right\"\n"
                                       "select.slab = { axis = \"x\", from = 0.9, to = 1.0 }\n"
                                       "translate = [0.0, 0.0, 1.0]\n"
                                       "[[handle]]\nname = \"file\"\n"
                                       "select.index_file = \"handles.txt\"\n"
                                       "target = \"initial\"\n"
                                       "[[handle]]\nname = \"flat\"\n"
                                       "select.slab = { axis = \"z\", from = 0.0, to = 0.0 }\n");
  const Scenario scenario = LoadScenario(scenario_file);
  CHECK(scenario.file == scenario_file);
  CHECK_THAT(scenario.mesh_source, Contains("square.obj"));
  REQUIRE(scenario.mesh.num_vertices() == 5);
  REQUIRE(scenario.initial.has_value());
  CHECK(*scenario.initial == initial);
  // Box [0,1]^2 x {0} from the referenced vertices: x >= 0.9 picks vertices 1 and 2, not the
  // stray vertex 4; the box diagonal is sqrt(2).
  const ScenarioHandle& right = scenario.handles[0];
  REQUIRE(right.vertices == std::vector<Index>{1, 2});
  CHECK(right.targets(0, 2) == Approx(std::sqrt(2.0)));
  const ScenarioHandle& file = scenario.handles[1];
  REQUIRE(file.vertices == std::vector<Index>{0, 1});
  CHECK(file.targets.row(0) == initial.row(0));
  CHECK(file.targets.row(1) == initial.row(1));
  // A flat axis gives every vertex the fraction 0.
  CHECK(scenario.handles[2].vertices == std::vector<Index>{0, 1, 2, 3});
  CHECK_THROWS_WITH(LoadScenario(dir.path() / "absent.toml"), Contains("absent.toml"));
}

TEST_CASE("scenario: refine subdivides before selecting", "[io][scenario]") {
  const Scenario coarse = Parse(kMesh);
  const Scenario fine = Parse(kMesh + "refine = 1\n[[handle]]\nselect.indices = [0]\n");
  const auto counts = testing::CountEdges(coarse.mesh);
  CHECK(fine.mesh.num_vertices() ==
        coarse.mesh.num_vertices() + static_cast<Index>(counts.undirected.size()));
}

// -----------------------------------------------------------------------------------------------
// Tetrahedral meshes, tetrahedralized surfaces, planar meshes.

TEST_CASE("scenario: TetGen files, a .node start configuration, target = initial",
          "[io][scenario][tet]") {
  ScratchDir dir;
  // Two tetrahedra, 1-based, the second written with negative orientation.
  dir.Write("tets/bar_rest.node", "5 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 1 1\n");
  dir.Write("tets/bar_rest.ele", "2 4 0\n1 1 2 3 4\n2 2 3 5 4\n");
  // The start configuration: only a .node file, shifted by (0, 0, 2).
  dir.Write("tets/bar_init.node", "5 3 0 0\n1 0 0 2\n2 1 0 2\n3 0 1 2\n4 0 0 3\n5 1 1 3\n");
  dir.Write("tets/handles.txt", "0 1\n\t4\n");
  const std::string text =
      "mesh = \"tets/bar_rest.node\"\ninitial = \"tets/bar_init.node\"\n"
      "[[handle]]\nselect.index_file = \"tets/handles.txt\"\ntarget = \"initial\"\n";
  const Scenario scenario = Parse(text, dir.path());
  CHECK(scenario.mesh.kind() == ElementKind::kTetrahedron);
  CHECK(scenario.mesh.num_elements() == 2);
  CHECK(!scenario.mesh.planar);
  REQUIRE(scenario.notes.size() == 1);
  CHECK_THAT(scenario.notes[0], Contains("bar_rest.ele") && Contains("reoriented"));
  REQUIRE(scenario.initial);
  CHECK(scenario.initial->row(4) == Eigen::RowVector3d(1, 1, 3));
  REQUIRE(scenario.handles.size() == 1);
  CHECK(scenario.handles[0].vertices == std::vector<Index>{0, 1, 4});
  CHECK(scenario.handles[0].targets.row(2) == Eigen::RowVector3d(1, 1, 3));
  // refine is Loop subdivision of triangles; planar needs triangles.
  ExpectError<ConfigError>("refine = 1\n" + text, {"errors.toml:1", "refine", "tetrahedra"},
                           dir.path());
  ExpectError<ConfigError>("planar = true\n" + text,
                           {"errors.toml:1", "planar = true", "tetrahedra"}, dir.path());
  // A start configuration of the wrong size; a broken .node file names its line.
  dir.Write("tets/short.node", "2 3\n0 0 0 0\n1 1 0 0\n");
  ExpectError<InputError>("mesh = \"tets/bar_rest.node\"\ninitial = \"tets/short.node\"\n",
                          {"errors.toml:2", "short.node", "has 2 vertices"}, dir.path());
  dir.Write("tets/broken.node", "2 3\n0 0 0 0\n1 1 zero 0\n");
  ExpectError<InputError>("mesh = \"tets/bar_rest.node\"\ninitial = \"tets/broken.node\"\n",
                          {"errors.toml:2", "initial", "broken.node", "line 3", "'zero'"},
                          dir.path());
}

TEST_CASE("scenario: tetrahedralize a built-in surface or a surface file",
          "[io][scenario][tetrahedralize]") {
  ScratchDir dir;
  const Mesh surface =
      MakeBuiltinMesh(ConfigNode::Parse("builtin = \"cylinder\"\nvertices = 300", "test"));
  const Scenario scenario = Parse(
      "mesh = { tetrahedralize = { builtin = \"cylinder\", vertices = 300 }, max_volume = 0.01 }\n"
      "[[handle]]\nname = \"bottom\"\nselect.indices = [0, 1, 2]\n"
      "[[handle]]\nname = \"top\"\nselect.slab = { axis = \"z\", from = 0.95, to = 1.0 }\n"
      "translate = [0.1, 0, 0]\n");
  const Mesh& mesh = scenario.mesh;
  CHECK(mesh.kind() == ElementKind::kTetrahedron);
  REQUIRE(mesh.num_vertices() > surface.num_vertices());
  CHECK(mesh.vertices.topRows(surface.num_vertices()) == surface.vertices);
  CHECK_THAT(scenario.mesh_source,
             Contains("tetrahedralized builtin") && Contains("max_volume=0.01"));
  REQUIRE(scenario.notes.size() == 1);
  CHECK_THAT(scenario.notes[0], Contains("surface vertices") && Contains("tetrahedra"));
  // Handle indices refer to the surface's vertices, unchanged.
  CHECK(scenario.handles[0].targets == surface.vertices.topRows(3));
  CHECK(!scenario.handles[1].vertices.empty());

  // A surface file, refined before it is filled.
  dir.Write("cube.obj",
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
            "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\n"
            "f 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n");
  const Scenario cube =
      Parse("mesh = { tetrahedralize = \"cube.obj\", max_radius_edge_ratio = 0 }\nrefine = 1\n",
            dir.path());
  CHECK(cube.mesh.kind() == ElementKind::kTetrahedron);
  CHECK(cube.mesh.num_vertices() == 8 + 18);  // refined surface: 8 + 18 edge midpoints
  CHECK_THAT(cube.mesh_source, Contains("cube.obj refined 1x"));

  // Errors: keys, values, broken surfaces.
  ExpectError<ConfigError>("mesh = { tetrahedralize = \"cube.obj\", max_volumes = 1 }\n",
                           {"errors.toml:1", "max_volumes", "max_volume"}, dir.path());
  ExpectError<ConfigError>("mesh = { tetrahedralize = \"cube.obj\", max_volume = 2 }\n",
                           {"errors.toml:1", "max_volume must be in [0, 1)"}, dir.path());
  ExpectError<ConfigError>("mesh = { tetrahedralize = 3 }\n",
                           {"errors.toml:1", "mesh.tetrahedralize must be"});
  ExpectError<ConfigError>("mesh = { tetrahedralize = { builtin = \"cylinder\", vertexes = 9 } }\n",
                           {"errors.toml:1", "vertexes"});
  ExpectError<InputError>("mesh = { tetrahedralize = \"none.obj\" }\n",
                          {"errors.toml:1", "none.obj", "not found"}, dir.path());
  ExpectError<InputError>(
      "mesh = { tetrahedralize = { builtin = \"cylinder\", vertices = 100, caps = false } }\n",
      {"errors.toml:1", "tetrahedralize builtin", "not closed"});
  dir.Write("t.node", "4 3\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n");
  dir.Write("t.ele", "1 4\n0 0 1 2 3\n");
  ExpectError<InputError>("mesh = { tetrahedralize = \"t.node\" }\n",
                          {"errors.toml:1", "t.node", "has tetrahedra already"}, dir.path());
}

TEST_CASE("scenario: planar meshes, automatic and explicit", "[io][scenario][planar]") {
  ScratchDir dir;
  const std::string rectangle = "mesh = { builtin = \"rectangle\", vertices = 200 }\n";
  const std::string left =
      "[[handle]]\nname = \"left\"\n"
      "select.slab = { axis = \"x\", from = 0.0, to = 0.05 }\n";
  const std::string right =
      "[[handle]]\nname = \"right\"\n"
      "select.slab = { axis = \"x\", from = 0.95, to = 1.0 }\n";
  // In-plane motion of a flat mesh: planar.
  const Scenario in_plane =
      Parse(rectangle + left + right + "rotate = { axis = [0, 0, 1], degrees = 45 }\n");
  CHECK(in_plane.mesh.planar);
  REQUIRE(in_plane.notes.size() == 1);
  CHECK_THAT(in_plane.notes[0], Contains("planar") && Contains("planar = false"));
  // A handle leaving the plane: a surface problem.
  const Scenario lifted = Parse(rectangle + left + right + "translate = [0, 0, 0.1]\n");
  CHECK(!lifted.mesh.planar);
  REQUIRE(lifted.notes.size() == 1);
  CHECK_THAT(lifted.notes[0], Contains("not planar") && Contains("handle 'right'"));
  // Explicit settings win.
  CHECK(!Parse("planar = false\n" + rectangle + left).mesh.planar);
  CHECK(Parse("planar = true\n" + rectangle + left).mesh.planar);
  ExpectError<ConfigError>(
      "planar = true\n" + rectangle + left + right + "translate = [0, 0, 0.1]\n",
      {"errors.toml:1", "planar = true", "handle 'right'", "z ="});
  ExpectError<ConfigError>("planar = true\nmesh = { builtin = \"plane\", vertices = 400 }\n",
                           {"errors.toml:1", "planar = true", "vertex", "z ="});
  ExpectError<ConfigError>("planar = 1\n" + rectangle, {"errors.toml:1", "true or false"});
  // OBJ/OFF files with z = 0 are planar like the built-ins; the spike plane is not.
  dir.Write("flat.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n");
  CHECK(Parse("mesh = \"flat.off\"\n", dir.path()).mesh.planar);
  CHECK(!Parse("mesh = { builtin = \"plane\", vertices = 400 }\n").mesh.planar);
  CHECK(!Parse(kMesh).mesh.planar);
}

TEST_CASE("example scenarios without data load: surface, volumetric twin, planar",
          "[io][scenario][tetrahedralize][planar]") {
  const auto dir = testing::SourceDir() / "experiments" / "scenarios";
  const Scenario surface = LoadScenario(dir / "cylinder-bend.toml");
  CHECK(surface.mesh.kind() == ElementKind::kTriangle);
  CHECK(!surface.mesh.planar);
  const Scenario twin = LoadScenario(dir / "cylinder-bend-tet.toml");
  CHECK(twin.mesh.kind() == ElementKind::kTetrahedron);
  CHECK(twin.mesh.num_elements() >= 10000);  // max_volume = 1e-4
  REQUIRE(twin.handles.size() == 2);
  CHECK(twin.handles[1].vertices.size() > 100);
  const Scenario flat = LoadScenario(dir / "rectangle-bend-2d.toml");
  CHECK(flat.mesh.planar);
  CHECK(std::abs(flat.mesh.num_vertices() - 20000) <= 2000);
  // The right end's targets lie where a length-preserving quarter-circle bend puts it: centred
  // on (R, 0.5 + R) with R = 4 / (pi / 2), within the rounding of the scenario's numbers.
  const ScenarioHandle& right = flat.handles[1];
  const Eigen::RowVector3d centre = right.targets.colwise().mean();
  const double radius = 4.0 / (M_PI / 2.0);
  CHECK(centre.x() == Approx(radius).margin(0.05));
  CHECK(centre.y() == Approx(0.5 + radius).margin(0.05));
  CHECK(centre.z() == 0.0);
}

TEST_CASE("example volumetric twin of the armadillo loads", "[io][scenario][shared][.slow]") {
  HARAP_REQUIRE_SHARED(armadillo, "meshes/armadillo-43k.obj.xz");
  const Scenario surface = LoadScenario(testing::SharedDir() / "scenarios/armadillo-bend-43k.toml");
  const auto start = std::chrono::steady_clock::now();
  const Scenario twin =
      LoadScenario(testing::SourceDir() / "experiments/scenarios/armadillo-bend-tet.toml");
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  REQUIRE(twin.mesh.kind() == ElementKind::kTetrahedron);
  WARN("armadillo-bend-tet.toml: " << twin.mesh.num_vertices() << " vertices, "
                                   << twin.mesh.num_elements() << " tetrahedra, loaded in "
                                   << seconds << " s");
  const Index n = surface.mesh.num_vertices();
  CHECK(twin.mesh.vertices.topRows(n) == surface.mesh.vertices);
  // The handles hold the same surface vertices (and interior points in the same slabs).
  for (size_t h = 0; h < 2; ++h) {
    std::vector<Index> on_surface;
    for (const Index v : twin.handles[h].vertices) {
      if (v < n) on_surface.push_back(v);
    }
    CHECK(on_surface == surface.handles[h].vertices);
  }
}

// -----------------------------------------------------------------------------------------------
// The shared scenarios.

void CheckSharedScenario(const std::filesystem::path& file) {
  INFO(file.string());
  const auto start = std::chrono::steady_clock::now();
  const Scenario scenario = LoadScenario(file);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  WARN(file.filename().string() << ": " << scenario.mesh.num_vertices() << " vertices, loaded in "
                                << seconds << " s");
  CHECK(scenario.file == file);
  REQUIRE(scenario.handles.size() == 2);
  for (const ScenarioHandle& handle : scenario.handles) {
    INFO(handle.name);
    CHECK(!handle.name.empty());
    CHECK(!handle.vertices.empty());
    CHECK(handle.targets.rows() == static_cast<Index>(handle.vertices.size()));
    CHECK(handle.targets.allFinite());
  }
  // The first handle of every shared scenario holds its vertices fixed.
  const ScenarioHandle& fixed = scenario.handles[0];
  for (size_t i = 0; i < fixed.vertices.size(); ++i) {
    REQUIRE(fixed.targets.row(static_cast<Index>(i)) ==
            scenario.mesh.vertices.row(fixed.vertices[i]));
  }
  const Constraints constraints = scenario.MergedConstraints();
  CHECK(constraints.indices.size() <=
        scenario.handles[0].vertices.size() + scenario.handles[1].vertices.size());
  CHECK(!constraints.indices.empty());
}

TEST_CASE("shared scenarios: the small ones load", "[io][scenario][shared]") {
  for (const char* name :
       {"cactus-small.toml", "bunny-ears.toml", "cow-stretch.toml", "armadillo-bend-43k.toml"}) {
    HARAP_REQUIRE_SHARED(file, std::string("scenarios/") + name);
    CheckSharedScenario(file);
  }
}

TEST_CASE("shared scenarios: every surface scenario loads", "[io][scenario][shared][.slow]") {
  HARAP_REQUIRE_SHARED(dir, "scenarios");
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() != ".toml") continue;
    CheckSharedScenario(entry.path());
    ++count;
  }
  CHECK(count >= 9);
  HARAP_REQUIRE_SHARED(armadillo, "scenarios/armadillo-bend.toml");
  CHECK(LoadScenario(armadillo).mesh.num_vertices() == 172966);
  HARAP_REQUIRE_SHARED(cylinder, "scenarios/cylinder-bend.toml");
  CHECK(std::abs(LoadScenario(cylinder).mesh.num_vertices() - 480000) <= 48000);
}

TEST_CASE("shared scenarios: every tetrahedral scenario loads", "[io][scenario][shared]") {
  HARAP_REQUIRE_SHARED(dir, "scenarios/tets");
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() != ".toml") continue;
    INFO(entry.path().string());
    const auto start = std::chrono::steady_clock::now();
    const Scenario scenario = LoadScenario(entry.path());
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const Mesh& mesh = scenario.mesh;
    WARN(entry.path().filename().string()
         << ": " << mesh.num_vertices() << " vertices, " << mesh.num_elements()
         << " tetrahedra, loaded in " << seconds << " s");
    CHECK(mesh.kind() == ElementKind::kTetrahedron);
    CHECK(!mesh.planar);
    // WRAPD's rest tetrahedra are all positively oriented (../shared/tets/README.md).
    CHECK(scenario.notes.empty());
    REQUIRE(scenario.initial);
    REQUIRE(scenario.initial->rows() == mesh.num_vertices());
    REQUIRE(scenario.handles.size() == 1);
    const ScenarioHandle& handle = scenario.handles[0];
    CHECK(handle.vertices.size() > 100);
    for (size_t i = 0; i < handle.vertices.size(); ++i) {
      REQUIRE(handle.targets.row(static_cast<Index>(i)) ==
              scenario.initial->row(handle.vertices[i]));
    }
    ++count;
  }
  CHECK(count == 11);
}

}  // namespace
}  // namespace harap
