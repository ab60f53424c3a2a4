// SPDX-License-Identifier: MIT
//
// Experiment configs (docs/experiments.md): scenarios × variants × grid, expanded into runs.
// Decisions:
//   - Plan order is scenario-major, then variants, then the grid as a cartesian product with the
//     first [grid] key varying slowest. Sharding deals this order round-robin, so every shard
//     gets a similar mix of meshes.
//   - Run ids hash the scenario as written (path relative to `relative_to`, or mesh + template)
//     and the resolved run config, not the plan position: adding a grid value or a scenario keeps
//     the ids (and so the finished results) of every other run.
//   - Every run config is validated against the registries here, so a typo in a name or key
//     fails before the first run, not after hours of sweeping.
#include "runner/experiment.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <fnmatch.h>
#include <glob.h>
#include <toml++/toml.h>

#include <algorithm>
#include <charconv>
#include <cstdlib>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "api/builtins.h"
#include "api/component_factory.h"
#include "api/known_answer.h"
#include "api/presets.h"
#include "api/register.h"
#include "framework/config.h"
#include "framework/error.h"
#include "framework/toml_reading.h"
#include "io/scenario.h"

namespace harap {

namespace {

namespace fs = std::filesystem;

constexpr const char* kDeformTables[] = {"optimizer", "energy", "solver", "hierarchy", "upsampler"};

class ExperimentParser {
 public:
  ExperimentParser(std::string source, fs::path base)
      : source_(source), toml_(std::move(source)), base_(std::move(base)) {}

  // The toolkit's errors, positioned in this config.
  template <class Where>
  [[noreturn]] void Fail(const Where& where, std::string_view problem) const {
    toml_.Fail(where, problem);
  }
  [[noreturn]] void Fail(std::string_view problem) const { toml_.Fail(source_, problem); }

  fs::path Resolve(const std::string& path) const {
    fs::path p(path);
    return (p.is_relative() ? paths_base_ / p : p).lexically_normal();
  }
  // How a path is written relative to `relative_to` (stable across machines, for run ids).
  std::string Written(const fs::path& absolute) const {
    return absolute.lexically_relative(paths_base_).generic_string();
  }

  void AddScenario(ExperimentScenario scenario, std::string identity) {
    std::string name = scenario.name;
    for (int k = 2; used_names_.count(name); ++k) name = fmt::format("{}-{}", scenario.name, k);
    used_names_.insert(name);
    scenario.name = name;
    experiment_.scenarios.push_back(std::move(scenario));
    identities_.push_back(std::move(identity));
  }

  void ParseScenarioFiles(const toml::table& scenarios) {
    const toml::node* files_node = scenarios.get("files");
    for (const std::string& pattern : toml_.Strings(scenarios, "files")) {
      const fs::path resolved = Resolve(pattern);
      std::vector<fs::path> matches;
      if (pattern.find_first_of("*?[") == std::string::npos) {
        if (!fs::exists(resolved)) {
          Fail(*files_node, fmt::format("scenario file {} not found", resolved.string()));
        }
        matches.push_back(resolved);
      } else {
        glob_t result{};
        const int status = glob(resolved.c_str(), 0, nullptr, &result);
        for (size_t i = 0; status == 0 && i < result.gl_pathc; ++i) {
          matches.emplace_back(result.gl_pathv[i]);
        }
        globfree(&result);
        if (matches.empty()) {
          Fail(*files_node, fmt::format("the pattern {} matches no file", resolved.string()));
        }
      }
      for (const fs::path& file : matches) {
        // The scenario's text now (a typo should not fail every run of it after the sweep
        // started); its mesh and other files are read by the runs.
        CheckScenarioText(file);
        ExperimentScenario scenario;
        scenario.name = file.stem().string();
        scenario.file = fs::absolute(file).lexically_normal();
        AddScenario(std::move(scenario), "file:" + Written(file));
      }
    }
  }

  HandleTemplate ParseTemplate(const toml::node* node) const {
    HandleTemplate handles;
    if (!node) return handles;
    const toml::table* table = node->as_table();
    if (!table) Fail(*node, "'template' must be a table");
    toml_.CheckKeys(*table, {"axis", "fixed", "moved", "degrees", "bend_axis", "translate"},
                    "a handle template");
    auto axis = [&](std::string_view key, std::string fallback, const char* extra) {
      const std::string value = toml_.String(*table, key, fallback);
      if (value != "x" && value != "y" && value != "z" && value != extra) {
        Fail(*table->get(key),
             fmt::format("'{}' must be \"x\", \"y\", \"z\" or \"{}\"", key, extra));
      }
      return value;
    };
    handles.axis = axis("axis", handles.axis, "longest");
    handles.bend_axis = axis("bend_axis", handles.bend_axis, "auto");
    auto fraction = [&](std::string_view key, double fallback) {
      const toml::node* value = table->get(key);
      if (!value) return fallback;
      const double f = toml_.Number(*value, key);
      if (f <= 0.0 || f >= 1.0) Fail(*value, fmt::format("'{}' must lie in (0, 1)", key));
      return f;
    };
    handles.fixed = fraction("fixed", handles.fixed);
    handles.moved = fraction("moved", handles.moved);
    if (handles.fixed + handles.moved >= 1.0) {
      Fail(*node, "fixed + moved must be below 1 (the handles would overlap)");
    }
    if (const toml::node* degrees = table->get("degrees"))
      handles.degrees = toml_.Number(*degrees, "degrees");
    if (const toml::node* translate = table->get("translate")) {
      const std::array<double, 3> shift = toml_.Vector3(*translate, "'translate'");
      std::copy(shift.begin(), shift.end(), handles.translate);
    }
    return handles;
  }

