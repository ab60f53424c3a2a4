// SPDX-License-Identifier: MIT
// Interactive sessions (docs/session.md) on armadillo-bend, hierarchical optimizer, the run
// config's defaults (octree, rotations upsampler, CHOLMOD), 2 threads, as `harap drag` runs them:
//
//   SessionFrame/armadillo-bend     one warm frame: SetTargets() + Solve() to 1e-6, the targets
//                                    alternating between the poses of frames 29 and 30 of 30
//                                    (each frame starts from the other pose's solution)
//   SessionPreview/armadillo-bend   one Preview() frame, targets alternating the same way
//                                    (compare with Solve3_auto_amd/armadillo-bend)
//   SessionEdit_<refactor>/armadillo-bend
//                                    a ball of 1% of the vertices added as handles, then removed:
//                                    every level's masked system refactored (CholmodSolver option
//                                    refactor = <refactor>: auto = the session's default, full =
//                                    every level factored from scratch, the baseline); counters
//                                    add_ms, remove_ms, and level0_add_ms / coarse_add_ms (the
//                                    finest level's and the coarse levels' share of the add)
//   SessionReweight_<refactor>/armadillo-bend
//                                    the same ball held by soft handles beside the scenario's
//                                    hard ones, their weight set to 10 and 50 in turn: every
//                                    level's A + W changes on the ball's rows (SetHandles with
//                                    weights; refactor = full: every level factored from
//                                    scratch, the baseline); counters reweight_ms, level0_ms
//
//   ./build/harap_benchmarks --benchmark_filter='Session|Solve3_auto_amd/armadillo'
// Skipped (not registered) when ../shared is absent; the data is loaded on first use.
#ifdef HARAP_HAVE_CHOLMOD  // the config sets CHOLMOD's refactor option

#include <benchmark/benchmark.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

#include "api/builtins.h"
#include "api/drag.h"
#include "api/session.h"
#include "benchmarks/edit_ball.h"
#include "framework/config.h"
#include "io/scenario.h"

namespace {

using namespace harap;

constexpr int kFrames = 30;
constexpr int kThreads = 2;

const Scenario& LoadedScenario() {
  static const Scenario scenario = LoadScenario(ArmadilloBendScenario());
  return scenario;
}

// A session on armadillo-bend with the scenario's handles at frame `kFrames - 1`, solved.
std::unique_ptr<ConfiguredSession> MakeSolvedSession(const std::string& refactor) {
  const Scenario& scenario = LoadedScenario();
  const Registries registries = MakeBuiltinRegistries();
  const ConfigNode config = ConfigNode::Parse(
      "[optimizer]\ntype = \"hierarchical\"\ntolerance = 1e-6\n[solver]\nrefactor = \"" + refactor +
          "\"\n",
      "session benchmark");
  auto session = MakeSession(registries, scenario.mesh, config, kThreads);
  const Constraints pose = FrameConstraints(scenario, (kFrames - 1.0) / kFrames);
  session->session().SetHandles(pose.indices, pose.targets);
  session->session().Solve();
  return session;
}

void Frame(benchmark::State& state, bool preview) {
  const Scenario& scenario = LoadedScenario();
  auto configured = MakeSolvedSession("auto");
  DeformationSession& session = configured->session();
  const Positions poses[2] = {FrameConstraints(scenario, 1.0).targets,
                              FrameConstraints(scenario, (kFrames - 1.0) / kFrames).targets};
  int next = 0;
  double iterations = 0.0;
  for (auto _ : state) {
    session.SetTargets(poses[next]);
    const OptimizeResult result = preview ? session.Preview() : session.Solve();
    iterations += result.total_iterations;
    next = 1 - next;
    benchmark::DoNotOptimize(result.positions.data());
  }
  state.counters["total_iterations"] = iterations / static_cast<double>(state.iterations());
  state.counters["vertices"] = static_cast<double>(scenario.mesh.num_vertices());
}

void Edit(benchmark::State& state, const std::string& refactor) {
  auto configured = MakeSolvedSession(refactor);
  DeformationSession& session = configured->session();
  const std::vector<Index> ball = EditBall(configured->mesh(), session.handles(), 0.01);
  Positions held(static_cast<Index>(ball.size()), 3);
  for (size_t k = 0; k < ball.size(); ++k) {
    held.row(static_cast<Index>(k)) = session.positions().row(ball[k]);
  }
  double add = 0.0, remove = 0.0, level0 = 0.0, coarse = 0.0;
  for (auto _ : state) {
    const HandleEditResult added = session.AddHandles(ball, held);
    const HandleEditResult removed = session.RemoveHandles(ball);
    add += added.seconds;
    remove += removed.seconds;
    for (const auto& level : added.levels) (level.level == 0 ? level0 : coarse) += level.seconds;
  }
  const double iterations = static_cast<double>(state.iterations());
  state.counters["add_ms"] = 1e3 * add / iterations;
  state.counters["remove_ms"] = 1e3 * remove / iterations;
  state.counters["level0_add_ms"] = 1e3 * level0 / iterations;
  state.counters["coarse_add_ms"] = 1e3 * coarse / iterations;
  state.counters["ball"] = static_cast<double>(ball.size());
}

void Reweight(benchmark::State& state, const std::string& refactor) {
  auto configured = MakeSolvedSession(refactor);
  DeformationSession& session = configured->session();
  const std::vector<Index> ball = EditBall(configured->mesh(), session.handles(), 0.01);
  Constraints handles = session.constraints();
  const size_t hard = handles.indices.size();
  handles.weights.assign(hard, Constraints::kHardWeight);
  handles.indices.insert(handles.indices.end(), ball.begin(), ball.end());
  handles.weights.resize(handles.indices.size(), 10.0);
  handles.targets.conservativeResize(static_cast<Index>(handles.indices.size()), 3);
  for (size_t k = 0; k < ball.size(); ++k) {
    handles.targets.row(static_cast<Index>(hard + k)) = session.positions().row(ball[k]);
  }
  session.SetHandles(handles.indices, handles.targets, handles.weights);
  double reweight = 0.0, level0 = 0.0;
  double weight = 10.0;
  for (auto _ : state) {
    weight = weight == 10.0 ? 50.0 : 10.0;
    std::fill(handles.weights.begin() + static_cast<std::ptrdiff_t>(hard), handles.weights.end(),
              weight);
    const HandleEditResult edit =
        session.SetHandles(handles.indices, handles.targets, handles.weights);
    reweight += edit.seconds;
    for (const auto& level : edit.levels) {
      if (level.level == 0) level0 += level.seconds;
    }
  }
  const double iterations = static_cast<double>(state.iterations());
  state.counters["reweight_ms"] = 1e3 * reweight / iterations;
  state.counters["level0_ms"] = 1e3 * level0 / iterations;
  state.counters["ball"] = static_cast<double>(ball.size());
}

[[maybe_unused]] const bool registered = [] {
  if (!std::filesystem::exists(ArmadilloBendScenario())) return false;
  const auto add = [](const std::string& name, auto... args) {
    RegisterArmadilloBendBenchmark(name, args...);
  };
  add("SessionFrame", Frame, false);
  add("SessionPreview", Frame, true);
  add("SessionEdit_auto", Edit, std::string("auto"));
  add("SessionEdit_full", Edit, std::string("full"));
  add("SessionReweight_auto", Reweight, std::string("auto"));
  add("SessionReweight_full", Reweight, std::string("full"));
  return true;
}();

}  // namespace

#endif  // HARAP_HAVE_CHOLMOD
