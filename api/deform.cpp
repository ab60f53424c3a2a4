// SPDX-License-Identifier: MIT
#include "api/deform.h"

#include <sys/resource.h>

#include <cmath>
#include <memory>
#include <nlohmann/json.hpp>
#include <numeric>

#include "api/component_factory.h"
#include "api/huge_pages.h"
#include "api/run_warnings.h"
#include "framework/error.h"

namespace harap {

long long PeakMemoryBytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<long long>(usage.ru_maxrss) * 1024;  // Linux reports kilobytes
}

namespace {

// Runs `optimize` once, or repeatedly for options.min_time (DeformOptions), and keeps the
// repetition with the median timings.total (of an even count, the lower one) in outcome.result
// and outcome.trace (which `optimize`'s iteration callback fills). Every repetition solves the same
// problem to the same positions (deterministic reductions), so only the first one's are kept.
template <class Optimize>
void RunRepeatedly(const Optimize& optimize, const DeformOptions& options, DeformOutcome& outcome) {
  struct Repetition {
    OptimizeResult result;
    std::vector<TraceEntry> trace;
  };
  std::vector<Repetition> repetitions;
  double timed = 0.0;
  do {
    outcome.trace.clear();
    OptimizeResult result = optimize();
    timed += result.timings.total;
    if (!repetitions.empty()) result.positions = Positions();
    repetitions.push_back({std::move(result), std::move(outcome.trace)});
    // A stopped run (Ctrl-C, a callback) is not repeated: its caller asked for it to end.
  } while (!repetitions.back().result.stopped_by_callback && timed < options.min_time &&
           static_cast<int>(repetitions.size()) < options.max_repetitions);
  // A repetition stopped part-way (Ctrl-C) is no measurement when complete ones exist.
  if (repetitions.size() > 1 && repetitions.back().result.stopped_by_callback) {
    repetitions.pop_back();
  }
  std::vector<size_t> order(repetitions.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return repetitions[a].result.timings.total < repetitions[b].result.timings.total;
  });
  outcome.repetitions.count = static_cast<int>(repetitions.size());
  outcome.repetitions.fastest_total = repetitions[order.front()].result.timings.total;
  outcome.repetitions.slowest_total = repetitions[order.back()].result.timings.total;
  Repetition& median = repetitions[order[(order.size() - 1) / 2]];
  if (&median != &repetitions.front()) {
    median.result.positions = std::move(repetitions.front().result.positions);
  }
  outcome.result = std::move(median.result);
  outcome.trace = std::move(median.trace);
}

}  // namespace

DeformOutcome RunDeform(const Registries& registries, const Scenario& scenario,
                        const ConfigNode& config, const DeformOptions& options) {
  const ResolvedRunConfig run(registries, config, scenario.mesh);
  const MeshRepairOptions mesh_options =
      MeshRepairOptions::FromConfig(OptionReader(config.Child("mesh")));
  const RegistryComponentFactory& factory = run.factory;

  DeformOutcome outcome;
  outcome.optimizer = run.optimizer_name;
  outcome.energy_type = factory.energy_name();
  outcome.solver = factory.solver_name();
  outcome.resolved_config = config.ToToml();

  Context context = options.MakeContext();
  outcome.threads = context.threads();
  context.iteration_callback = [&](const IterationSummary& summary) {
    outcome.trace.push_back(
        {summary.seconds, summary.energy, summary.level, summary.inverted_elements});
    return options.progress ? options.progress(summary) : CallbackAction::kContinue;
  };
  std::map<int, SparseMatrix> level_matrices;
  if (options.diagnostics) {
    context.system_callback = [&](int level, const SparseMatrix& reduced) {
      level_matrices[level] = reduced;
    };
  }
  DeformationProblem problem;
  problem.mesh = &scenario.mesh;
  problem.constraints = scenario.MergedConstraints();
  problem.initial = scenario.initial;
  problem.stiffness = options.stiffness.empty() ? scenario.ElementStiffness() : options.stiffness;
  Stopwatch check_clock;
  context.ReportPhase("checking the mesh");
  // Built inside the run's arena so the checks' parallel sorts keep to --threads.
  const std::unique_ptr<const PreparedProblem> prepared_problem = [&] {
    try {
      return context.Run(
          [&] { return std::make_unique<const PreparedProblem>(problem, mesh_options); });
    } catch (const InputError& error) {
      throw InputError(fmt::format("{}: {}", scenario.mesh_source, error.what()));
    }
  }();
  const PreparedProblem& prepared = *prepared_problem;
  outcome.mesh_check_seconds = check_clock.Seconds();
  outcome.mesh_checks = prepared.checks();
  outcome.mesh_summary = prepared.Summary();
  outcome.mesh_repaired = prepared.changed();
  outcome.solved_vertices = prepared.problem().mesh->num_vertices();
  outcome.solved_elements = prepared.problem().mesh->num_elements();
  if (const MeshCheckReport* repaired = prepared.repaired_checks()) {
    outcome.repaired_mesh_checks = *repaired;
    outcome.repaired_mesh_summary = prepared.RepairedSummary();
  }

  RunRepeatedly(
      [&] {
        context.run_clock.Restart();
        return context.Run(
            [&] { return run.optimizer->Optimize(prepared.problem(), factory, context); });
      },
      options, outcome);
  outcome.result.positions = prepared.ToInputVertices(outcome.result.positions);
  for (const LevelResult& level : outcome.result.levels) {
    // What the level's solver was, and for "adaptive" what it chose.
    outcome.level_solvers.push_back(factory.solver_used(level.level, level.unknowns));
    outcome.level_solver_direct.push_back(factory.solver_direct(level.level, level.unknowns));
  }
  // The pieces the optimizer asked for, whether or not their tables were written.
  if (factory.made_hierarchy()) outcome.hierarchy = factory.hierarchy_name();
  if (factory.made_upsampler()) outcome.upsampler = factory.upsampler_name();
  RunWarningInput warning_input;
  warning_input.scenario = &scenario;
  warning_input.input_checks = &outcome.mesh_checks;
  warning_input.solved_checks =
      outcome.mesh_repaired ? &outcome.repaired_mesh_checks : &outcome.mesh_checks;
  warning_input.result = &outcome.result;
  warning_input.hierarchical = factory.made_hierarchy();
  outcome.warnings = RunWarnings(warning_input);
  for (auto& [level, matrix] : level_matrices) {
    outcome.spectra[level] = AnalyzeSystemSpectrum(matrix, EigenSolverOptions{}, context);
    matrix = SparseMatrix();  // release it
  }
  return outcome;
}