  void ParseFolders(const toml::table& scenarios) {
    const toml::node* folders = scenarios.get("folder");
    if (!folders) return;
    const toml::array* array = folders->as_array();
    if (!array) Fail(*folders, "'folder' must be an array of tables ([[scenarios.folder]])");
    for (const toml::node& entry : *array) {
      const toml::table* folder = entry.as_table();
      if (!folder) Fail(entry, "[[scenarios.folder]] must be a table");
      toml_.CheckKeys(*folder, {"path", "include", "exclude", "template"}, "[[scenarios.folder]]");
      const std::string path = toml_.String(*folder, "path", "");
      if (path.empty()) Fail(entry, "[[scenarios.folder]] needs 'path'");
      const fs::path directory = Resolve(path);
      if (!fs::is_directory(directory)) {
        Fail(*folder->get("path"), fmt::format("{} is not a folder", directory.string()));
      }
      std::vector<std::string> include = toml_.Strings(*folder, "include");
      if (include.empty()) {
        for (const char* ext : {"obj", "ply", "off", "stl"}) {
          include.push_back(fmt::format("*.{}", ext));
          include.push_back(fmt::format("*.{}.xz", ext));
        }
      }
      const std::vector<std::string> exclude = toml_.Strings(*folder, "exclude");
      const HandleTemplate handles = ParseTemplate(folder->get("template"));
      std::vector<fs::path> meshes;
      for (const auto& item : fs::directory_iterator(directory)) {
        if (!item.is_regular_file()) continue;
        const std::string name = item.path().filename().string();
        auto matches = [&](const std::vector<std::string>& patterns) {
          return std::any_of(patterns.begin(), patterns.end(), [&](const std::string& p) {
            return fnmatch(p.c_str(), name.c_str(), 0) == 0;
          });
        };
        if (matches(include) && !matches(exclude)) meshes.push_back(item.path());
      }
      std::sort(meshes.begin(), meshes.end());
      if (meshes.empty()) {
        Fail(entry, fmt::format("no mesh in {} matches include = [{}]", directory.string(),
                                fmt::join(include, ", ")));
      }
      for (const fs::path& mesh : meshes) {
        ExperimentScenario scenario;
        std::string stem = mesh.filename().string();
        if (stem.ends_with(".xz")) stem.resize(stem.size() - 3);
        scenario.name = fs::path(stem).stem().string();
        scenario.mesh = fs::absolute(mesh).lexically_normal();
        scenario.handles = handles;
        const HandleTemplate& h = handles;
        AddScenario(
            std::move(scenario),
            fmt::format("mesh:{}:{} {} {} {} {} {} {} {}", Written(mesh), h.axis, h.fixed, h.moved,
                        h.degrees, h.bend_axis, h.translate[0], h.translate[1], h.translate[2]));
      }
    }
  }

  // The mesh files `meshes` names: each entry a glob pattern, a list file (.txt: one mesh per
  // line, relative to the list's folder, # comments) or a mesh file.
  std::vector<fs::path> MeshesNamed(const toml::table& scenarios) const {
    const toml::node* node = scenarios.get("meshes");
    std::vector<std::string> entries;
    if (node && node->is_string()) {
      entries.push_back(toml_.String(scenarios, "meshes", ""));
    } else {
      entries = toml_.Strings(scenarios, "meshes");
    }
    std::vector<fs::path> meshes;
    for (const std::string& entry : entries) {
      const fs::path resolved = Resolve(entry);
      if (entry.find_first_of("*?[") != std::string::npos) {
        glob_t result{};
        const int status = glob(resolved.c_str(), 0, nullptr, &result);
        const size_t before = meshes.size();
        for (size_t i = 0; status == 0 && i < result.gl_pathc; ++i) {
          meshes.emplace_back(result.gl_pathv[i]);
        }
        globfree(&result);
        if (meshes.size() == before) {
          Fail(*node, fmt::format("the pattern {} matches no file", resolved.string()));
        }
      } else if (resolved.extension() == ".txt") {
        std::ifstream list(resolved);
        if (!list) Fail(*node, fmt::format("mesh list {} cannot be read", resolved.string()));
        std::string line;
        while (std::getline(list, line)) {
          line = line.substr(0, line.find('#'));
          line.erase(0, line.find_first_not_of(" \t\r"));
          line.erase(line.find_last_not_of(" \t\r") + 1);
          if (line.empty()) continue;
          const fs::path mesh(line);
          meshes.push_back(
              (mesh.is_relative() ? resolved.parent_path() / mesh : mesh).lexically_normal());
        }
      } else {
        // A missing or unreadable mesh becomes a failed run with its reason, as in a glob.
        meshes.push_back(resolved);
      }
    }
    return meshes;
  }

