// SPDX-License-Identifier: MIT
#pragma once

#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "framework/context.h"
#include "framework/energy.h"
#include "framework/hierarchy.h"
#include "framework/linear_solver.h"
#include "framework/mesh.h"
#include "framework/upsampler.h"

namespace harap {

/// Vertex constraints: vertex indices[k] goes to targets.row(k). Indices are unique.
///
/// A constraint is hard (the vertex is pinned at its target) or soft: with weight w it adds
/// w ‖u_k − t_k‖² to the energy instead of pinning (a pull; see SoftTargets in data_term.h).
/// `weights` is empty (every constraint hard) or has one entry per index, kHardWeight (+∞)
/// marking a hard one and a finite w > 0 a soft one.
struct Constraints {
  static constexpr double kHardWeight = std::numeric_limits<double>::infinity();
  std::vector<Index> indices;
  Positions targets;            ///< #indices×3
  std::vector<double> weights;  ///< empty, or #indices (kHardWeight = hard)

  bool is_hard(size_t k) const { return weights.empty() || weights[k] == kHardWeight; }
  bool has_soft() const {
    for (size_t k = 0; k < weights.size(); ++k) {
      if (!is_hard(k)) return true;
    }
    return false;
  }
  /// The hard constraints alone (weights empty).
  Constraints HardPart() const {
    if (!has_soft()) return Constraints{indices, targets, {}};
    return Select(true);
  }
  /// The soft constraints alone (weights all finite).
  Constraints SoftPart() const {
    if (!has_soft()) return Constraints{{}, Positions(0, 3), {}};
    return Select(false);
  }

 private:
  Constraints Select(bool hard) const {
    Constraints part;
    for (size_t k = 0; k < indices.size(); ++k) {
      if (is_hard(k) == hard) part.indices.push_back(indices[k]);
    }
    part.targets.resize(static_cast<Index>(part.indices.size()), 3);
    Index row = 0;
    for (size_t k = 0; k < indices.size(); ++k) {
      if (is_hard(k) != hard) continue;
      part.targets.row(row++) = targets.row(static_cast<Index>(k));
      if (!hard) part.weights.push_back(weights[k]);
    }
    return part;
  }
};

/// A deformation problem: the rest mesh, the constraints and, optionally, a start configuration
/// (default: rest positions with constrained vertices at their targets).
struct DeformationProblem {
  const Mesh* mesh = nullptr;
  Constraints constraints;
  std::optional<Positions> initial;
};

/// Creates the pluggable pieces an optimizer uses, configured by the caller (the composition root
/// implements it with the registries, from config tables it resolved before the run). Optimizers
/// that work on several levels ask for one energy and one solver per level.
///
/// Thread safety: the Make* calls may run concurrently (a hierarchical run sets finer levels up
/// on another thread while it solves coarser ones), so implementations hold only immutable,
/// resolved options and read no configuration. Option errors belong to the factory's
/// construction, not to these calls.
class ComponentFactory {
 public:
  virtual ~ComponentFactory() = default;
  virtual std::unique_ptr<Energy> MakeEnergy() const = 0;
  /// `level` is the hierarchy level (0 = finest), `num_unknowns` the size of the reduced system.
  virtual std::unique_ptr<LinearSolver> MakeLinearSolver(int level, Index num_unknowns) const = 0;
  virtual std::unique_ptr<Hierarchy> MakeHierarchy() const = 0;
  virtual std::unique_ptr<Upsampler> MakeUpsampler() const = 0;
};

/// Wall time per phase (seconds), as in the paper's Table 1.
struct PhaseTimings {
  double hierarchy = 0.0;   ///< H: building the mesh hierarchy.
  double precompute = 0.0;  ///< P: energy precomputation (weights, matrices) on all levels.
  double constrain = 0.0;   ///< C: constraint elimination and factorization on all levels.
  double solve = 0.0;       ///< S: local/global iterations (and up-sampling).
  double total = 0.0;       ///< T: the whole Optimize() call.
};

/// Per-level outcome (one entry for single-level optimizers).
struct LevelResult {
  int level = 0;
  Index vertices = 0;
  Index elements = 0;
  int iterations = 0;
  double energy = 0.0;   ///< At the end of the level, rotations fitted to the final positions.
  double seconds = 0.0;  ///< Wall time spent on the level (precompute, factor and iterations).
  bool converged = false;
  Index unknowns = 0;             ///< Rows of the level's reduced global-step matrix A_ff.
  SolveStatistics linear_solves;  ///< The level's global-step solves.
  /// What the level's solver counted besides the above, by name (LevelSolveResult::measures):
  /// "inverted_elements" (ADMM: det F_t < 0 at the end), "accelerated_iterations" (Anderson:
  /// accelerated iterates kept), "newton_steps" and "hessian_products" (Newton steps). Absent
  /// where not counted.
  std::map<std::string, double> measures;
  /// measures[name], or `absent` if the level solver did not count it.
  double Measure(const std::string& name, double absent = -1.0) const {
    const auto it = measures.find(name);
    return it == measures.end() ? absent : it->second;
  }
  EnergyWeights weights;  ///< The level energy's weight scheme and negative weights.
};

/// What the constraint handling did to keep the global system non-singular.
struct ConstraintReport {
  Index constrained_vertices = 0;
  Index isolated_vertices = 0;  ///< no element uses them: kept where they are
  Index free_components = 0;    ///< connected components without any constraint
  Index vertices_in_free_components = 0;
};

struct OptimizeResult {
  Positions positions;  ///< #V×3 deformed positions on the input mesh.
  double energy = 0.0;  ///< Final energy, rotations re-fitted to `positions`.
  /// Energy::AuxiliaryMeasures of the final state (e.g. "energy_wrapd"); empty for most energies.
  std::map<std::string, double> measures;
  int iterations = 0;  ///< Iterations on the finest level.
  int total_iterations = 0;
  bool converged = false;
  bool stopped_by_callback = false;
  PhaseTimings timings;
  std::vector<LevelResult> levels;  ///< Finest level first.
  ConstraintReport constraints;     ///< On the finest level.
  std::vector<std::string> notes;   ///< Human-readable remarks (pinned components, ...).
};

/// Minimizes an energy subject to vertex constraints (classic local/global, hierarchical, ADMM).
/// Options come from the optimizer's config table at creation; the pieces it uses come from the
/// factory. Reports each iteration through context.iteration_callback; never prints.
class Optimizer {
 public:
  virtual ~Optimizer() = default;
  virtual OptimizeResult Optimize(const DeformationProblem& problem,
                                  const ComponentFactory& factory,
                                  const Context& context) const = 0;

  /// Throws ConfigError naming the option when the pieces `factory` makes cannot work with this
  /// optimizer's options (e.g. Newton steps need an energy with a rotation derivative). Called
  /// once, when a run's configuration is resolved, before any work. Default: no requirements.
  virtual void CheckComponents(const ComponentFactory& /*factory*/) const {}

 protected:
  Optimizer() = default;
};

}  // namespace harap
