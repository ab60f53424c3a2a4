// SPDX-License-Identifier: MIT
// harap view without a browser: the page's messages (parsing and validation) and a page's
// session driven message by message, its answers decoded.
#include <fmt/format.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cstring>
#include <nlohmann/json.hpp>

#include "api/builtins.h"
#include "framework/error.h"
#include "io/mesh_writers.h"
#include "io/scenario.h"
#include "tests/support/shared_data.h"
#include "tests/support/temp_folder.h"
#include "tests/support/test_meshes.h"
#include "view/page_session.h"
#include "view/protocol.h"
#include "view/scenario_source.h"

namespace harap::view {
namespace {

using Json = nlohmann::json;
using namespace harap::testing;

MessageLimits Limits() {
  MessageLimits limits;
  limits.num_vertices = 10;
  limits.num_groups = 2;
  return limits;
}

std::string Refusal(const std::string& text) {
  try {
    ParseClientMessage(text, Limits());
  } catch (const InputError& error) {
    return error.what();
  }
  return "accepted";
}

TEST_CASE("page messages: valid ones parse", "[view]") {
  const ParsedMessage move = ParseClientMessage(
      R"({"type":"move","group":1,"transform":[0,-1,0,0.5, 1,0,0,0, 0,0,1,2],"solve":"full","id":7})",
      Limits());
  REQUIRE(move.id == 7);
  const auto& m = std::get<MoveMessage>(move.message);
  CHECK(m.group == 1);
  CHECK(m.full);
  CHECK(m.rotation(0, 1) == -1.0);
  CHECK(m.translation == Eigen::Vector3d(0.5, 0.0, 2.0));
  const auto add = std::get<AddHandleMessage>(
      ParseClientMessage(R"({"type":"add_handle","vertex":9,"radius":0.25})", Limits()).message);
  CHECK(add.vertex == 9);
  CHECK(add.radius == 0.25);
  const auto configure = std::get<ConfigureMessage>(
      ParseClientMessage(R"({"type":"configure","optimizer":"hierarchical","tolerance":1e-7})",
                         Limits())
          .message);
  CHECK(configure.optimizer == "hierarchical");
  CHECK(configure.tolerance == 1e-7);
}

TEST_CASE("page messages: which ones make a running full solve pointless", "[view]") {
  CHECK(SupersedesFullSolve(R"({"type":"move","group":0,"transform":[],"solve":"full"})"));
  CHECK(SupersedesFullSolve(R"({"type":"move","group":99})"));  // refused later, still a move
  CHECK(SupersedesFullSolve(R"({"type":"solve"})"));
  CHECK(SupersedesFullSolve(R"({"type":"configure","energy":"arap"})"));
  CHECK(SupersedesFullSolve(R"({"type":"remove_handle","group":1})"));
  CHECK_FALSE(SupersedesFullSolve(R"({"type":"add_handle","vertex":3,"radius":0.1})"));
  CHECK_FALSE(SupersedesFullSolve(R"({"type":"level","level":1})"));
  CHECK_FALSE(SupersedesFullSolve(R"({"type":"scenario"})"));
  CHECK_FALSE(SupersedesFullSolve(R"({"type":7})"));
  CHECK_FALSE(SupersedesFullSolve(R"(["move"])"));
  CHECK_FALSE(SupersedesFullSolve("not json"));
  CHECK_FALSE(SupersedesFullSolve(""));
}

TEST_CASE("page messages: malformed ones are refused naming the problem", "[view]") {
  CHECK(Refusal("{") == "message is not valid JSON");
  CHECK(Refusal("[1,2]") == "message is not a JSON object");
  CHECK(Refusal(R"({"type":"fly"})").find("unknown message type 'fly' (valid: move") == 0);
  CHECK(Refusal(R"({"type":"solve","extra":1})").find("unknown field 'extra'") !=
        std::string::npos);
  CHECK(Refusal(R"({"type":"remove_handle","group":2})") ==
        "message 'remove_handle': 'group' = 2 is out of range [0, 1]");
  CHECK(Refusal(R"({"type":"remove_handle","group":1.5})") ==
        "message 'remove_handle': 'group' must be an integer");
  CHECK(Refusal(R"({"type":"add_handle","vertex":10,"radius":1})") ==
        "message 'add_handle': 'vertex' = 10 is out of range [0, 9]");
  CHECK(Refusal(R"({"type":"add_handle","vertex":1,"radius":-1})") ==
        "message 'add_handle': 'radius' = -1 is negative");
  CHECK(Refusal(R"({"type":"move","group":0,"transform":[1,0,0]})").find("12 numbers") !=
        std::string::npos);
  CHECK(Refusal(R"({"type":"move","group":0,"transform":[1,0,0,1e400,0,1,0,0,0,0,1,0]})") ==
        "message is not valid JSON");
  CHECK(Refusal(R"({"type":"move","group":0,"transform":[1,0,0,"x",0,1,0,0,0,0,1,0]})") ==
        "message 'move': transform[3] must be a number");
  CHECK(Refusal(R"({"type":"move","group":0,"transform":[2,0,0,0,0,1,0,0,0,0,1,0]})")
            .find("not a rotation") != std::string::npos);
  CHECK(Refusal(R"({"type":"move","group":0,"transform":[-1,0,0,0,0,1,0,0,0,0,1,0]})")
            .find("not a rotation") != std::string::npos);
  CHECK(Refusal(R"({"type":"solve","id":-3})") ==
        "message 'solve': 'id' must be a non-negative integer");
  CHECK(Refusal(R"({"type":"configure","tolerance":2})") ==
        "message 'configure': 'tolerance' = 2 is not in (0, 1)");
  CHECK(Refusal(std::string(70000, ' ')).find("refused (at most") != std::string::npos);
  CHECK(MessageIdOf(R"({"type":"fly","id":12})") == 12);
  CHECK_FALSE(MessageIdOf("{").has_value());
  MessageLimits none = Limits();
  none.num_groups = 0;
  CHECK_THROWS_WITH(ParseClientMessage(R"({"type":"remove_handle","group":0})", none),
                    "message 'remove_handle': there is no handle");
}

// A page's session on a 20×20 grid with its left column fixed and its right column as a
// second handle, answers collected.
struct Page {
  TempFolder folder{"view-page"};
  Registries registries = MakeBuiltinRegistries();
  ViewSource source;
  std::vector<Outgoing> sent;
  std::unique_ptr<PageSession> page;
  bool newer_message_waiting = false;  ///< what the page session is told while it solves