  // `[scenarios] meshes = ...` × `kinds` × `refine`: one generated scenario each, named
  // MESH-KIND (+ "-rN" when refined).
  void ParseGeneratedScenarios(const toml::table& scenarios) {
    if (!scenarios.contains("meshes")) {
      for (const char* key : {"kinds", "refine", "handle_fraction"}) {
        if (const toml::node* node = scenarios.get(key)) {
          Fail(*node, fmt::format("'{}' applies to generated scenarios: give 'meshes'", key));
        }
      }
      return;
    }
    std::vector<std::string> kinds = toml_.Strings(scenarios, "kinds");
    if (kinds.empty()) kinds = ScenarioKindNames();
    for (const std::string& kind : kinds) {
      try {
        ParseScenarioKind(kind);
      } catch (const ConfigError& error) {
        Fail(*scenarios.get("kinds"), error.what());
      }
    }
    std::vector<int> refinements = {0};
    if (const toml::node* node = scenarios.get("refine")) {
      const toml::array* array = node->as_array();
      if (!array) Fail(*node, "'refine' must be an array of integers, e.g. [0, 1]");
      refinements.clear();
      for (const toml::node& value : *array) {
        const auto* integer = value.as_integer();
        if (!integer || integer->get() < 0 || integer->get() > 3) {
          Fail(value, "'refine' values must be integers from 0 to 3");
        }
        refinements.push_back(static_cast<int>(integer->get()));
      }
    }
    double fraction = 0.05;
    if (const toml::node* node = scenarios.get("handle_fraction")) {
      fraction = toml_.Number(*node, "handle_fraction");
      if (!(fraction > 0.0 && fraction < 0.5)) {
        Fail(*node, "'handle_fraction' must lie in (0, 0.5)");
      }
    }
    for (const fs::path& mesh : MeshesNamed(scenarios)) {
      std::string stem = mesh.filename().string();
      if (stem.ends_with(".xz")) stem.resize(stem.size() - 3);
      stem = fs::path(stem).stem().string();
      for (const std::string& kind : kinds) {
        for (const int refine : refinements) {
          ExperimentScenario scenario;
          scenario.name = refine == 0 ? fmt::format("{}-{}", stem, kind)
                                      : fmt::format("{}-{}-r{}", stem, kind, refine);
          scenario.mesh = fs::absolute(mesh).lexically_normal();
          scenario.generated = true;
          scenario.generator.kind = ParseScenarioKind(kind);
          scenario.generator.refine = refine;
          scenario.generator.handle_fraction = fraction;
          AddScenario(std::move(scenario),
                      fmt::format("generated:{}:{}:{}:{}", Written(mesh), kind, refine, fraction));
        }
      }
    }
  }

  // The run tables a run config may set: `harap deform`'s, and `[registration]` for
  // registration experiments.
  std::vector<std::string> RunTables() const {
    std::vector<std::string> tables(std::begin(kDeformTables), std::end(kDeformTables));
    if (experiment_.known_answers.enabled) tables.emplace_back("registration");
    return tables;
  }

  // [known_answers]: the experiment registers rest meshes to targets made from its scenarios'
  // solutions (api/known_answer.h).
  void ParseKnownAnswers(const toml::table& root) {
    const toml::node* node = root.get("known_answers");
    if (!node) {
      if (const toml::node* registration = root.get("registration")) {
        Fail(*registration,
             "[registration] applies to registration experiments: add a [known_answers] table");
      }
      return;
    }
    const toml::table* table = node->as_table();
    if (!table) Fail(*node, "[known_answers] must be a table");
    toml_.CheckKeys(*table, {"targets", "points_per_vertex", "removed", "outliers", "seed"},
                    "[known_answers]");
    KnownAnswerSettings& settings = experiment_.known_answers;
    settings.enabled = true;
    if (table->contains("targets")) {
      settings.targets = toml_.Strings(*table, "targets");
      if (settings.targets.empty()) Fail(*table->get("targets"), "'targets' names no target");
      for (const std::string& target : settings.targets) {
        try {
          ParseKnownAnswerTarget(target);
        } catch (const ConfigError& error) {
          Fail(*table->get("targets"), error.what());
        }
      }
    }
    KnownAnswerOptions& options = settings.options;
    auto number = [&](std::string_view key, double& value) {
      if (const toml::node* entry = table->get(key)) value = toml_.Number(*entry, key);
    };
    number("points_per_vertex", options.points_per_vertex);
    number("removed", options.damage.removed);
    number("outliers", options.damage.outliers);
    if (const toml::node* seed = table->get("seed")) {
      if (!seed->is_integer() || seed->as_integer()->get() < 0) {
        Fail(*seed, "'seed' must be an integer >= 0");
      }
      options.seed = static_cast<std::uint64_t>(seed->as_integer()->get());
    }
    try {
      options.Validate();
    } catch (const ConfigError& error) {
      Fail(*node, fmt::format("[known_answers]: {}", error.what()));
    }
  }

