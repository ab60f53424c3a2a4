// SPDX-License-Identifier: MIT
// The bad-input corpus: every file in tests/data/bad/ (written by make_bad_inputs.py) must fail
// with the error type and message EXPECTED.tsv gives for it, and the message must name the file.
// Meshes go through ReadMesh, scenarios (.toml) through LoadScenario.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>

#include "framework/error.h"
#include "io/mesh_io.h"
#include "io/scenario.h"
#include "tests/support/shared_data.h"

namespace harap {
namespace {

namespace fs = std::filesystem;

struct Expectation {
  std::string error_type;            // InputError or ConfigError
  std::vector<std::string> phrases;  // each must occur in the message
};

// EXPECTED.tsv: file <TAB> error type <TAB> phrase [<TAB> phrase ...]; '#' starts a comment.
std::map<std::string, Expectation> ReadExpectations(const fs::path& file) {
  std::ifstream stream(file);
  REQUIRE(stream);
  std::map<std::string, Expectation> table;
  for (std::string line; std::getline(stream, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::string name;
    Expectation expectation;
    std::getline(fields, name, '\t');
    std::getline(fields, expectation.error_type, '\t');
    for (std::string phrase; std::getline(fields, phrase, '\t');) {
      if (!phrase.empty()) expectation.phrases.push_back(phrase);
    }
    INFO("EXPECTED.tsv line: " << line);
    REQUIRE(!expectation.phrases.empty());
    REQUIRE(table.emplace(name, expectation).second);
  }
  return table;
}

void Load(const fs::path& file) {
  if (file.extension() == ".toml") {
    LoadScenario(file);
  } else {
    ReadMesh(file);
  }
}

TEST_CASE("bad-input corpus: every file fails with its expected error", "[io][bad_input]") {
  const fs::path folder = testing::SourceDir() / "tests" / "data" / "bad";
  const auto expectations = ReadExpectations(folder / "EXPECTED.tsv");
  std::set<std::string> files;
  for (const auto& entry : fs::directory_iterator(folder)) {
    const std::string name = entry.path().filename().string();
    if (name != "EXPECTED.tsv" && name != "make_bad_inputs.py") files.insert(name);
  }
  CHECK(files.size() >= 30);
  for (const std::string& name : files) {
    DYNAMIC_SECTION(name) {
      const auto expected = expectations.find(name);
      INFO("add a line for " << name << " to tests/data/bad/EXPECTED.tsv");
      REQUIRE(expected != expectations.end());
      std::string type = "no error";
      std::string message;
      try {
        Load(folder / name);
      } catch (const ConfigError& error) {
        type = "ConfigError";
        message = error.what();
      } catch (const InputError& error) {
        type = "InputError";
        message = error.what();
      }
      INFO("message: " << message);
      CHECK(type == expected->second.error_type);
      CHECK_THAT(message, Catch::Contains(name));
      for (const std::string& phrase : expected->second.phrases) {
        CHECK_THAT(message, Catch::Contains(phrase));
      }
    }
  }
  for (const auto& [name, expectation] : expectations) {
    INFO("EXPECTED.tsv names a file that does not exist");
    CHECK(files.count(name) == 1);
  }
}

}  // namespace
}  // namespace harap
