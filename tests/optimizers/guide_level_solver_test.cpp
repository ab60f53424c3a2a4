// SPDX-License-Identifier: MIT
// The worked example of docs/adding-a-level-solver.md: a small level solver, registered by name
// and run by the hierarchical optimizer on every level. If this file changes, update the guide
// (it quotes the steps), and the other way round: the suite builds and runs it, so a guide
// that no longer matches the interface fails here.
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <string>

#include "framework/constrained_system.h"
#include "framework/level_solver.h"
#include "solvers/optimizers/coarse_constraints.h"
#include "solvers/optimizers/register_optimizers.h"
#include "tests/support/test_factory.h"
#include "tests/support/test_meshes.h"

using namespace harap;
using namespace harap::testing;

namespace {

// Step 1: the level solver. Local/global without a factorization: the local step fits the
// rotations exactly (Energy::FitRotations), the global step is replaced by a few Gauss–Seidel
// sweeps on A_ff u_f = B_f(R) − A_fc u_c from the current positions. Both steps are exact
// minimizations over their block (rotations; one vertex at a time for fixed rotations), so the
// energy never increases. Setting a level up costs no factorization, each iteration a few
// passes over A: a level solver for levels whose factorization would not fit in memory.
class SweepsLevelSolver final : public LevelSolver {
 public:
  struct Options {
    double tolerance = 1e-6;  ///< on max ‖Δu_i‖² / diag² of an iteration, as local_global's
    int max_iterations = 1000;  ///< per level
    int sweeps = 4;             ///< Gauss–Seidel sweeps per global step

    // Step 2: options from the optimizer's table, read once when a run is resolved (the
    // optimizer rejects unknown keys after).
    static Options FromConfig(OptionReader node) {
      Options options;
      options.tolerance = node.Get("tolerance", options.tolerance,
                                   "stop when max squared displacement / diag² falls below this");
      options.max_iterations =
          node.Get("max_iterations", options.max_iterations, "cap on iterations (per level)");
      options.sweeps = node.Get("sweeps", options.sweeps, "Gauss-Seidel sweeps per global step");
      if (options.sweeps < 1)
        node.Fail("sweeps", fmt::format("must be >= 1, got {}", options.sweeps));
      return options;
    }
  };

  explicit SweepsLevelSolver(const Options& options) : options_(options) {}

  // Step 3: the phases.
  std::unique_ptr<LevelSolver> CreateAnother() const override {
    return std::make_unique<SweepsLevelSolver>(options_);
  }

  void Precompute(const LevelSetup& setup, const ComponentFactory& factory,
                  const Context& context) override {
    Stopwatch clock;
    mesh_ = setup.mesh;
    level_ = setup.level;
    energy_ = factory.MakeEnergy();
    if (setup.input_mesh != nullptr) energy_->SetInputMesh(*setup.input_mesh, context);
    energy_->Precompute(*mesh_, context);
    precompute_seconds_ = clock.Seconds();
  }

  ConstrainSummary Constrain(const LevelConstraints& constraints, const ComponentFactory&,
                             const Context&) override {
    Stopwatch clock;
    constraints_ = constraints;
    // Coarse targets follow the vertex rotations; per-element energies average them (Eq. 11).
    if (constraints_.targets_follow_rotations() && rotation_site() == RotationSite::kElement) {
      FindIncidentElements(*mesh_, constraints_);
    }
    system_ = std::make_unique<ConstrainedSystem>(energy_->system_matrix(), constraints_.vertices);
    constrain_seconds_ = clock.Seconds();
    return ConstrainSummary{true, LinearSolver::RefactorRoute::kFull, system_->num_free(),
                            constrain_seconds_};
  }

  void MoveTargets(const Positions& mean_target) override {
    constraints_.mean_target = mean_target;
  }