  /// `right_weight`: the right column's handle weight (finite: soft). `options`: what the page
  /// asked for when it connected.
  /// `waiting_at_start`: a superseding message waits while the first solve runs.
  explicit Page(double right_weight = Constraints::kHardWeight, const PageOptions& options = {},
                bool waiting_at_start = false)
      : newer_message_waiting(waiting_at_start) {
    Mesh mesh = Grid(20, 20);
    std::vector<Index> left, right;
    for (Index v = 0; v < mesh.num_vertices(); ++v) {
      if (mesh.vertices(v, 0) < 1e-9) left.push_back(v);
      if (mesh.vertices(v, 0) > mesh.vertices.col(0).maxCoeff() - 1e-9) right.push_back(v);
    }
    source.scenario.mesh = mesh;
    for (const auto& [name, vertices] : {std::pair{"left", left}, std::pair{"right", right}}) {
      ScenarioHandle handle;
      handle.name = name;
      handle.vertices = vertices;
      handle.targets.resize(static_cast<Eigen::Index>(vertices.size()), 3);
      for (size_t i = 0; i < vertices.size(); ++i)
        handle.targets.row(static_cast<Eigen::Index>(i)) = mesh.vertices.row(vertices[i]);
      if (std::string(name) == "right") handle.weight = right_weight;
      source.scenario.handles.push_back(handle);
    }
    source.run_config = ConfigNode::Parse("[optimizer]\ntolerance = 1e-10\n", "test");
    const std::filesystem::path mesh_file = folder.dir / "grid.obj";
    WriteMesh(mesh_file, mesh.vertices, mesh.elements);
    source.mesh_toml = fmt::format("mesh = \"{}\"\n", mesh_file.string());
    source.threads = 1;
    page = std::make_unique<PageSession>(
        registries, source, [this](Outgoing message) { sent.push_back(message); }, options,
        [this] { return newer_message_waiting; });
    page->Start();
  }
  std::vector<Json> Texts() const {
    std::vector<Json> texts;
    for (const Outgoing& message : sent) {
      if (!message.binary) texts.push_back(Json::parse(message.data));
    }
    return texts;
  }
  Json Last(const std::string& type) const {
    const std::vector<Json> texts = Texts();
    for (auto it = texts.rbegin(); it != texts.rend(); ++it) {
      if ((*it)["type"] == type) return *it;
    }
    return nullptr;
  }
};

uint32_t U32(const std::string& frame, size_t offset) {
  uint32_t value = 0;
  std::memcpy(&value, frame.data() + offset, 4);
  return value;
}

TEST_CASE("a page's session: mesh, solve, moves, handle edits, bad messages", "[view]") {
  Page page;
  REQUIRE(page.sent.size() >= 4);
  REQUIRE(page.sent[0].binary);
  CHECK(U32(page.sent[0].data, 0) == static_cast<uint32_t>(FrameKind::kMesh));
  CHECK(U32(page.sent[0].data, 4) == 400);  // drawn: every vertex (below the display budget)
  CHECK(U32(page.sent[0].data, 12) == 400);
  CHECK(page.Last("handles")["groups"].size() == 2);
  CHECK(page.Last("solved")["mode"] == "full");
  CHECK(page.Last("solved")["energy"].get<double>() < 1e-12);  // handles at rest: no energy

  // Moving the right column: a preview, then a full solve whose energy is the session's.
  const size_t before = page.sent.size();
  page.page->HandleText(
      R"({"type":"move","group":1,"transform":[1,0,0,0.3, 0,1,0,0, 0,0,1,0],"id":5})");
  REQUIRE(page.sent.size() == before + 2);
  const Outgoing& frame = page.sent[before];
  REQUIRE(frame.binary);
  CHECK(U32(frame.data, 0) == static_cast<uint32_t>(FrameKind::kPositions));
  CHECK(U32(frame.data, 4) == 5);
  CHECK(page.Last("solved")["mode"] == "preview");
  page.page->HandleText(
      R"({"type":"move","group":1,"transform":[1,0,0,0.3, 0,1,0,0, 0,0,1,0],"solve":"full","id":6})");
  const Json solved = page.Last("solved");
  CHECK(solved["id"] == 6);
  CHECK(solved["converged"] == true);
  CHECK(solved["energy"].get<double>() > 0.0);
  CHECK_FALSE(solved["trace"].empty());
  // The same targets again: nothing moves, so the frame lists no vertex.
  page.page->HandleText(
      R"({"type":"move","group":1,"transform":[1,0,0,0.3, 0,1,0,0, 0,0,1,0],"solve":"full","id":7})");
  const Outgoing& same = page.sent[page.sent.size() - 2];
  CHECK(U32(same.data, 8) < 400);

  // The exported scenario holds the targets: loading it gives the right column moved by 0.3.
  page.page->HandleText(R"({"type":"scenario","id":8})");
  const std::string toml = page.Last("scenario")["toml"];
  const Scenario exported = ParseScenario(toml, "exported", ".");
  REQUIRE(exported.handles.size() == 2);
  CHECK(exported.handles[1].name == "right");
  for (size_t i = 0; i < exported.handles[1].vertices.size(); ++i) {
    const Index v = exported.handles[1].vertices[i];
    CHECK(exported.handles[1].targets(static_cast<Eigen::Index>(i), 0) ==
          Approx(page.source.scenario.mesh.vertices(v, 0) + 0.3).margin(1e-12));
  }

  // Add a handle in the middle, then remove it; removing the last handles is refused.
  page.page->HandleText(R"({"type":"add_handle","vertex":210,"radius":0.01,"id":9})");
  CHECK(page.Last("handles")["groups"].size() == 3);
  CHECK(page.Last("handles")["id"] == 9);
  CHECK(page.Last("edit")["edits"][0]["levels"][0]["route"] != "none");
  page.page->HandleText(R"({"type":"remove_handle","group":2,"id":10})");
  CHECK(page.Last("handles")["groups"].size() == 2);
  page.page->HandleText(R"({"type":"remove_handle","group":0})");
  page.page->HandleText(R"({"type":"remove_handle","group":0,"id":11})");
  CHECK(page.Last("error")["message"] == "message 'remove_handle': the last handle must stay");
  CHECK(page.Last("error")["id"] == 11);

  // Bad messages: answered with errors, the session keeps working.
  page.page->HandleText(R"({"type":"move","group":3,"transform":[],"id":12})");
  CHECK(page.Last("error")["id"] == 12);
  page.page->HandleBinary(16);
  CHECK(page.Last("error")["message"].get<std::string>().find("binary message of 16 bytes") == 0);
  page.page->HandleText(R"({"type":"configure","energy":"nonsense","id":13})");
  CHECK(page.Last("error")["id"] == 13);
  page.page->HandleText(R"({"type":"solve","id":14})");
  CHECK(page.Last("solved")["id"] == 14);

  // A level's clusters: one per display vertex (a classic session's only level: the vertices).
  page.page->HandleText(R"({"type":"level","level":0,"id":15})");
  const Outgoing& clusters = page.sent.back();
  REQUIRE(clusters.binary);
  CHECK(U32(clusters.data, 0) == static_cast<uint32_t>(FrameKind::kClusters));
  CHECK(U32(clusters.data, 8) == 400);
  CHECK(U32(clusters.data, 12 + 4 * 399) == 399);
  page.page->HandleText(R"({"type":"level","level":1,"id":16})");
  CHECK(page.Last("error")["message"].get<std::string>().find("'level' = 1 is out of range") !=
        std::string::npos);
}

TEST_CASE("a page's configure starts from the source's options every time", "[view]") {
  Page page;
  page.page->HandleText(R"({"type":"configure","preset":"fast","id":1})");
  const std::string fast = page.Last("ready")["config"];
  CHECK(fast.find("level_0") != std::string::npos);
  CHECK(fast.find("preset") == std::string::npos);  // its settings stand in for it
  // A refused configure leaves nothing behind, and no preset means none of its settings.
  page.page->HandleText(R"({"type":"configure","energy":"nonsense","id":2})");
  CHECK(page.Last("error")["id"] == 2);
  page.page->HandleText(R"({"type":"configure","id":3})");
  const std::string plain = page.Last("ready")["config"];
  CHECK(plain.find("level_0") == std::string::npos);
  CHECK(plain.find("nonsense") == std::string::npos);
  CHECK(plain.find("tolerance = 1e-10") != std::string::npos);
  CHECK(page.Last("solved")["converged"] == true);
}

TEST_CASE("a page's session: consecutive preview moves of a group are solved once", "[view]") {
  Page page;
  const size_t before = page.sent.size();
  page.page->HandleTexts(
      {R"({"type":"move","group":1,"transform":[1,0,0,0.1, 0,1,0,0, 0,0,1,0],"id":1})",
       R"({"type":"move","group":1,"transform":[1,0,0,0.2, 0,1,0,0, 0,0,1,0],"id":2})",
       R"({"type":"move","group":1,"transform":[1,0,0,0.3, 0,1,0,0, 0,0,1,0],"id":3})"});
  REQUIRE(page.sent.size() == before + 2);
  CHECK(page.Last("solved")["id"] == 3);
}

TEST_CASE("a page's session: a full solve after a preview of the same targets converges",
          "[view]") {
  const std::string preview =
      R"({"type":"move","group":1,"transform":[0.8,-0.6,0,0.3, 0.6,0.8,0,0, 0,0,1,0],"id":1})";
  const std::string full =
      R"({"type":"move","group":1,"transform":[0.8,-0.6,0,0.3, 0.6,0.8,0,0, 0,0,1,0],"solve":"full","id":2})";
  Page previewed, direct;
  previewed.page->HandleText(preview);
  previewed.page->HandleText(full);
  direct.page->HandleText(full);
  const Json preview_solved = previewed.Last("solved");
  const Json direct_solved = direct.Last("solved");
  CHECK(preview_solved["mode"] == "full");
  CHECK(preview_solved["converged"] == true);
  // More than the one iteration that a preview's state taken for a converged start would give.
  CHECK(preview_solved["iterations"].get<int>() > 1);
  const double energy = direct_solved["energy"];
  CHECK(preview_solved["energy"].get<double>() == Approx(energy).epsilon(1e-6));
}

TEST_CASE("a page's session: a superseding message stops a full solve; refused, it lets it resume",
          "[view]") {
  const std::string full =
      R"({"type":"move","group":1,"transform":[0.8,-0.6,0,0.3, 0.6,0.8,0,0, 0,0,1,0],"solve":"full","id":2})";
  Page interrupted, direct;
  direct.page->HandleText(full);
  const Json converged = direct.Last("solved");
  REQUIRE(converged["converged"] == true);
  REQUIRE(converged["iterations"].get<int>() > 2);

  // While a superseding message waits, the full solve stops after an iteration, answered once;
  // it is not resumed while the message still waits (the next batch carries it out).
  interrupted.newer_message_waiting = true;
  interrupted.page->HandleText(full);
  std::vector<Json> solves;
  for (const Json& text : interrupted.Texts()) {
    if (text["type"] == "solved" && text.contains("id") && text["id"] == 2) solves.push_back(text);
  }
  REQUIRE(solves.size() == 1);
  CHECK(solves[0]["interrupted"] == true);
  CHECK(solves[0]["converged"] == false);
  CHECK(solves[0]["iterations"].get<int>() < converged["iterations"].get<int>());

  // The message that stopped it is refused (a group that does not exist): the solve continues
  // to the tolerance and answers with the interrupted solve's id.
  interrupted.newer_message_waiting = false;
  interrupted.page->HandleText(
      R"({"type":"move","group":7,"transform":[1,0,0,0, 0,1,0,0, 0,0,1,0],"id":3})");
  CHECK(interrupted.Last("error")["id"] == 3);
  const Json resumed = interrupted.Last("solved");
  CHECK(resumed["id"] == 2);
  CHECK(resumed["interrupted"] == false);
  CHECK(resumed["converged"] == true);
  CHECK(resumed["energy"].get<double>() == Approx(converged["energy"].get<double>()).epsilon(1e-6));

  // A move supersedes an interrupted solve: it is not resumed after the move's own solve.
  interrupted.newer_message_waiting = true;
  interrupted.page->HandleText(full);
  interrupted.newer_message_waiting = false;
  const size_t before = interrupted.Texts().size();
  interrupted.page->HandleText(
      R"({"type":"move","group":1,"transform":[1,0,0,0.2, 0,1,0,0, 0,0,1,0],"id":4})");
  const std::vector<Json> after = interrupted.Texts();
  int solved_after = 0;
  for (size_t i = before; i < after.size(); ++i) solved_after += after[i]["type"] == "solved";
  CHECK(solved_after == 1);
  CHECK(interrupted.Last("solved")["id"] == 4);
  CHECK(interrupted.Last("solved")["mode"] == "preview");

  // A superseding message in the same batch: the full solve stops after one iteration, and the
  // preview after it is the last answer.
  interrupted.page->HandleTexts(
      {R"({"type":"move","group":1,"transform":[0.6,-0.8,0,0.1, 0.8,0.6,0,0, 0,0,1,0],"solve":"full","id":5})",
       R"({"type":"move","group":1,"transform":[1,0,0,0.1, 0,1,0,0, 0,0,1,0],"id":6})"});
  std::vector<Json> batch;
  for (const Json& text : interrupted.Texts()) {
    if (text["type"] == "solved" && text.contains("id") && text["id"] >= 5) batch.push_back(text);
  }
  REQUIRE(batch.size() == 2);
  CHECK(batch[0]["id"] == 5);
  CHECK(batch[0]["interrupted"] == true);
  CHECK(batch[0]["iterations"].get<int>() == 1);
  CHECK(batch[1]["id"] == 6);
  CHECK(batch[1]["mode"] == "preview");
}

TEST_CASE("a page's session: a first solve stopped at start resumes when nothing supersedes it",
          "[view]") {
  Page page(Constraints::kHardWeight, {}, /*waiting_at_start=*/true);
  const Json stopped = page.Last("solved");
  CHECK(stopped["interrupted"] == true);
  CHECK_FALSE(stopped.contains("id"));
  page.newer_message_waiting = false;
  page.page->HandleText(R"({"type":"solve","group":0,"id":1})");  // refused: no key 'group'
  CHECK(page.Last("error")["id"] == 1);
  const Json resumed = page.Last("solved");
  CHECK(resumed["interrupted"] == false);
  CHECK_FALSE(resumed.contains("id"));
  CHECK(resumed["converged"] == true);
}

TEST_CASE("the display of a large mesh: decimated to the budget, onto mesh vertices", "[view]") {
  const Mesh sphere = Icosphere(4);  // 2562 vertices
  const DisplayMesh all = MakeDisplayMesh(sphere, 5000);
  CHECK(all.vertices.size() == static_cast<size_t>(sphere.num_vertices()));
  CHECK(all.triangles.rows() == sphere.num_elements());
  for (const Index budget : {1000, 300}) {
    const DisplayMesh display = MakeDisplayMesh(sphere, budget);
    CHECK(display.vertices.size() <= static_cast<size_t>(budget));
    CHECK(display.vertices.size() > static_cast<size_t>(budget / 4));
    CHECK(std::is_sorted(display.vertices.begin(), display.vertices.end()));
    CHECK(display.triangles.minCoeff() >= 0);
    CHECK(display.triangles.maxCoeff() < static_cast<Index>(display.vertices.size()));
    // Still a surface around the centre: no triangle faces inwards.
    for (Eigen::Index f = 0; f < display.triangles.rows(); ++f) {
      const Eigen::RowVector3d a = sphere.vertices.row(display.vertices[display.triangles(f, 0)]),
                               b = sphere.vertices.row(display.vertices[display.triangles(f, 1)]),
                               c = sphere.vertices.row(display.vertices[display.triangles(f, 2)]);
      CHECK((b - a).cross(c - a).dot(a + b + c) > -1e-12);
    }
  }
}

std::string QueryRefusal(const std::string& query) {
  try {
    ParsePageQuery(query);
  } catch (const InputError& error) {
    return error.what();
  }
  return "accepted";
}

TEST_CASE("the page's WebSocket address: its query is parsed and checked", "[view]") {
  CHECK(ParsePageQuery("").display_vertices == 0);
  CHECK(ParsePageQuery("display_vertices=20000").display_vertices == 20000);
  CHECK(ParsePageQuery("display_vertices=100").display_vertices == 100);
  CHECK_THAT(QueryRefusal("display=5"),
             Catch::Contains("unknown parameter 'display'; valid: display_vertices"));
  CHECK_THAT(QueryRefusal("display_vertices=20000&x"), Catch::Contains("unknown parameter 'x'"));
  CHECK_THAT(QueryRefusal("display_vertices=200&display_vertices=300"),
             Catch::Contains("given twice"));
  CHECK(ParsePageQuery("&display_vertices=300&&").display_vertices == 300);  // empty pairs
  CHECK(ParsePageQuery("display_vertices=2147483647").display_vertices == 2147483647);
  for (const char* value :
       {"", "99", "-5", "2e4", "20000abc", "nan", "2147483648", "99999999999999999999"}) {
    CAPTURE(value);
    CHECK_THAT(QueryRefusal(fmt::format("display_vertices={}", value)),
               Catch::Contains("is not an integer in [100, 2147483647]"));
  }
  CHECK_THAT(QueryRefusal("display_vertices"), Catch::Contains("is not an integer"));
  // A long garbage key is cut in the message.
  CHECK(QueryRefusal(std::string(10000, 'k')).size() < 200);
}

TEST_CASE("a page's display: the smaller of its own request and the server's budget", "[view]") {
  PageOptions options;
  options.display_vertices = 150;  // the grid has 400 vertices, the server's budget is 200000
  Page small(Constraints::kHardWeight, options);
  // The page hears that the display is decimated, then gets the mesh frame.
  REQUIRE(small.sent.size() >= 2);
  CHECK_THAT(small.sent[0].data, Catch::Contains("decimating the display to at most 150"));
  const Outgoing& mesh_frame = small.sent[1];
  REQUIRE(mesh_frame.binary);
  const uint32_t drawn = U32(mesh_frame.data, 4);
  CHECK(drawn <= 150);
  CHECK(drawn > 150 / 4);
  CHECK(U32(mesh_frame.data, 12) == 400);  // the session still solves every vertex
  CHECK(small.Last("mesh")["display_vertices"] == drawn);
  CHECK(small.Last("solved")["mode"] == "full");

  options.display_vertices = 100000;  // more than the mesh: all of it
  Page large(Constraints::kHardWeight, options);
  CHECK(U32(large.sent.front().data, 4) == 400);
}

TEST_CASE("the surface of a tetrahedral mesh: boundary faces, outwards", "[view]") {
  const Mesh box = TetBox(3, 3, 3);
  const Elements surface = SurfaceTriangles(box);
  CHECK(surface.rows() == 6 * 2 * 2 * 2);  // 6 sides, 2×2 squares, 2 triangles each
  const Eigen::RowVector3d center = box.vertices.colwise().mean();
  for (Eigen::Index f = 0; f < surface.rows(); ++f) {
    const Eigen::RowVector3d a = box.vertices.row(surface(f, 0)),
                             b = box.vertices.row(surface(f, 1)),
                             c = box.vertices.row(surface(f, 2));
    CHECK((b - a).cross(c - a).dot((a + b + c) / 3.0 - center) > 0.0);
  }
}

TEST_CASE("view sources: a mesh file alone has no handles; a scenario keeps its mesh line",
          "[view]") {
  const std::filesystem::path scenario = SourceDir() / "tests" / "view" / "small-bend.toml";
  const ViewSource source = LoadViewSource(scenario, ConfigNode::Parse("", "test"), 1);
  CHECK(source.scenario.handles.size() == 2);
  CHECK(source.mesh_toml == "mesh = { builtin = 'cylinder', vertices = 2000 }\n");
}

TEST_CASE("a page's session: a scenario's soft handle stays soft and is exported so", "[view]") {
  const std::string move =
      R"({"type":"move","group":1,"transform":[1,0,0,0.3, 0,1,0,0.2, 0,0,1,0],"solve":"full","id":1})";
  Page hard, soft(5.0);
  hard.page->HandleText(move);
  soft.page->HandleText(move);
  const Json hard_solved = hard.Last("solved");
  const Json soft_solved = soft.Last("solved");
  CHECK(soft_solved["converged"] == true);
  // The pinned solution is one the soft problem may take, with no pull left: the soft
  // handle's minimum lies below it.
  CHECK(soft_solved["energy"].get<double>() > 0.0);
  CHECK(soft_solved["energy"].get<double>() < hard_solved["energy"].get<double>() * (1 - 1e-6));
  // A preview with the soft handle works too.
  soft.page->HandleText(
      R"({"type":"move","group":1,"transform":[1,0,0,0.2, 0,1,0,0.1, 0,0,1,0],"id":2})");
  CHECK(soft.Last("solved")["mode"] == "preview");
  CHECK(soft.Last("solved")["id"] == 2);
  // The exported scenario keeps the weight; `harap deform` on it solves the same problem.
  soft.page->HandleText(R"({"type":"scenario","id":3})");
  const std::string toml = soft.Last("scenario")["toml"];
  const Scenario exported = ParseScenario(toml, "exported", ".");
  REQUIRE(exported.handles.size() == 2);
  CHECK(exported.handles[0].weight == Constraints::kHardWeight);
  CHECK(exported.handles[1].weight == 5.0);
}

}  // namespace
}  // namespace harap::view
