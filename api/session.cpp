// SPDX-License-Identifier: MIT
#include "api/session.h"

#include <nlohmann/json.hpp>
#include <numeric>
#include <unordered_map>

#include "api/run_warnings.h"
#include "framework/error.h"

namespace harap {

ConfiguredSession::ConfiguredSession(const Registries& registries, const Mesh& mesh,
                                     const ConfigNode& run_config, int threads,
                                     const SessionOptions::FrameStart* frame_start,
                                     const std::vector<double>& stiffness)
    : registries_(registries), config_(run_config) {
  ValidateRunConfig(config_);
  const MeshRepairOptions mesh_options =
      MeshRepairOptions::FromConfig(OptionReader(config_.Child("mesh")));
  // The defaults of `harap deform` (RunDeform).
  const DefaultComponents defaults = DefaultComponentsFor(registries_, mesh);
  OptionReader optimizer_node(config_.Child("optimizer"));
  optimizer_ = optimizer_node.Get("type", defaults.optimizer, "which optimizer");
  SessionOptions options = SessionOptions::FromConfig(optimizer_node, registries_.level_solvers);
  if (frame_start) options.frame_start = *frame_start;
  factory_ = std::make_unique<RegistryComponentFactory>(registries_, config_, defaults);
  options.optimizer.level_solver->CheckCompatible(*factory_->MakeEnergy(), /*handle_edits=*/true);
  const Context context = Context::WithThreads(threads);
  threads_ = context.threads();
  DeformationProblem problem;
  problem.mesh = &mesh;
  problem.constraints.targets.resize(0, 3);
  problem.stiffness = stiffness;
  const auto prepared =
      context.Run([&] { return std::make_unique<const PreparedProblem>(problem, mesh_options); });
  mesh_checks_ = prepared->checks();
  mesh_summary_ = prepared->Summary();
  const Mesh& solved = *prepared->problem().mesh;
  if (solved.num_vertices() != mesh.num_vertices()) {
    // Handles and positions of a session are per input vertex; welding renumbers them.
    throw InputError(fmt::format(
        "the mesh repair welds {} vertices into {}; a session works on the input's vertices: "
        "set [mesh] weld_duplicates = false, or weld the mesh file first",
        mesh.num_vertices(), solved.num_vertices()));
  }
  mesh_ = solved;
  // Each vertex's component (by the elements, as CheckMesh finds them), so that MeshChecksFor()
  // counts a handle set's vertices per component without checking the mesh again.
  std::vector<Index> parent(static_cast<size_t>(mesh_.num_vertices()));
  std::iota(parent.begin(), parent.end(), Index{0});
  const auto root = [&](Index v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (Index e = 0; e < mesh_.num_elements(); ++e) {
    for (Index a = 1; a < mesh_.elements.cols(); ++a) {
      parent[root(mesh_.elements(e, a))] = root(mesh_.elements(e, 0));
    }
  }
  // CheckMesh names a component by its lowest element (of the input mesh, whose connectivity
  // the solved mesh keeps: only duplicate elements may be dropped).
  std::unordered_map<Index, Index> by_first_element;
  for (size_t c = 0; c < mesh_checks_.components.size(); ++c) {
    by_first_element[mesh_checks_.components[c].first_element] = static_cast<Index>(c);
  }
  std::vector<Index> first_element(parent.size(), -1);
  for (Index e = mesh.num_elements() - 1; e >= 0; --e) first_element[root(mesh.elements(e, 0))] = e;
  vertex_component_.assign(parent.size(), -1);
  for (Index e = 0; e < mesh_.num_elements(); ++e) {
    for (Index a = 0; a < mesh_.elements.cols(); ++a) {
      const Index v = mesh_.elements(e, a);
      const auto it = by_first_element.find(first_element[root(v)]);
      if (it != by_first_element.end()) vertex_component_[v] = it->second;
    }
  }
  session_ = std::make_unique<DeformationSession>(mesh_, *factory_, options, context,
                                                  prepared->problem().stiffness);
}

MeshCheckReport ConfiguredSession::MeshChecksFor(const std::vector<Index>& handles) const {
  MeshCheckReport checks = mesh_checks_;
  for (MeshComponentInfo& component : checks.components) component.constrained_vertices = 0;
  for (const Index v : handles) {
    if (v < 0 || v >= static_cast<Index>(vertex_component_.size())) continue;
    if (const Index c = vertex_component_[v]; c >= 0) ++checks.components[c].constrained_vertices;
  }
  checks.components_without_constraints = 0;
  for (const MeshComponentInfo& component : checks.components) {
    if (component.constrained_vertices == 0) ++checks.components_without_constraints;
  }
  return checks;
}

std::unique_ptr<ConfiguredSession> MakeSession(const Registries& registries, const Mesh& mesh,
                                               const ConfigNode& run_config, int threads,
                                               SessionOptions::FrameStart frame_start,
                                               const std::vector<double>& stiffness) {
  return std::make_unique<ConfiguredSession>(registries, mesh, run_config, threads, &frame_start,
                                             stiffness);
}

std::string_view RefactorRouteName(LinearSolver::RefactorRoute route) {
  switch (route) {
    case LinearSolver::RefactorRoute::kFull:
      return "full";
    case LinearSolver::RefactorRoute::kNumeric:
      return "numeric";
    case LinearSolver::RefactorRoute::kUpdate:
      return "update";
    case LinearSolver::RefactorRoute::kPartial:
      return "partial";
  }
  return "?";
}

DeformOutcome SessionOutcome(const ConfiguredSession& session, const Scenario& scenario,
                             OptimizeResult result, std::vector<TraceEntry> trace) {
  const RegistryComponentFactory& factory = session.factory();
  DeformOutcome outcome;
  outcome.optimizer = session.optimizer();
  outcome.energy_type = session.energy_name();
  outcome.solver = session.solver_name();
  if (factory.made_hierarchy()) outcome.hierarchy = factory.hierarchy_name();
  if (factory.made_upsampler()) outcome.upsampler = factory.upsampler_name();
  for (const LevelResult& level : result.levels) {
    outcome.level_solvers.push_back(factory.solver_used(level.level, level.unknowns));
    outcome.level_solver_direct.push_back(factory.solver_direct(level.level, level.unknowns));
  }
  outcome.threads = session.threads();
  outcome.result = std::move(result);
  outcome.trace = std::move(trace);
  outcome.resolved_config = session.resolved_config();
  std::vector<Index> handles;
  for (const ScenarioHandle& handle : scenario.handles) {
    handles.insert(handles.end(), handle.vertices.begin(), handle.vertices.end());
  }
  outcome.mesh_checks = session.MeshChecksFor(handles);
  outcome.mesh_summary = SummarizeMeshChecks(outcome.mesh_checks);
  outcome.solved_vertices = session.mesh().num_vertices();
  outcome.solved_elements = session.mesh().num_elements();
  // A session refuses welding, so the solved mesh differs from the input at most by dropped
  // duplicate elements.
  outcome.mesh_repaired = session.mesh().num_elements() != scenario.mesh.num_elements();
  RunWarningInput warning_input;
  warning_input.scenario = &scenario;
  warning_input.input_checks = &outcome.mesh_checks;
  warning_input.solved_checks = &outcome.mesh_checks;
  warning_input.result = &outcome.result;
  warning_input.hierarchical = factory.made_hierarchy();
  outcome.warnings = RunWarnings(warning_input);
  return outcome;
}

std::string HandleEditJson(const HandleEditResult& edit) {
  using nlohmann::json;
  json levels = json::array();
  for (const HandleEditResult::Level& level : edit.levels) {
    levels.push_back(
        {{"level", level.level},
         {"constrained_vertices", level.constrained_vertices},
         {"changed_rows", level.changed_rows},
         {"factored", level.factored},
         {"route", level.factored ? std::string(RefactorRouteName(level.route)) : "none"},
         {"seconds", level.seconds}});
  }
  const ConstraintReport& c = edit.constraints;
  const json result = {{"seconds", edit.seconds},
                       {"levels", levels},
                       {"constraints",
                        {{"constrained_vertices", c.constrained_vertices},
                         {"isolated_vertices", c.isolated_vertices},
                         {"free_components", c.free_components},
                         {"vertices_in_free_components", c.vertices_in_free_components}}},
                       {"notes", edit.notes}};
  return result.dump();
}

}  // namespace harap