  LevelSolveResult Solve(LevelState& state, const LevelSolveRequest& request,
                         const Context& context) override {
    if (request.global_step_only) throw InputError("sweeps: no single global step to offer");
    const double tolerance = request.Tolerance(options_.tolerance);
    const int max_iterations =
        request.max_iterations > 0 ? request.max_iterations : options_.max_iterations;
    const RotationSite site = rotation_site();
    const bool have_rotations =
        static_cast<Index>(state.rotations.size()) == energy_->num_rotations();
    // The solver places its constrained vertices itself.
    PlaceConstrainedVertices(constraints_, site, have_rotations ? &state.rotations : nullptr,
                             state.positions);
    if (!have_rotations) state.rotations.assign(energy_->num_rotations(), Rotation::Identity());
    LevelSolveResult result;
    double energy = std::numeric_limits<double>::quiet_NaN();
    if (!request.start_from_rotations) {
      energy = energy_->FitRotations(state.positions, state.rotations, context);
    }
    const double squared_diagonal = request.diagonal * request.diagonal;
    Positions rhs(state.positions.rows(), 3);
    Eigen::MatrixXd b, x;
    while (result.iterations < max_iterations) {
      // Moving coarse targets (targets_follow_rotations): placed before every global step.
      if (request.targets_follow_rotations && constraints_.targets_follow_rotations()) {
        PlaceConstrainedVertices(constraints_, site, &state.rotations, state.positions);
      }
      system_->SetFixedPositions(state.positions);
      energy_->AssembleRhs(state.rotations, rhs, context);
      system_->ReducedRhs(rhs, b);
      system_->GatherFree(state.positions, x);
      for (int sweep = 0; sweep < options_.sweeps; ++sweep) GaussSeidelSweep(b, x);
      const double displacement = system_->ScatterFree(x, state.positions) / squared_diagonal;
      energy = energy_->FitRotations(state.positions, state.rotations, context);
      ++result.iterations;
      if (context.iteration_callback &&
          context.iteration_callback({level_, result.iterations, energy, displacement,
                                      context.run_clock.Seconds()}) == CallbackAction::kStop) {
        result.stopped_by_callback = true;
        break;
      }
      if (displacement < tolerance) {
        result.converged = true;
        break;
      }
    }
    if (std::isnan(energy))
      energy = energy_->FitRotations(state.positions, state.rotations, context);
    result.energy = energy;
    result.measures["sweeps"] = static_cast<double>(result.iterations) * options_.sweeps;
    return result;
  }

  double FitRotations(LevelState& state, const Context& context) override {
    if (static_cast<Index>(state.rotations.size()) != energy_->num_rotations()) {
      state.rotations.assign(energy_->num_rotations(), Rotation::Identity());
    }
    return energy_->FitRotations(state.positions, state.rotations, context);
  }
  std::map<std::string, double> AuxiliaryMeasures(const LevelState& state,
                                                  const Context& context) const override {
    return energy_->AuxiliaryMeasures(state.positions, state.rotations, context);
  }
  RotationSite rotation_site() const override { return energy_->rotation_site(); }
  Index num_unknowns() const override { return system_->num_free(); }
  ConstraintReport constraint_report() const override { return system_->report(); }

 private:
  // One symmetric-storage Gauss–Seidel pass over the free vertices, all three coordinates.
  void GaussSeidelSweep(const Eigen::MatrixXd& b, Eigen::MatrixXd& x) const {
    const SparseMatrix& a = system_->reduced_matrix();
    for (Index i = 0; i < a.outerSize(); ++i) {
      Eigen::RowVector3d sum = b.row(i);
      double diagonal = 0.0;
      for (SparseMatrix::InnerIterator it(a, i); it; ++it) {  // column i = row i (symmetric)
        if (it.row() == i) {
          diagonal = it.value();
        } else {
          sum -= it.value() * x.row(it.row());
        }
      }
      if (diagonal > 0.0) x.row(i) = sum / diagonal;
    }
  }

  Options options_;
  const Mesh* mesh_ = nullptr;
  int level_ = 0;
  std::unique_ptr<Energy> energy_;
  LevelConstraints constraints_;
  std::unique_ptr<ConstrainedSystem> system_;
};

// Step 4: registration. Level solvers go into Registries::level_solvers; the optimizers take a
// copy of that registry when they are registered, so register level solvers first.
Registries RegistriesWithSweeps() {
  Registries registries = MakeBuiltinRegistries();
  registries.level_solvers.AddParsed<SweepsLevelSolver>(
      "sweeps", "local/global with Gauss-Seidel sweeps for the global step",
      &SweepsLevelSolver::Options::FromConfig);
  registries.optimizers = Registry<Optimizer>("optimizer");
  RegisterOptimizers(registries.optimizers, registries.level_solvers);
  return registries;
}

// A bent tube of 30 × 16 = 480 vertices and a three-level hierarchy.
struct SmallBentTube : BentTube {
  SmallBentTube() : BentTube(30, 16, 2.0, M_PI / 3, Eigen::Vector3d(0.0, 0.5, -0.4)) {}
};

OptimizeResult Run(const Registries& registries, const std::string& toml,
                   const DeformationProblem& problem, EnergyTrace* trace = nullptr) {
  const ConfigNode config = ConfigNode::Parse(toml, "guide config");
  const RegistryComponentFactory factory(registries, config);
  Context context;
  if (trace) {
    context.iteration_callback = [&](const IterationSummary& s) {
      (*trace)[s.level].push_back(s.energy);
      return CallbackAction::kContinue;
    };
  }
  return MakeOptimizer(registries, config)->Optimize(problem, factory, context);
}

}  // namespace

