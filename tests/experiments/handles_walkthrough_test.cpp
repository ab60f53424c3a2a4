// SPDX-License-Identifier: MIT
// A new user's walkthroughs (issue 24): `harap handles` before solving, absolute coordinates,
// per-vertex targets, the deformation benchmark's .sel/.def files, refining a non-manifold mesh.
// Small generated meshes only.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <sstream>
#include <string>

#include "tests/support/run_harap.h"

namespace {

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using harap::testing::RunHarap;

struct Folder {
  explicit Folder(const std::string& name)
      : dir(fs::temp_directory_path() / fmt::format("harap-ux-{}-{}", name, getpid())) {
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  ~Folder() {
    std::error_code ignore;
    fs::remove_all(dir, ignore);
  }
  std::string Write(const std::string& name, const std::string& text) const {
    std::ofstream(dir / name) << text;
    return (dir / name).string();
  }
  fs::path dir;
};

std::string ReadText(const fs::path& file) {
  std::ifstream stream(file, std::ios::binary);
  std::stringstream buffer;
  buffer << stream.rdbuf();
  return buffer.str();
}

// A bar along x in [0, 3] with a 1 x 1 cross-section, rings at x = 0, 1, 2, 3, as OFF.
std::string BarOff() {
  std::string off = "OFF\n16 28 0\n";
  for (int ring = 0; ring < 4; ++ring) {
    off += fmt::format("{} 0 0\n{} 1 0\n{} 1 1\n{} 0 1\n", ring, ring, ring, ring);
  }
  for (int ring = 0; ring < 3; ++ring) {
    for (int k = 0; k < 4; ++k) {
      const int a = 4 * ring + k, b = 4 * ring + (k + 1) % 4, c = a + 4, d = b + 4;
      off += fmt::format("3 {} {} {}\n3 {} {} {}\n", a, b, d, a, d, c);
    }
  }
  off += "3 0 2 1\n3 0 3 2\n3 12 13 14\n3 12 14 15\n";  // caps
  return off;
}

TEST_CASE("harap handles: box, per-handle count, centroid and motion; coloured PLY",
          "[experiments][handles]") {
  Folder folder("handles");
  folder.Write("bar.off", BarOff());
  const std::string scenario = folder.Write(
      "bar.toml", "mesh = \"bar.off\"\n"
                  "[[handle]]\nname = \"left\"\nselect.slab = { axis = \"x\", from = 0, to = 0.1 }\n"
                  "[[handle]]\nname = \"right\"\nunits = \"absolute\"\n"
                  "select.slab = { axis = \"x\", from = 2.5, to = 3.5 }\n"
                  "rotate = { axis = [1, 0, 0], degrees = 30 }\ntranslate = [0, 0, 0.5]\n");
  const std::string ply = (folder.dir / "handles.ply").string();
  const auto result = RunHarap(fmt::format("handles {} --out {}", scenario, ply));
  INFO(result.output);
  REQUIRE(result.status == 0);
  CHECK_THAT(result.output, Contains("bounding box x in [0, 3], y in [0, 1], z in [0, 1]"));
  CHECK_THAT(result.output, Contains("'left' (blue in the PLY)"));
  CHECK_THAT(result.output, Contains("'right' (red in the PLY)"));
  CHECK_THAT(result.output, Contains("vertices  4"));
  CHECK_THAT(result.output, Contains("centroid  (3, 0.5, 0.5) -> (3, 0.5, 1)"));
  CHECK_THAT(result.output, Contains("rotate 30° about (1, 0, 0)"));
  CHECK_THAT(result.output, Contains("translate (0, 0, 0.5)"));
  CHECK_THAT(result.output, Contains("absolute coordinates"));
  CHECK_THAT(result.output, Contains("free        8 of 16 vertices"));
  CHECK_THAT(result.output, !Contains("iterations"));  // nothing solved
  // The PLY: 16 vertices with colours, handle colours where the handles are, grey elsewhere.
  const std::string bytes = ReadText(ply);
  REQUIRE(bytes.find("property uchar red") != std::string::npos);
  const size_t body = bytes.find("end_header\n") + 11;
  auto color = [&](int v) {
    const size_t at = body + static_cast<size_t>(v) * (3 * 8 + 3) + 24;
    return fmt::format("{} {} {}", static_cast<int>(static_cast<unsigned char>(bytes[at])),
                       static_cast<int>(static_cast<unsigned char>(bytes[at + 1])),
                       static_cast<int>(static_cast<unsigned char>(bytes[at + 2])));
  };
  CHECK(color(0) == "31 119 180");   // left: blue
  CHECK(color(15) == "214 39 40");   // right: red
  CHECK(color(6) == "190 190 190");  // free: grey
  // A non-PLY name is refused before anything is written.
  const auto wrong = RunHarap(fmt::format("handles {} --out {}", scenario,
                                          (folder.dir / "handles.obj").string()));
  CHECK(wrong.status == 1);
  CHECK_THAT(wrong.output, Contains("ending in .ply"));
  CHECK_FALSE(fs::exists(folder.dir / "handles.obj"));
  // A selection in the wrong units: the error says which units and gives the box.
  const std::string miss = folder.Write(
      "miss.toml", "mesh = \"bar.off\"\n[[handle]]\nselect.slab = { axis = \"x\", from = 2.5, "
                   "to = 3.0 }\n");
  const auto missed = RunHarap("handles " + miss);
  CHECK(missed.status == 1);
  CHECK_THAT(missed.output, Contains("fractions of the bounding box x in [0, 3]"));
  CHECK_THAT(missed.output, Contains("units = \"absolute\""));
}

TEST_CASE("deformation benchmark files and per-vertex targets: handles, then deform",
          "[experiments][handles]") {
  Folder folder("benchmark");
  folder.Write("bar.off", BarOff());
  std::string labels;
  for (int v = 0; v < 16; ++v) labels += v < 4 ? "0\n" : v < 12 ? "1\n" : "2\n";
  folder.Write("bar.sel", labels);
  folder.Write("bar.def", "1 0 0 0\n0 1 0 0\n0 0 1 1.5\n0 0 0 1\n");  // lift by 1.5
  const std::string scenario = folder.Write(
      "bar.toml", "mesh = \"bar.off\"\nselection = \"bar.sel\"\ndeformation = \"bar.def\"\n");
  const auto shown = RunHarap("handles " + scenario);
  INFO(shown.output);
  REQUIRE(shown.status == 0);
  CHECK_THAT(shown.output, Contains("'fixed'"));
  CHECK_THAT(shown.output, Contains("label 2 of bar.sel"));
  CHECK_THAT(shown.output, Contains("4x4 transform from bar.def"));
  CHECK_THAT(shown.output, Contains("centroid  (3, 0.5, 0.5) -> (3, 0.5, 2)"));
  const auto solved = RunHarap(fmt::format("deform {} --out {}", scenario,
                                           (folder.dir / "bar-out.ply").string()));
  INFO(solved.output);
  CHECK(solved.status == 0);

  // Per-vertex targets: the right end's four vertices, given one by one.
  folder.Write("moves.txt", "# index x y z\n12 3 0 1\n13 3 1 1\n14 3 1 2\n15 3 0 2\n");
  const std::string targets = folder.Write(
      "targets.toml", "mesh = \"bar.off\"\n"
                      "[[handle]]\nname = \"left\"\nselect.indices = [0, 1, 2, 3]\n"
                      "[[handle]]\nname = \"lifted\"\ntarget_file = \"moves.txt\"\n");
  const auto listed = RunHarap("handles " + targets);
  INFO(listed.output);
  CHECK(listed.status == 0);
  CHECK_THAT(listed.output, Contains("per-vertex targets from"));
  CHECK_THAT(listed.output, Contains("centroid  (3, 0.5, 0.5) -> (3, 0.5, 1.5)"));
  folder.Write("moves.txt", "12 3 0 1\n13 3 1\n");
  const auto bad = RunHarap("deform " + targets);
  CHECK(bad.status == 1);
  CHECK_THAT(bad.output, Contains("moves.txt:2"));
  CHECK_THAT(bad.output, Contains("4 values"));
}

TEST_CASE("refine = 1 of a non-manifold mesh refines with a note", "[experiments][handles]") {
  Folder folder("nonmanifold");
  // Three triangles on the edge (0, 1) and a second fan touching vertex 2.
  folder.Write("book.obj",
               "v 0 0 0\nv 2 0 0\nv 1 1 0\nv 1 -1 0\nv 1 0 1\nv 2 2 0\nv 0 2 0\nv 1 3 0\n"
               "f 1 2 3\nf 2 1 4\nf 1 2 5\nf 3 6 8\nf 3 8 7\n");
  const std::string scenario = folder.Write(
      "book.toml", "mesh = \"book.obj\"\nrefine = 1\n"
                   "[[handle]]\nselect.indices = [0]\n");
  const auto result = RunHarap("handles " + scenario);
  INFO(result.output);
  REQUIRE(result.status == 0);
  CHECK_THAT(result.output, Contains("(20 vertices, 20 faces)"));  // 8 + 12 edges, 4 x 5
  CHECK_THAT(result.output, Contains("Loop variant"));
  CHECK_THAT(result.output, Contains("1 non-manifold edge "));
}

}  // namespace