namespace {

nlohmann::json FindingsJson(const MeshCheckReport& checks) {
  using nlohmann::json;
  json result;
  for (const MeshFinding* finding : checks.Findings()) {
    result[finding->name] = {{"count", finding->count},
                             {"examples", finding->examples},
                             {"example_kind", finding->example_kind},
                             {"action", finding->action}};
  }
  // The largest components, enough to see the main body and a few stray pieces.
  constexpr size_t kListed = 20;
  json listed = json::array();
  for (size_t c = 0; c < std::min(kListed, checks.components.size()); ++c) {
    const MeshComponentInfo& component = checks.components[c];
    listed.push_back({{"first_element", component.first_element},
                      {"elements", component.elements},
                      {"vertices", component.vertices},
                      {"constrained_vertices", component.constrained_vertices}});
  }
  result["components"] = {
      {"count", checks.components.size()},
      {"with_handles", checks.components.size() - checks.components_without_constraints},
      {"without_handles", checks.components_without_constraints},
      {"largest", listed}};
  return result;
}

nlohmann::json MeshChecksJson(const DeformOutcome& outcome) {
  nlohmann::json result = FindingsJson(outcome.mesh_checks);
  result["repaired"] = outcome.mesh_repaired;
  result["solved_vertices"] = outcome.solved_vertices;
  result["solved_elements"] = outcome.solved_elements;
  result["seconds"] = outcome.mesh_check_seconds;
  result["summary"] = outcome.mesh_summary;
  if (outcome.mesh_repaired) {
    nlohmann::json after = FindingsJson(outcome.repaired_mesh_checks);
    after["summary"] = outcome.repaired_mesh_summary;
    result["after_repair"] = after;
  }
  return result;
}

// Per level: size, iterations, energy, time, the linear solves, the level solver's measures and,
// with --diagnostics, the spectrum.
nlohmann::json LevelsJson(const DeformOutcome& outcome) {
  using nlohmann::json;
  const OptimizeResult& r = outcome.result;
  json levels = json::array();
  for (size_t k = 0; k < r.levels.size(); ++k) {
    const LevelResult& level = r.levels[k];
    const SolveStatistics& solves = level.linear_solves;
    json entry = {
        {"level", level.level},
        {"vertices", level.vertices},
        {"faces", level.elements},
        {"unknowns", level.unknowns},
        {"iterations", level.iterations},
        {"energy", level.energy},
        {"seconds", level.seconds},
        {"converged", level.converged},
        {"solver", k < outcome.level_solvers.size() ? outcome.level_solvers[k] : ""},
        {"solves", solves.solves},
        {"solver_iterations", solves.iterations},
        // null: no solve measured its residual (direct solvers by default).
        {"max_relative_residual",
         solves.residuals_computed > 0 ? json(solves.max_relative_residual) : json(nullptr)},
        {"last_relative_residual",
         solves.residuals_computed > 0 ? json(solves.last_relative_residual) : json(nullptr)},
        {"solve_seconds", solves.seconds}};
    // The energy's weights on the level: scheme, and how many edges have a negative weight.
    if (!level.weights.scheme.empty()) {
      entry["weights"] = level.weights.scheme;
      entry["weighted_edges"] = level.weights.edges;
      entry["negative_weights"] = level.weights.negative_edges;
      entry["energy_can_be_negative"] = level.weights.can_be_negative;
    }
    // The level solver's own measures (inverted_elements, newton_steps, ...); counts as integers.
    for (const auto& [name, value] : level.measures) {
      const bool count = value == std::floor(value) && std::abs(value) < 9.0e15;
      entry[name] = count ? json(static_cast<long long>(value)) : json(value);
    }
    if (const auto it = outcome.spectra.find(level.level); it != outcome.spectra.end()) {
      auto describe = [](const ExtremeEigenvalues& e) {
        return json{{"lambda_min", e.smallest},
                    {"lambda_max", e.largest},
                    {"condition_number", e.condition_number()},
                    {"converged", e.converged},
                    {"products", e.products},
                    {"solves", e.solves},
                    {"seconds", e.seconds}};
      };
      entry["spectrum"] = {{"matrix", describe(it->second.matrix)},
                           {"jacobi", describe(it->second.jacobi)},
                           {"seconds", it->second.seconds}};
    }
    levels.push_back(entry);
  }
  return levels;
}

}  // namespace

