// SPDX-License-Identifier: MIT
#include "solvers/optimizers/level_cascade.h"

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "framework/error.h"
#include "solvers/optimizers/coarse_constraints.h"

namespace harap {

LevelCascade::LevelCascade(const Mesh& mesh, const Context& context)
    : input_mesh_(mesh), finest_(context.Run([&] { return LocalityOrdering(mesh); })) {}

void LevelCascade::SetHierarchy(MeshHierarchy hierarchy, std::unique_ptr<Upsampler> upsampler) {
  HARAP_CHECK(upsampler != nullptr, "a hierarchy needs an upsampler");
  hierarchy_ = std::move(hierarchy);
  as_built_ = RenumberForLocality(finest_, hierarchy_);
  upsampler_ = std::move(upsampler);
  solvers_.resize(hierarchy_.num_levels());
  setup_seconds_.resize(hierarchy_.num_levels(), 0.0);
}

void LevelCascade::SetSingleLevel() {
  solvers_.resize(1);
  setup_seconds_.resize(1, 0.0);
}

void LevelCascade::set_solver(int l, std::unique_ptr<LevelSolver> solver, double setup_seconds) {
  solvers_[l] = std::move(solver);
  setup_seconds_[l] = setup_seconds;
}

void LevelCascade::TakeRotationSite(int coarsest_solved) {
  site_ = solvers_[coarsest_solved]->rotation_site();
}

Constraints LevelCascade::ToLevel(const Constraints& input) const {
  Constraints renumbered = input;
  const Index n = input_mesh_.num_vertices();
  for (Index& v : renumbered.indices) {
    HARAP_CHECK(v >= 0 && v < n, "constrained vertex {} out of range", v);
    v = finest_.new_vertex[v];
  }
  return renumbered;
}

LevelConstraints LevelCascade::MapConstraints(int l, const Constraints& level0) const {
  // Ascending as built: as_built_[l] lists the level's vertices in that order.
  return harap::MapConstraints(hierarchy_, l, level0, &as_built_[l]);
}

std::vector<double> LevelCascade::LevelStiffness(int l,
                                                 const std::vector<double>& input_stiffness) const {
  if (input_stiffness.empty()) return {};
  if (l > 0) {
    return harap::LevelStiffness(hierarchy_, l, input_mesh_, input_stiffness, finest_.new_vertex);
  }
  std::vector<double> stiffness(input_stiffness.size());
  for (size_t e = 0; e < stiffness.size(); ++e)
    stiffness[e] = input_stiffness[finest_.old_element[e]];
  return stiffness;
}

bool LevelCascade::Upsample(int l, const LevelState& coarse, LevelState& fine,
                            const Context& context) const {
  upsampler_->Upsample(hierarchy_.levels[l], hierarchy_.levels[l + 1], site_, coarse, fine,
                       context);
  return upsampler_->output() == UpsampleOutput::kRotations;
}

LevelState& LevelCascade::Run(int top, Pass& pass, const Context& context, OptimizeResult& result,
                              std::vector<std::string>& notes) {
  LevelState* coarser = nullptr;  // the last visited level's state
  bool stopped = false;           // a solve was stopped: finish on the finest level
  Pass::Finish finish = Pass::Finish::kFitRotations;
  const size_t first_result = result.levels.size();
  for (int l = top; l >= 0; --l) {
    if (!pass.Visits(l)) continue;
    bool from_rotations = false;
    LevelState& state = pass.Start(l, coarser, from_rotations);
    coarser = &state;
    if (!pass.Solves(l) || (stopped && l > 0)) continue;
    pass.Prepare(l);
    if (stopped && finish == Pass::Finish::kFitRotations) {
      // As far as the solve got, handed down to the finest level: its rotations fitted.
      result.energy = solvers_[0]->FitRotations(state, context);
      coarser = &pass.Done(l, state, nullptr);
      break;
    }
    Stopwatch clock;
    LevelSolver& solver = *solvers_[l];
    const LevelSolveRequest request = pass.Request(l, from_rotations, stopped);
    const LevelSolveResult run = pass.Solve(solver, state, request, context);
    const double seconds = setup_seconds_[l] + clock.Seconds();
    const Index unknowns = solver.num_unknowns();
    coarser = &pass.Done(l, state, &run);
    notes.insert(notes.end(), run.notes.begin(), run.notes.end());
    result.total_iterations += run.iterations;
    const Mesh& level_mesh = LevelMesh(l);
    result.levels.push_back(LevelResult{l, level_mesh.num_vertices(), level_mesh.num_elements(),
                                        run.iterations, run.energy, seconds, run.converged,
                                        unknowns, run.linear_solves, run.measures, run.weights});
    if (l == 0) {
      result.energy = run.energy;
      result.iterations = run.iterations;
      result.converged = run.converged && !stopped;
    }
    if (run.stopped_by_callback && !stopped) {
      stopped = true;
      result.stopped_by_callback = true;
      finish = pass.OnStop(l);
    }
  }
  std::reverse(result.levels.begin() + static_cast<std::ptrdiff_t>(first_result),
               result.levels.end());
  HARAP_CHECK(coarser != nullptr, "the cascade visited no level");
  return *coarser;
}

}  // namespace harap
