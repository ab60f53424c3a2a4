// SPDX-License-Identifier: MIT
#include "cli/output_checks.h"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string>
#include <system_error>

#include "framework/error.h"

namespace harap {

namespace fs = std::filesystem;

void CheckWritable(const fs::path& file, std::string_view option) {
  std::error_code error;
  if (fs::is_directory(file, error)) {
    throw InputError(fmt::format("{} {}: is a folder; give a file name", option, file.string()));
  }
  const fs::path parent = file.has_parent_path() ? file.parent_path() : fs::path(".");
  if (!fs::is_directory(parent, error)) {
    throw InputError(fmt::format("{} {}: the folder {} does not exist (create it first)", option,
                                 file.string(), parent.string()));
  }
  const bool existed = fs::exists(file, error);
  // Append mode opens an existing file without truncating it (the run may still fail).
  std::FILE* stream = std::fopen(file.c_str(), "ab");
  if (stream == nullptr) {
    throw InputError(fmt::format("{} {}: cannot write the file ({})", option, file.string(),
                                 std::strerror(errno)));
  }
  std::fclose(stream);
  if (!existed) fs::remove(file, error);
}

bool LooksLikeMeshFile(const fs::path& file) {
  std::string name = file.filename().string();
  std::transform(name.begin(), name.end(), name.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (name.size() > 3 && name.ends_with(".xz")) name.resize(name.size() - 3);
  for (const char* extension : {".obj", ".ply", ".off", ".stl", ".node", ".ele", ".mesh"}) {
    if (name.ends_with(extension)) return true;
  }
  return false;
}

namespace {

// The top-level table of `file`, or nothing when it cannot be read or parsed (the loader that
// runs next reports that with line and column).
std::optional<toml::table> TopLevel(const fs::path& file) {
  try {
    return toml::parse_file(file.string());
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

}  // namespace

void RefuseConfigAsScenario(const fs::path& file) {
  const std::optional<toml::table> root = TopLevel(file);
  if (!root || root->contains("mesh") || root->contains("handle")) return;
  if (!root->contains("scenarios") && !root->contains("variant")) return;
  throw InputError(fmt::format(
      "{} is an experiment config ([scenarios], [[variant]]), but a scenario is expected here; "
      "run the config with harap run {}, or give one of the scenarios it lists",
      file.string(), file.string()));
}

void RefuseScenarioAsConfig(const fs::path& file) {
  const std::optional<toml::table> root = TopLevel(file);
  if (!root || root->contains("scenarios")) return;
  if (!root->contains("mesh") && !root->contains("handle")) return;
  throw InputError(fmt::format(
      "{} is a scenario (mesh and [[handle]]), but harap run takes an experiment config that "
      "lists scenarios and variants (docs/experiments.md), for example\n"
      "    [scenarios]\n"
      "    files = [\"{}\"]\n"
      "    [[variant]]\n"
      "    name = \"classic\"\n"
      "    optimizer.type = \"classic\"\n"
      "To deform this one scenario: harap deform {}",
      file.string(), file.filename().string(), file.string()));
}

void RefuseMeshAsScenario(const fs::path& file) {
  RefuseConfigAsScenario(file);
  if (!LooksLikeMeshFile(file)) return;
  fs::path scenario = file;
  if (scenario.extension() == ".xz") scenario.replace_extension();
  scenario.replace_extension(".toml");
  throw InputError(fmt::format(
      "{} is a mesh file, but a scenario (TOML) is expected here: it names the mesh and the "
      "handles that move it. Write {} beside the mesh, for example\n"
      "    mesh = \"{}\"\n"
      "    [[handle]]                      # held in place\n"
      "    select.slab = {{ axis = \"x\", from = 0.0, to = 0.1 }}\n"
      "    [[handle]]                      # moved\n"
      "    select.slab = {{ axis = \"x\", from = 0.9, to = 1.0 }}\n"
      "    translate = [0.0, 0.3, 0.0]\n"
      "(slab bounds are fractions of the bounding box; see docs/input.md), then run harap "
      "deform {}",
      file.string(), scenario.string(), file.filename().string(), scenario.string()));
}

void RefuseMeshAsToml(const fs::path& file, std::string_view option, std::string_view expected) {
  if (!LooksLikeMeshFile(file)) return;
  throw InputError(fmt::format(
      "{} {}: this is a mesh file, but {} takes {}. A mesh goes into a scenario "
      "(mesh = \"{}\" with its [[handle]] tables, docs/input.md), which harap deform runs",
      option, file.string(), option, expected, file.filename().string()));
}

std::string ScenarioLoadingPhase(const fs::path& file) {
  const std::string plain = "reading the scenario and its mesh";
  toml::table root;
  try {
    root = toml::parse_file(file.string());
  } catch (const std::exception&) {
    return plain;
  }
  std::string mesh = "reading its mesh";
  if (const toml::table* table = root["mesh"].as_table()) {
    if (table->contains("tetrahedralize")) {
      mesh = "tetrahedralizing its mesh (TetGen)";
    } else if (table->contains("builtin")) {
      mesh = "building its built-in mesh";
    }
  }
  const int refine = root["refine"].value_or(0);
  if (refine > 0) mesh += fmt::format(" with refine = {}", refine);
  return "reading the scenario, " + mesh;
}

}  // namespace harap