std::string DeformReportJson(const Scenario& scenario, const DeformOutcome& outcome,
                             bool include_trace) {
  using nlohmann::json;
  const OptimizeResult& r = outcome.result;
  json report;
  report["status"] = outcome.interrupted ? "interrupted" : "ok";
  report["scenario"] = scenario.file.string();
  report["mesh"] = {
      {"source", scenario.mesh_source},
      {"vertices", scenario.mesh.num_vertices()},
      {"faces", scenario.mesh.num_elements()},
      {"element_kind",
       scenario.mesh.kind() == ElementKind::kTetrahedron ? "tetrahedron" : "triangle"},
      {"planar", scenario.mesh.planar}};
  report["mesh_checks"] = MeshChecksJson(outcome);
  report["optimizer"] = outcome.optimizer;
  report["energy_type"] = outcome.energy_type;
  report["solver"] = outcome.solver;
  if (!outcome.hierarchy.empty()) report["hierarchy"] = outcome.hierarchy;
  if (!outcome.upsampler.empty()) report["upsampler"] = outcome.upsampler;
  report["energy"] = r.energy;
  // The energy's auxiliary measures (e.g. energy_wrapd) sit beside `energy`.
  for (const auto& [name, value] : r.measures) {
    HARAP_CHECK(!report.contains(name), "auxiliary measure '{}' clashes with a report key", name);
    report[name] = value;
  }
  report["iterations"] = r.iterations;
  report["total_iterations"] = r.total_iterations;
  report["converged"] = r.converged;
  report["timings"] = {{"hierarchy", r.timings.hierarchy},
                       {"precompute", r.timings.precompute},
                       {"constrain", r.timings.constrain},
                       {"solve", r.timings.solve},
                       {"total", r.timings.total}};
  // One run (also every session's outcome, which leaves the spread unset): its own total.
  const bool repeated = outcome.repetitions.count > 1;
  report["repetitions"] = {
      {"count", outcome.repetitions.count},
      {"fastest_total", repeated ? outcome.repetitions.fastest_total : r.timings.total},
      {"slowest_total", repeated ? outcome.repetitions.slowest_total : r.timings.total}};
  report["peak_memory_bytes"] = PeakMemoryBytes();
  report["huge_pages"] = HugePageBacking();
  report["threads"] = outcome.threads;
  report["constraints"] = {
      {"constrained_vertices", r.constraints.constrained_vertices},
      {"isolated_vertices", r.constraints.isolated_vertices},
      {"free_components", r.constraints.free_components},
      {"vertices_in_free_components", r.constraints.vertices_in_free_components}};
  json handles = json::array();
  for (const auto& handle : scenario.handles) {
    handles.push_back({{"name", handle.name}, {"vertices", handle.vertices.size()}});
  }
  report["handles"] = handles;
  if (!scenario.stiffness.empty()) {
    json regions = json::array();
    for (const auto& region : scenario.stiffness) {
      json entry = {{"name", region.name},
                    {"vertices", region.vertices.size()},
                    {"selection", region.selection}};
      if (region.attribute.empty()) {
        entry["factor"] = region.factor;
      } else {
        entry["attribute"] = region.attribute;
        entry["per"] = region.element_factors.empty() ? "vertex" : "element";
      }
      regions.push_back(entry);
    }
    report["stiffness"] = regions;
  }
  report["levels"] = LevelsJson(outcome);
  // Remarks about the input (scenario loading) first, then those of the run.
  std::vector<std::string> notes = scenario.notes;
  notes.insert(notes.end(), r.notes.begin(), r.notes.end());
  report["notes"] = notes;
  report["warnings"] = outcome.warnings;
  report["config"] = outcome.resolved_config;
  if (include_trace) {
    json trace = json::array();
    for (const auto& entry : outcome.trace) {
      json point = {{"t", entry.t}, {"energy", entry.energy}, {"level", entry.level}};
      if (entry.inverted_elements >= 0) point["inverted_elements"] = entry.inverted_elements;
      trace.push_back(point);
    }
    report["trace"] = trace;
  }
  return report.dump(2);
}

std::string HandlesJson(const Scenario& scenario) {
  nlohmann::json handles = nlohmann::json::array();
  for (const auto& handle : scenario.handles) {
    handles.push_back({{"name", handle.name}, {"vertices", handle.vertices}});
  }
  return nlohmann::json{{"handles", handles}}.dump();
}

}  // namespace harap