  // One registration case per scenario and target, named SCENARIO-TARGET.
  void ExpandKnownAnswers() {
    std::vector<ExperimentScenario> scenarios = std::move(experiment_.scenarios);
    std::vector<std::string> identities = std::move(identities_);
    experiment_.scenarios.clear();
    identities_.clear();
    used_names_.clear();
    const KnownAnswerSettings& settings = experiment_.known_answers;
    for (size_t s = 0; s < scenarios.size(); ++s) {
      for (const std::string& target : settings.targets) {
        ExperimentScenario known = scenarios[s];
        known.name = fmt::format("{}-{}", scenarios[s].name, target);
        known.known_answer_target = target;
        AddScenario(std::move(known),
                    fmt::format("{}:known-answer:{}:{}:{}:{}:{}", identities[s], target,
                                settings.options.points_per_vertex, settings.options.damage.removed,
                                settings.options.damage.outliers, settings.options.seed));
      }
    }
  }

  // Leaves of `table` as (dotted key, node), in the order written in the file (toml++ iterates
  // tables in key order).
  static void Flatten(const toml::table& table, const std::string& prefix,
                      std::vector<std::pair<std::string, const toml::node*>>& out) {
    for (const auto& [key, value] : table) {
      const std::string dotted =
          prefix.empty() ? std::string(key.str()) : fmt::format("{}.{}", prefix, key.str());
      if (const toml::table* sub = value.as_table()) {
        Flatten(*sub, dotted, out);
      } else {
        out.emplace_back(dotted, &value);
      }
    }
    if (!prefix.empty()) return;
    std::stable_sort(out.begin(), out.end(), [](const auto& a, const auto& b) {
      const auto& x = a.second->source().begin;
      const auto& y = b.second->source().begin;
      return std::pair(x.line, x.column) < std::pair(y.line, y.column);
    });
  }

  static std::string Literal(const toml::node& node) {
    // Floating-point numbers in their shortest form (1e-06, not 9.9999999999999995e-07), kept
    // floating-point for TOML (2.0, not 2).
    if (const auto* floating = node.as_floating_point()) {
      std::string text = fmt::format("{}", floating->get());
      if (text.find_first_of(".eEn") == std::string::npos) text += ".0";
      return text;
    }
    std::ostringstream text;
    node.visit([&](const auto& value) { text << value; });
    return text.str();
  }

  static std::string Display(const toml::node& node) {
    if (const auto* text = node.as_string()) return text->get();
    return Literal(node);
  }

  // Checks that a dotted run-config key names one of the five run tables, or is `preset` (a
  // named option set below the run's other options, api/presets.h; not for registrations).
  // `where` is the value: a variant's, or a [grid] array of them.
  void CheckRunKey(const std::string& key, const toml::node& where) const {
    if (key == "preset" && !experiment_.known_answers.enabled) {
      const toml::array* values = where.as_array();
      const bool strings =
          values ? std::all_of(values->begin(), values->end(),
                               [](const toml::node& value) { return value.is_string(); })
                 : where.is_string();
      if (!strings) Fail(where, "'preset' must be a string naming a preset");
      return;
    }
    const std::string table = key.substr(0, key.find('.'));
    const std::vector<std::string> tables = RunTables();
    if (key.find('.') == std::string::npos ||
        std::find(tables.begin(), tables.end(), table) == tables.end()) {
      Fail(where, fmt::format("'{}' is not a run option; use TABLE.KEY with TABLE one of {}{}", key,
                              fmt::join(tables, ", "),
                              experiment_.known_answers.enabled ? "" : ", or preset"));
    }
  }

  Experiment Parse(std::string_view text) {
    const toml::table root = toml_.Parse(text);
    toml_.CheckKeys(
        root,
        {"experiment", "scenarios", "run", "grid", "variant", "report", "slurm", "optimizer",
         "energy", "solver", "hierarchy", "upsampler", "known_answers", "registration"},
        "the top level");
    ParseKnownAnswers(root);
    experiment_.source_text = std::string(text);
    ParseDescription(root);

    // [scenarios]
    const toml::table* scenarios = root["scenarios"].as_table();
    if (!scenarios) {
      Fail("no [scenarios] table (files = [...], meshes = \"...\" or [[scenarios.folder]])");
    }
    toml_.CheckKeys(
        *scenarios,
        {"relative_to", "files", "folder", "meshes", "kinds", "refine", "handle_fraction"},
        "[scenarios]");
    paths_base_ = (base_ / toml_.String(*scenarios, "relative_to", ".")).lexically_normal();
    ParseScenarioFiles(*scenarios);
    ParseFolders(*scenarios);
    ParseGeneratedScenarios(*scenarios);
    if (experiment_.scenarios.empty()) Fail("[scenarios] names no scenario");
    if (experiment_.known_answers.enabled) ExpandKnownAnswers();

    if (const toml::table* run = root["run"].as_table()) ParseRunSettings(*run);
    if (const toml::table* slurm = root["slurm"].as_table()) ParseSlurmSettings(*slurm);
    const std::string base_text = BaseTablesText(root);
    const std::vector<Variant> variants = ParseVariants(root);
    const std::vector<GridAxis> axes = ParseGrid(root);
    ExpandRuns(base_text, variants, axes);
    if (const toml::node* report = root.get("report")) {
      ValidateReport(*report->as_table(), !root.contains("variant"));
    }
    WarnAboutDifferentEnergies();
    return std::move(experiment_);
  }

