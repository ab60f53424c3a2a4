// SPDX-License-Identifier: MIT
#include "cli/cli_output.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <functional>
#include <map>
#include <utility>
#include <vector>

#include "api/builtins.h"
#include "api/component_factory.h"
#include "api/huge_pages.h"
#include "api/library.h"
#include "api/presets.h"
#include "framework/error.h"
#include "io/builtin_meshes.h"
#include "io/mesh_repair.h"

#ifndef HARAP_VERSION
#define HARAP_VERSION "unknown"
#endif
#ifndef HARAP_GIT_DESCRIBE
#define HARAP_GIT_DESCRIBE ""
#endif

namespace harap {

namespace {

const char* ElementWord(const Mesh& mesh) {
  return mesh.kind() == ElementKind::kTetrahedron ? "tetrahedra" : "faces";
}

std::string IterationsLine(const DeformOutcome& outcome) {
  const OptimizeResult& r = outcome.result;
  std::string state;
  if (outcome.interrupted) {
    state = "interrupted";
  } else if (!r.levels.empty() && r.levels.front().unknowns == 0) {
    state = "nothing to solve: every vertex is a handle";
  } else {
    state = r.converged ? "converged" : (r.stopped_by_callback ? "stopped" : "not converged");
  }
  if (r.levels.size() > 1) {
    return fmt::format("{} on the finest level / {} over all {} levels ({})", r.iterations,
                       r.total_iterations, r.levels.size(), state);
  }
  if (!outcome.hierarchy.empty()) {
    return fmt::format("{} on the hierarchy's only level ({})", r.iterations, state);
  }
  return fmt::format("{} ({})", r.iterations, state);
}

}  // namespace

std::string TimingsLine(const PhaseTimings& t) {
  // The hierarchical optimizer sets finer levels up while coarser ones solve (overlap_setup):
  // then the phases add up to more than the total, which would look like a bookkeeping error.
  const double phases = t.hierarchy + t.precompute + t.constrain + t.solve;
  return fmt::format(
      "hierarchy {:.3f} | precompute {:.3f} | constrain {:.3f} | solve {:.3f} | total {:.3f}{}",
      t.hierarchy, t.precompute, t.constrain, t.solve, t.total,
      phases > 1.05 * t.total + 0.01
          ? " (phases overlap: finer levels were set up while coarser ones solved)"
          : "");
}

void PrintDeformSummary(const Scenario& scenario, const DeformOutcome& outcome) {
  const OptimizeResult& r = outcome.result;
  fmt::print("scenario    {}\n", scenario.file.string());
  fmt::print("mesh        {} ({} vertices, {} {})\n", scenario.mesh_source,
             scenario.mesh.num_vertices(), scenario.mesh.num_elements(),
             ElementWord(scenario.mesh));
  std::string pieces = fmt::format("optimizer {} | energy {} | solver {}", outcome.optimizer,
                                   outcome.energy_type, outcome.solver);
  if (!outcome.hierarchy.empty()) pieces += fmt::format(" | hierarchy {}", outcome.hierarchy);
  if (!outcome.upsampler.empty()) pieces += fmt::format(" | upsampler {}", outcome.upsampler);
  fmt::print("pieces      {}\n", pieces);
  for (const ScenarioStiffness& region : scenario.stiffness) {
    if (region.attribute.empty()) {
      fmt::print("stiffness   {}: factor {} on {} vertices ({})\n", region.name, region.factor,
                 region.vertices.size(), region.selection);
    } else {
      fmt::print("stiffness   {}: {}\n", region.name, region.selection);
    }
  }
  fmt::print("iterations  {}\n", IterationsLine(outcome));
  fmt::print("energy      {:.9e}\n", r.energy);
  for (const auto& [name, value] : r.measures) fmt::print("{:<11} {:.9e}\n", name, value);
  fmt::print("time [s]    {}\n", TimingsLine(r.timings));
  fmt::print("memory      {:.1f} MiB peak (huge pages: {})\n",
             PeakMemoryBytes() / (1024.0 * 1024.0), HugePageBacking());
  for (const auto& note : scenario.notes) fmt::print("note        {}\n", note);
  for (size_t k = 0; k < r.levels.size(); ++k) {
    const LevelResult& level = r.levels[k];
    const SolveStatistics& solves = level.linear_solves;
    const bool direct = k < outcome.level_solver_direct.size() && outcome.level_solver_direct[k];
    // A direct solver has no iterations, and a residual only when asked to check it.
    const std::string iterations = direct ? fmt::format("{:>18}", "direct")
                                          : fmt::format("{:7} iterations", solves.iterations);
    const std::string residual =
        solves.residuals_computed > 0
            ? fmt::format("max residual {:.2e}", solves.max_relative_residual)
            : std::string("residual not computed");
    const EnergyWeights& weights = level.weights;
    const std::string weight_text =
        weights.scheme.empty()
            ? std::string()
            : fmt::format(" | weights {} ({} negative)", weights.scheme, weights.negative_edges);
    fmt::print("level {:<5} {:>8} unknowns | {:<12} {:4} solves {} {:7.3f} s | {}{}\n", level.level,
               level.unknowns, k < outcome.level_solvers.size() ? outcome.level_solvers[k] : "",
               solves.solves, iterations, solves.seconds, residual, weight_text);
    if (const auto it = outcome.spectra.find(level.level); it != outcome.spectra.end()) {
      const SystemSpectrum& spectrum = it->second;
      fmt::print(
          "            A: λ [{:.4e}, {:.4e}] κ {:.3e} | D^-1/2 A D^-1/2: λ [{:.4e}, "
          "{:.4e}] κ {:.3e} | {:.2f} s\n",
          spectrum.matrix.smallest, spectrum.matrix.largest, spectrum.matrix.condition_number(),
          spectrum.jacobi.smallest, spectrum.jacobi.largest, spectrum.jacobi.condition_number(),
          spectrum.seconds);
    }
  }
  if (outcome.mesh_summary.empty()) fmt::print("checks      no findings\n");
  for (const auto& line : outcome.mesh_summary) fmt::print("checks      {}\n", line);
  if (outcome.mesh_repaired) {
    fmt::print(
        "repaired    solved on {} vertices, {} {} (results written for all {} input "
        "vertices); the repaired mesh:\n",
        outcome.solved_vertices, outcome.solved_elements, ElementWord(scenario.mesh),
        scenario.mesh.num_vertices());
    if (outcome.repaired_mesh_summary.empty()) fmt::print("  checks    no findings\n");
    for (const auto& line : outcome.repaired_mesh_summary) fmt::print("  checks    {}\n", line);
  }
  for (const auto& note : r.notes) fmt::print("note        {}\n", note);
  for (const auto& warning : outcome.warnings) fmt::print("warning     {}\n", warning);
}

namespace {

template <class Interface>
void ListRegistry(const Registry<Interface>& registry) {
  fmt::print("{}:\n", registry.kind());
  for (const auto& name : registry.Names()) {
    fmt::print("  {:<20} {}\n", name, registry.Description(name));
    for (const auto& option : registry.DescribeOptions(name)) {
      if (option.key == "type") continue;
      fmt::print("      {}.{} = {}\n          {}\n", registry.kind(), option.key,
                 option.default_value, option.help);
    }
  }
  fmt::print("\n");
}

// Level solvers are chosen by `optimizer.inner` and read their options from the [optimizer] table.
void ListLevelSolvers(const Registry<LevelSolver>& registry) {
  fmt::print(
      "inner:\n  (level solvers, chosen by optimizer.inner of hierarchical; their options go in "
      "the [optimizer] table)\n");
  for (const auto& name : registry.Names()) {
    fmt::print("  {:<20} {}\n", name, registry.Description(name));
    for (const auto& option : registry.DescribeOptions(name)) {
      fmt::print("      optimizer.{} = {}\n          {}\n", option.key, option.default_value,
                 option.help);
    }
  }
  fmt::print("\n");
}

void ListSmallSystems() {
  fmt::print("solver.small_systems (optional table: a second solver for small reduced systems):\n");
  for (const auto& option : DescribeSmallSystemsOptions()) {
    fmt::print("      solver.small_systems.{} = {}\n          {}\n", option.key,
               option.default_value, option.help);
  }
  fmt::print("\n");
}

// A run config table that is no registry's, with the options its parser reads.
void ListTableOptions(const char* table, const char* title,
                      const std::vector<OptionInfo>& options) {
  fmt::print("{} ({}):\n", table, title);
  for (const auto& option : options) {
    fmt::print("      {}.{} = {}\n          {}\n", table, option.key, option.default_value,
               option.help);
  }
  fmt::print("\n");
}

// `--preset NAME` (and `preset = "NAME"` in configs): each preset's settings, by when they apply.
void ListPresets() {
  fmt::print("presets:\n  (--preset NAME, or preset = \"NAME\" in a config; other options win)\n");
  for (const Preset& preset : Presets()) {
    fmt::print("  {:<20} {}\n", preset.name, preset.description);
    const std::pair<const char*, const std::vector<std::pair<std::string, std::string>>*> groups[] =
        {{"", &preset.settings},
         {"  (hierarchical optimizer)", &preset.hierarchical_settings},
         {"  (hierarchical optimizer, local_global levels)", &preset.local_global_settings}};
    for (const auto& [when, settings] : groups) {
      for (const auto& [key, value] : *settings) fmt::print("      {} = {}{}\n", key, value, when);
    }
  }
  fmt::print("\n");
}

void ListBuiltinMeshes() {
  fmt::print("built-in meshes (scenario: mesh = {{ builtin = NAME, ... }}):\n");
  for (const auto& name : BuiltinMeshNames()) fmt::print("  {}\n", name);
  fmt::print(
      "volumetric twins of surfaces (scenario: mesh = {{ tetrahedralize = FILE or "
      "{{ builtin = NAME, ... }}, max_volume, max_radius_edge_ratio, "
      "min_dihedral_angle }}, see docs/input.md)\n");
}

}  // namespace

int ListPieces(const std::string& requested) {
  const Registries registries = MakeBuiltinRegistries();
  std::string kind = requested;
  std::transform(kind.begin(), kind.end(), kind.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  // Each KIND by its plural (as `harap list` titles them) and its singular (the config table).
  const std::vector<std::pair<std::vector<std::string>, std::function<void()>>> kinds = {
      {{"optimizers", "optimizer"}, [&] { ListRegistry(registries.optimizers); }},
      {{"energies", "energy"}, [&] { ListRegistry(registries.energies); }},
      {{"solvers", "solver"},
       [&] {
         ListRegistry(registries.linear_solvers);
         ListSmallSystems();
       }},
      {{"hierarchies", "hierarchy"}, [&] { ListRegistry(registries.hierarchies); }},
      {{"upsamplers", "upsampler"}, [&] { ListRegistry(registries.upsamplers); }},
      {{"level_solvers", "level_solver", "inner"},
       [&] { ListLevelSolvers(registries.level_solvers); }},
      {{"mesh"},
       [&] {
         ListTableOptions("mesh", "run config [mesh] table, applied before solving",
                          DescribeComponents(registries).mesh_options);
       }},
      {{"registration"},
       [&] {
         ListTableOptions("registration", "run config [registration] table of harap register",
                          DescribeComponents(registries).registration_options);
       }},
      {{"builtins", "builtin", "meshes"}, ListBuiltinMeshes},
      {{"presets", "preset"}, ListPresets},
  };
  if (kind.empty()) {
    for (const auto& [names, list] : kinds) list();
    return 0;
  }
  std::string valid;
  for (const auto& [names, list] : kinds) {
    if (std::find(names.begin(), names.end(), kind) != names.end()) {
      list();
      return 0;
    }
    valid += (valid.empty() ? "" : ", ") + names.front();
  }
  throw ConfigError(
      fmt::format("harap list: unknown kind '{}'; valid kinds: {} (or none for "
                  "everything)",
                  requested, valid));
}

std::string VersionString() {
  const std::string describe = HARAP_GIT_DESCRIBE;
  return describe.empty() ? fmt::format("harap {}", HARAP_VERSION)
                          : fmt::format("harap {} (git {})", HARAP_VERSION, describe);
}

}  // namespace harap
