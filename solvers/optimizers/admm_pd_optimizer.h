// SPDX-License-Identifier: MIT
#pragma once

#include <memory>
#include <string_view>

#include "framework/config.h"
#include "framework/optimizer.h"
#include "solvers/optimizers/admm_elements.h"

namespace harap {

/// Rotation-unaware ADMM for the per-element ARAP energy [Overby, Brown, Li & Narain 2017,
/// "ADMM ⊇ Projective Dynamics"], the baseline of the ADMM family: per element an auxiliary
/// Z_t ≈ F_t(x) and a scaled dual U_t, weights w_t² = beta·vol_t; local step = the ARAP proximal
/// map of F_t + U_t in closed form (polar decomposition), global step = one solve with the
/// prefactored weighted Laplacian, dual update. Needs energy `elements` (tetrahedra or planar
/// triangles). The energy is not monotone in the iterations (ADMM decreases the augmented
/// Lagrangian, not E); it converges to a stationary point of E.
class AdmmPdOptimizer final : public Optimizer {
 public:
  static constexpr std::string_view kName = "admm_pd";

  struct Options {
    AdmmOptions admm;  ///< beta (1), tolerance (1e-8), patience (3), max_iterations (1000)
    static Options FromConfig(const ConfigNode& node);
  };

  explicit AdmmPdOptimizer(const Options& options) : options_(options) {}
  static std::unique_ptr<Optimizer> Create(const ConfigNode& node);

  OptimizeResult Optimize(const DeformationProblem& problem, const ComponentFactory& factory,
                          const Context& context) const override;

 private:
  Options options_;
};

}  // namespace harap