 private:
  // A [[variant]]: its name and its run-config settings (dotted key, TOML literal).
  struct Variant {
    std::string name;
    std::vector<std::pair<std::string, std::string>> settings;
  };
  // A [grid] axis: dotted key and its values.
  using GridAxis = std::pair<std::string, std::vector<const toml::node*>>;

  // [experiment] and [report], which go to the report script as they are.
  void ParseDescription(const toml::table& root) {
    nlohmann::json report_json = nlohmann::json::object();
    if (const toml::table* meta = root["experiment"].as_table()) {
      toml_.CheckKeys(*meta, {"name", "title", "description"}, "[experiment]");
      experiment_.name = toml_.String(*meta, "name", "");
      experiment_.title = toml_.String(*meta, "title", "");
      report_json["description"] = toml_.String(*meta, "description", "");
    }
    if (experiment_.name.empty()) experiment_.name = fs::path(source_).stem().string();
    if (experiment_.title.empty()) experiment_.title = experiment_.name;
    report_json["name"] = experiment_.name;
    report_json["title"] = experiment_.title;
    if (const toml::node* report = root.get("report")) {
      if (!report->is_table()) Fail(*report, "[report] must be a table");
      std::ostringstream json;
      json << toml::json_formatter(*report->as_table());
      report_json["report"] = nlohmann::json::parse(json.str());
    } else {
      report_json["report"] = nlohmann::json::object();
    }
    experiment_.report_json = report_json.dump();
  }

  // [run]
  void ParseSlurmSettings(const toml::table& slurm) {
    toml_.CheckKeys(
        slurm, {"tasks", "partition", "time", "cpus_per_task", "mem", "throttle", "sbatch_flags"},
        "[slurm]");
    ExperimentSlurmSettings& settings = experiment_.slurm;
    auto count = [&](std::string_view key, int minimum, int fallback) {
      const toml::node* node = slurm.get(key);
      if (!node) return fallback;
      if (!node->is_integer() || node->as_integer()->get() < minimum ||
          node->as_integer()->get() > 1000000) {
        Fail(*node, fmt::format("'{}' must be an integer >= {}", key, minimum));
      }
      return static_cast<int>(node->as_integer()->get());
    };
    settings.tasks = count("tasks", 0, settings.tasks);
    settings.cpus_per_task = count("cpus_per_task", 1, settings.cpus_per_task);
    settings.throttle = count("throttle", 0, settings.throttle);
    settings.partition = toml_.String(slurm, "partition", "");
    settings.time = toml_.String(slurm, "time", "");
    settings.mem = toml_.String(slurm, "mem", "");
    settings.sbatch_flags = toml_.Strings(slurm, "sbatch_flags");
  }

  void ParseRunSettings(const toml::table& run) {
    toml_.CheckKeys(run, {"threads", "save_mesh", "timeout", "min_time"}, "[run]");
    if (const toml::node* threads = run.get("threads")) {
      if (!threads->is_integer() || threads->as_integer()->get() < 0) {
        Fail(*threads, "'threads' must be an integer >= 0 (0: cores / --jobs)");
      }
      experiment_.settings.threads = static_cast<int>(threads->as_integer()->get());
    }
    if (const toml::node* save = run.get("save_mesh")) {
      if (!save->is_boolean()) Fail(*save, "'save_mesh' must be true or false");
      experiment_.settings.save_mesh = save->as_boolean()->get();
    }
    if (const toml::node* timeout = run.get("timeout")) {
      experiment_.settings.timeout = toml_.Number(*timeout, "timeout");
      if (experiment_.settings.timeout < 0) Fail(*timeout, "'timeout' must be >= 0 seconds");
    }
    if (const toml::node* min_time = run.get("min_time")) {
      experiment_.settings.min_time = toml_.Number(*min_time, "min_time");
      if (!(experiment_.settings.min_time >= 0 && experiment_.settings.min_time <= 3600)) {
        Fail(*min_time, "'min_time' must be 0 to 3600 seconds");
      }
    }
  }

  // The base run tables ([optimizer], [energy], ...) as TOML text, which every run starts from.
  std::string BaseTablesText(const toml::table& root) const {
    toml::table base_tables;
    for (const std::string& table : RunTables()) {
      if (const toml::node* node = root.get(table)) {
        if (!node->is_table()) Fail(*node, fmt::format("'{}' must be a table", table));
        base_tables.insert(table, *node->as_table());
      }
    }
    std::ostringstream base_text;
    base_text << base_tables;
    return base_text.str();
  }