// Step 5: run it by name.
TEST_CASE("guide: a level solver registered by name runs on every level", "[optimizers][guide]") {
  const Registries registries = RegistriesWithSweeps();
  SmallBentTube tube;
  const std::string hierarchy = "[hierarchy]\nmin_vertices = 60\n";
  EnergyTrace trace;
  const OptimizeResult sweeps = Run(registries,
                                    "[optimizer]\ntype = \"hierarchical\"\ninner = \"sweeps\"\n"
                                    "sweeps = 8\ntolerance = 1e-10\nmax_iterations = 3000\n"
                                    "targets_follow_rotations = false\n" +
                                        hierarchy,
                                    tube.problem, &trace);
  const OptimizeResult exact = Run(registries,
                                   "[optimizer]\ntype = \"hierarchical\"\ntolerance = 1e-10\n"
                                   "max_iterations = 3000\ntargets_follow_rotations = false\n" +
                                       hierarchy,
                                   tube.problem);
  REQUIRE(sweeps.levels.size() >= 3);
  REQUIRE(sweeps.levels.size() == exact.levels.size());
  for (const LevelResult& level : sweeps.levels) {
    INFO("level " << level.level);
    CHECK(level.iterations > 0);
    CHECK(level.Measure("sweeps") == 8.0 * level.iterations);  // the solver's own measure
  }
  // Exact block minimizations: the energy never increases within a level...
  CheckEnergiesNeverIncrease(trace);
  // ... and the sweeps reach the minimum the factored global step reaches.
  INFO("sweeps " << sweeps.energy << ", local_global " << exact.energy);
  CHECK(std::abs(sweeps.energy - exact.energy) <= 1e-3 * exact.energy);
  // A one-level run of the same driver works too: the classic optimizer's shape.
  const OptimizeResult flat =
      Run(registries,
          "[optimizer]\ntype = \"hierarchical\"\ninner = \"sweeps\"\nmax_iterations = 5\n"
          "[hierarchy]\nmax_levels = 1\n",
          tube.problem);
  CHECK(flat.levels.size() == 1);
  CHECK(flat.iterations == 5);
}

TEST_CASE("guide: optimizer.inner is a registry name", "[optimizers][guide]") {
  const Registries registries = RegistriesWithSweeps();
  CHECK(registries.level_solvers.Contains("sweeps"));
  // Its options are listed with the optimizer's (harap list).
  bool listed = false;
  for (const OptionInfo& option : registries.level_solvers.DescribeOptions("sweeps")) {
    listed = listed || option.key == "sweeps";
  }
  CHECK(listed);
  SmallBentTube tube;
  const auto message = [&](const std::string& toml) {
    try {
      Run(registries, toml, tube.problem);
    } catch (const ConfigError& error) {
      return std::string(error.what());
    }
    return std::string("no error");
  };
  // Unknown names fail listing the valid ones; unknown keys fail too.
  CHECK_THAT(message("[optimizer]\ntype = \"hierarchical\"\ninner = \"sweep\"\n"),
             Catch::Contains("sweep") && Catch::Contains("local_global") &&
                 Catch::Contains("sweeps") && Catch::Contains("wrapd"));
  CHECK_THAT(message("[optimizer]\ntype = \"hierarchical\"\ninner = \"sweeps\"\nsweeps = 0\n"),
             Catch::Contains("sweeps") && Catch::Contains(">= 1"));
  CHECK_THAT(message("[optimizer]\ntype = \"hierarchical\"\ninner = \"sweeps\"\nanderson = 5\n"),
             Catch::Contains("anderson"));
  CHECK(message("[optimizer]\ntype = \"hierarchical\"\ninner = \"sweeps\"\nmax_iterations = 3\n") ==
        "no error");
  // The builtin optimizers, registered before "sweeps" existed, do not know it.
  const Registries builtin = MakeBuiltinRegistries();
  const ConfigNode config =
      ConfigNode::Parse("[optimizer]\ntype = \"hierarchical\"\ninner = \"sweeps\"\n", "guide");
  CHECK_THROWS_AS(MakeOptimizer(builtin, config), ConfigError);
}
