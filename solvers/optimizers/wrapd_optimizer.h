// SPDX-License-Identifier: MIT
#pragma once

#include <memory>
#include <string_view>

#include "framework/config.h"
#include "framework/optimizer.h"
#include "solvers/optimizers/admm_elements.h"

namespace harap {

/// WRAPD's ARAP mode [Brown & Narain 2021, "WRAPD: Weighted Rotation-aware ADMM"]: ADMM split on
/// the symmetric stretch S_t = sym(polar(F_t)) instead of F_t, so the rotations are left to the
/// global step. Local step in closed form on S_t, Z_t, U_t: Z = (I + beta (S + U)) / (1 + beta),
/// U += S − Z; global step: a few L-BFGS iterations (history lbfgs_history) on
/// Σ_t ½ w_t² ‖S_t(x) − (Z_t − U_t)‖²_F with the prefactored A₀ = Σ_t w_t² D_tᵀ D_t as the initial
/// Hessian and Armijo backtracking. Stops when the relative energy change stays below
/// `tolerance` for `patience` iterations and no element is inverted. Constant weights (WRAPD's
/// reweighting is for non-ARAP energies and off in its ARAP runs, `-rw 0`). Tetrahedra only.
class WrapdOptimizer final : public Optimizer {
 public:
  static constexpr std::string_view kName = "wrapd";

  struct Options {
    /// beta (1), tolerance (1e-8), patience (3), max_iterations (1000), lbfgs_iterations (10),
    /// lbfgs_history (6)
    AdmmOptions admm;
    static Options FromConfig(const ConfigNode& node);
  };

  explicit WrapdOptimizer(const Options& options) : options_(options) {}
  static std::unique_ptr<Optimizer> Create(const ConfigNode& node);

  OptimizeResult Optimize(const DeformationProblem& problem, const ComponentFactory& factory,
                          const Context& context) const override;

 private:
  Options options_;
};

}  // namespace harap