  // [[variant]]; one unnamed variant without settings when there is none.
  std::vector<Variant> ParseVariants(const toml::table& root) const {
    std::vector<Variant> variants;
    if (const toml::node* node = root.get("variant")) {
      const toml::array* array = node->as_array();
      if (!array) Fail(*node, "'variant' must be an array of tables ([[variant]])");
      std::set<std::string> names;
      for (const toml::node& entry : *array) {
        const toml::table* table = entry.as_table();
        if (!table) Fail(entry, "[[variant]] must be a table");
        Variant variant;
        variant.name = toml_.String(*table, "name", "");
        if (variant.name.empty()) Fail(entry, "[[variant]] needs a 'name'");
        if (!names.insert(variant.name).second) {
          Fail(entry, fmt::format("two variants are named '{}'", variant.name));
        }
        std::vector<std::pair<std::string, const toml::node*>> leaves;
        Flatten(*table, "", leaves);
        for (const auto& [key, value] : leaves) {
          if (key == "name") continue;
          CheckRunKey(key, *value);
          variant.settings.emplace_back(key, Literal(*value));
        }
        variants.push_back(std::move(variant));
      }
    }
    if (variants.empty()) variants.push_back({});
    return variants;
  }

  // [grid]: dotted key -> array of values.
  std::vector<GridAxis> ParseGrid(const toml::table& root) {
    std::vector<GridAxis> axes;
    if (const toml::node* node = root.get("grid")) {
      const toml::table* grid = node->as_table();
      if (!grid) Fail(*node, "[grid] must be a table of KEY = [values]");
      std::vector<std::pair<std::string, const toml::node*>> leaves;
      Flatten(*grid, "", leaves);
      for (const auto& [key, value] : leaves) {
        CheckRunKey(key, *value);
        const toml::array* values = value->as_array();
        if (!values || values->empty()) {
          Fail(*value, fmt::format("[grid] '{}' must be a non-empty array of values", key));
        }
        std::vector<const toml::node*> list;
        for (const toml::node& v : *values) list.push_back(&v);
        axes.emplace_back(key, std::move(list));
        experiment_.grid_keys.push_back(key);
      }
    }
    return axes;
  }

  // The runs: scenarios × variants × grid (first grid key slowest), each validated once per
  // distinct run config and identified by its scenario and config.
  void ExpandRuns(const std::string& base_text, const std::vector<Variant>& variants,
                  const std::vector<GridAxis>& axes) {
    const Registries registries = MakeBuiltinRegistries();
    std::map<std::string, std::string> resolved;  // run config -> Validate()'s resolved text
    size_t combinations = 1;
    for (const auto& axis : axes) combinations *= axis.second.size();
    std::set<std::string> ids;
    for (size_t s = 0; s < experiment_.scenarios.size(); ++s) {
      for (const Variant& variant : variants) {
        for (size_t c = 0; c < combinations; ++c) {
          ExperimentRun run = MakeRun(s, variant, axes, c, base_text);
          auto [known, fresh] = resolved.try_emplace(run.config_toml);
          if (fresh) known->second = Validate(registries, run);
          // The id follows what the run does: a preset's settings, not only its name, so that
          // a run folder made before a preset changed runs it again.
          const uint64_t hash = Fnv1a(identities_[s] + "\n" + known->second);
          run.id = fmt::format("{}-{:08x}", experiment_.scenarios[s].name,
                               static_cast<uint32_t>(hash ^ (hash >> 32)));
          if (!ids.insert(run.id).second) {
            Fail(
                fmt::format("two runs of scenario '{}' have the same settings ({}); remove the "
                            "duplicate variant or grid value",
                            experiment_.scenarios[s].name, run.label));
          }
          experiment_.runs.push_back(std::move(run));
        }
      }
    }
  }

  // Run `combination` of the grid for scenario `s` and `variant`: its parameters, label and
  // run config.
  ExperimentRun MakeRun(size_t s, const Variant& variant, const std::vector<GridAxis>& axes,
                        size_t combination, const std::string& base_text) const {
    ExperimentRun run;
    run.index = static_cast<int>(experiment_.runs.size());
    run.scenario = static_cast<int>(s);
    run.variant = variant.name;
    run.parameters = variant.settings;
    std::vector<std::string> label_parts;
    if (!variant.name.empty()) label_parts.push_back(variant.name);
    size_t rest = combination;
    std::vector<size_t> choice(axes.size());
    for (size_t a = axes.size(); a-- > 0;) {
      choice[a] = rest % axes[a].second.size();
      rest /= axes[a].second.size();
    }
    for (size_t a = 0; a < axes.size(); ++a) {
      const toml::node& value = *axes[a].second[choice[a]];
      run.parameters.emplace_back(axes[a].first, Literal(value));
      const std::string& key = axes[a].first;
      // "solver.type" reads best as "solver", other keys by their last part.
      const std::string short_key =
          key.ends_with(".type") ? key.substr(0, key.size() - 5) : key.substr(key.rfind('.') + 1);
      label_parts.push_back(fmt::format("{}={}", short_key, Display(value)));
    }
    run.label = fmt::format("{}", fmt::join(label_parts, ", "));
    ConfigNode config = ConfigNode::Parse(base_text, source_);
    for (const auto& [key, literal] : run.parameters) config.Set(key, literal);
    run.config_toml = config.ToToml();
    return run;
  }

  // [report] as the report script reads it (report.py), so that a typo fails now and not after
  // the runs: known keys and figure names (one list for both sides), compare/panel naming a
  // [grid] key (or "variant"), value types.
  void ValidateReport(const toml::table& report, bool no_variants) const {
    const ReportKeys known = LoadReportKeys();
    toml_.CheckKeys(report, known.keys, "[report]");
    for (const std::string& figure : toml_.Strings(report, "figures")) {
      if (std::find(known.figures.begin(), known.figures.end(), figure) == known.figures.end()) {
        Fail(*report.get("figures"),
             fmt::format("[report] figures: unknown figure '{}'; valid figures: {}", figure,
                         fmt::join(known.figures, ", ")));
      }
    }
    const auto& grid = experiment_.grid_keys;
    auto grid_key = [&](std::string_view key, bool variant_allowed) {
      const toml::node* node = report.get(key);
      if (!node) return;
      if (!node->is_string()) Fail(*node, fmt::format("[report] '{}' must be a string", key));
      const std::string value = node->as_string()->get();
      if (std::find(grid.begin(), grid.end(), value) != grid.end()) return;
      if (variant_allowed && value == "variant" && !no_variants) return;
      std::vector<std::string> valid;
      if (variant_allowed && !no_variants) valid.push_back("\"variant\"");
      for (const std::string& g : grid) valid.push_back(fmt::format("\"{}\"", g));
      Fail(*node, fmt::format("[report] {} = \"{}\" names no {}; valid: {}", key, value,
                              variant_allowed ? "[grid] key or variants" : "[grid] key",
                              valid.empty() ? std::string("none (the config has no [grid]"
                                                          " and no [[variant]])")
                                            : fmt::format("{}", fmt::join(valid, ", "))));
    };
    grid_key("compare", true);
    grid_key("panel", false);
    for (const char* text_key : {"claim", "notes", "baseline"}) {
      if (const toml::node* node = report.get(text_key); node && !node->is_string()) {
        Fail(*node, fmt::format("[report] '{}' must be a string", text_key));
      }
    }
    if (const toml::node* render = report.get("render")) {
      if (!render->is_boolean()) {
        const std::vector<std::string> names = toml_.Strings(report, "render");
        for (const std::string& name : names) {
          const bool known_scenario = std::any_of(
              experiment_.scenarios.begin(), experiment_.scenarios.end(),
              [&](const ExperimentScenario& scenario) { return scenario.name == name; });
          if (!known_scenario) {
            Fail(*render, fmt::format("[report] render names '{}', which is no scenario of this "
                                      "experiment",
                                      name));
          }
        }
      }
    }
    if (const toml::node* runs = report.get("render_runs")) {
      if (!runs->is_integer() || runs->as_integer()->get() < 1) {
        Fail(*runs, "[report] render_runs must be an integer >= 1");
      }
    }
  }

  // Runs whose [energy] tables differ measure different energies: their values must not be
  // compared (the report gives no energy ratio between them either).
  void WarnAboutDifferentEnergies() {
    std::vector<std::pair<std::string, std::string>> energies;  // (table, first label)
    for (const ExperimentRun& run : experiment_.runs) {
      std::string table = "(the default energy)";
      try {
        const toml::table config = toml::parse(run.config_toml);
        if (const toml::table* energy = config["energy"].as_table(); energy && !energy->empty()) {
          std::ostringstream text;
          text << toml::toml_formatter(*energy, toml::format_flags::none);
          table = text.str();
          std::replace(table.begin(), table.end(), '\n', ' ');
          while (!table.empty() && table.back() == ' ') table.pop_back();
        }
      } catch (const toml::parse_error&) {
        continue;  // cannot happen: the config was written by ConfigNode
      }
      const bool seen = std::any_of(energies.begin(), energies.end(),
                                    [&](const auto& entry) { return entry.first == table; });
      if (!seen) energies.emplace_back(table, run.label.empty() ? std::string("base") : run.label);
    }
    if (energies.size() < 2) return;
    std::vector<std::string> parts;
    for (const auto& [table, label] : energies) {
      parts.push_back(fmt::format("[energy] {} (e.g. '{}')", table, label));
    }
    experiment_.warnings.push_back(fmt::format(
        "the runs use {} different energies: {}. Energies of different functionals are not "
        "comparable: harap report compares their times, iterations and pictures but gives no "
        "energy ratio between them",
        energies.size(), fmt::join(parts, "; ")));
  }

  // Checks the run's config and returns it as `harap deform --config` resolves its `preset`
  // key (the config itself without one).
  std::string Validate(const Registries& registries, const ExperimentRun& run) const {
    // Line numbers in the messages would refer to the generated run config, not to the file.
    ConfigNode config = ConfigNode::Parse(run.config_toml, "resolved run config");
    try {
      const std::string resolved =
          ApplyPreset(config, "").empty() ? run.config_toml : config.ToToml();
      if (experiment_.known_answers.enabled) {
        CheckRegisterConfig(registries, config);
      } else {
        ValidateRunConfig(config);
        const RegistryComponentFactory factory(registries, config);
        MakeOptimizer(registries, config)->CheckComponents(factory);
      }
      return resolved;
    } catch (const Error& error) {
      throw ConfigError(fmt::format("{}: run '{}' is invalid: {}", source_,
                                    run.label.empty() ? "base config" : run.label, error.what()));
    }
  }

  static uint64_t Fnv1a(std::string_view text) {
    uint64_t hash = 14695981039346656037ull;
    for (const unsigned char c : text) {
      hash ^= c;
      hash *= 1099511628211ull;
    }
    return hash;
  }

  std::string source_;
  TomlReader toml_;
  fs::path base_;
  fs::path paths_base_;
  Experiment experiment_;
  std::set<std::string> used_names_;
  std::vector<std::string> identities_;
};

}  // namespace

Experiment ParseExperiment(std::string_view toml_text, const std::string& source_name,
                           const std::filesystem::path& base_directory) {
  return ExperimentParser(source_name, base_directory).Parse(toml_text);
}

Experiment LoadExperiment(const std::filesystem::path& file) {
  std::ifstream stream(file, std::ios::binary);
  if (!stream)
    throw InputError(fmt::format("{}: cannot open the experiment config", file.string()));
  std::stringstream buffer;
  buffer << stream.rdbuf();
  Experiment experiment =
      ParseExperiment(buffer.str(), file.string(), fs::absolute(file).parent_path());
  experiment.file = fs::absolute(file);
  return experiment;
}

std::string Shard::Suffix() const {
  return count == 1 ? std::string() : fmt::format("-shard-{}-of-{}", index, count);
}

Shard ParseShard(std::string_view text) {
  const size_t slash = text.find('/');
  Shard shard;
  auto parse = [&](std::string_view part, int& value) {
    const auto [end, error] = std::from_chars(part.data(), part.data() + part.size(), value);
    return error == std::errc() && end == part.data() + part.size();
  };
  if (slash == std::string_view::npos || !parse(text.substr(0, slash), shard.index) ||
      !parse(text.substr(slash + 1), shard.count) || shard.count < 1 || shard.index < 0 ||
      shard.index >= shard.count) {
    throw ConfigError(fmt::format("--shard '{}': expected I/N with 0 <= I < N, e.g. 0/4", text));
  }
  return shard;
}

ReportKeys LoadReportKeys() {
  // The report script's folder: next to HARAP_REPORT_SCRIPT if that names one, else the source
  // tree's experiments/scripts.
  fs::path file = fs::path(HARAP_SCRIPTS_DIR) / "report_keys.json";
  if (const char* script = std::getenv("HARAP_REPORT_SCRIPT")) {
    const fs::path beside = fs::path(script).parent_path() / "report_keys.json";
    if (fs::exists(beside)) file = beside;
  }
  std::ifstream stream(file);
  if (!stream) {
    throw InputError(
        fmt::format("{}: cannot read the report's figure names and keys (the file "
                    "report.py reads too)",
                    file.string()));
  }
  try {
    const nlohmann::json json = nlohmann::json::parse(stream);
    return {json.at("figures").get<std::vector<std::string>>(),
            json.at("report_keys").get<std::vector<std::string>>()};
  } catch (const nlohmann::json::exception& error) {
    throw InputError(fmt::format("{}: {}", file.string(), error.what()));
  }
}

std::string TemplateScenarioToml(const ExperimentScenario& scenario, const double extent[3]) {
  const HandleTemplate& t = scenario.handles;
  auto by_extent = [&](int a, int b) { return extent[a] < extent[b]; };
  auto longest_of = [&](std::vector<int> axes) {
    return *std::max_element(axes.begin(), axes.end(), by_extent);
  };
  const int axis = t.axis == "longest" ? longest_of({0, 1, 2}) : t.axis[0] - 'x';
  int bend = 0;
  if (t.bend_axis == "auto") {
    std::vector<int> others;
    for (int d = 0; d < 3; ++d) {
      if (d != axis) others.push_back(d);
    }
    // About the shorter of the other two axes: the moved end swings in the plane of the two
    // longest extents (an in-plane bend of a flat shape, visible from its thin side).
    bend = *std::min_element(others.begin(), others.end(), by_extent);
  } else {
    bend = t.bend_axis[0] - 'x';
  }
  const char* names = "xyz";
  std::string text = fmt::format(
      "# Generated by harap run from a handle template (docs/experiments.md).\n"
      "mesh = \"{}\"\n\n"
      "[[handle]]\nname = \"fixed\"\nselect.slab = {{ axis = \"{}\", from = 0.0, to = {} }}\n\n"
      "[[handle]]\nname = \"moved\"\nselect.slab = {{ axis = \"{}\", from = {}, to = 1.0 }}\n",
      scenario.mesh.generic_string(), names[axis], t.fixed, names[axis], 1.0 - t.moved);
  if (t.degrees != 0.0) {
    double rotation_axis[3] = {0.0, 0.0, 0.0};
    rotation_axis[bend] = 1.0;
    text += fmt::format("rotate = {{ axis = [{:.1f}, {:.1f}, {:.1f}], degrees = {} }}\n",
                        rotation_axis[0], rotation_axis[1], rotation_axis[2], t.degrees);
  }
  if (t.translate[0] != 0.0 || t.translate[1] != 0.0 || t.translate[2] != 0.0) {
    text +=
        fmt::format("translate = [{}, {}, {}]\n", t.translate[0], t.translate[1], t.translate[2]);
  }
  return text;
}

}  // namespace harap
