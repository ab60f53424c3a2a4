// SPDX-License-Identifier: MIT
#pragma once

#include <Eigen/SparseCholesky>
#include <memory>
#include <string_view>

#include "framework/config.h"
#include "framework/linear_solver.h"

namespace harap {

/// Sparse LDLᵀ factorization P A Pᵀ = L D Lᵀ with Eigen's SimplicialLDLT and an AMD ordering,
/// then X = A⁻¹ B by two triangular solves. Always built: the reference the other solvers are
/// tested against and the fallback when CHOLMOD is not available. Slower than `cholmod` on
/// large matrices (no METIS, no supernodes) but identical in contract.
///
/// `a` is n×n SPD in full storage (only its lower triangle is read); B and X are n×k.
/// Factorize() analyzes and factors (each object factors one matrix); Solve() is
/// allocation-free after its first call with a given k (it keeps an n×k workspace).
///
/// Factorize() throws NumericalError when A is not positive definite: a pivot ≤ 0, or one so
/// small relative to A's diagonal that A is numerically singular. Not thread-safe.
class EigenLdltSolver final : public LinearSolver {
 public:
  static constexpr std::string_view kName = "eigen_ldlt";

  struct Options {
    /// Pivots d_k ≤ pivot_tolerance · A_kk count as zero (numerically singular A); in [0, 1),
    /// 0 rejects only non-positive pivots. The default lies between roundoff and real pivots: on
    /// grid Laplacians up to 90K unknowns |d| / A_kk ≤ 1.5e-12 when singular, ≥ 0.15 when
    /// pinned; SPD needs 0 < d_k ≤ A_kk.
    double pivot_tolerance = 1e-10;
    /// Compute max over columns of ‖b − A x‖ / ‖b‖ in every Solve() (keeps a copy of A; slow).
    bool check_residual = false;

    /// Reads the options and rejects unknown keys (ConfigError listing the valid ones).
    static Options FromConfig(OptionReader node);
  };

  explicit EigenLdltSolver(const Options& options) : LinearSolver(kName), options_(options) {}

  bool is_direct() const override { return true; }

  const Options& options() const { return options_; }

 private:
  void FactorizeImpl(const SparseMatrix& a, const Context& context) override;
  SolveSummary SolveImpl(const Eigen::Ref<const Eigen::MatrixXd>& b, Eigen::Ref<Eigen::MatrixXd> x,
                         const Context& context) override;
  using Ldlt = Eigen::SimplicialLDLT<SparseMatrix, Eigen::Lower, Eigen::AMDOrdering<int>>;

  Options options_;
  Ldlt ldlt_;
  Eigen::VectorXd pivots_;     ///< D of L D Lᵀ, in the factor's order.
  Eigen::MatrixXd workspace_;  ///< n×k permuted right-hand side / solution.
  SparseMatrix a_copy_;        ///< Only with check_residual.
  Eigen::MatrixXd residual_;   ///< Only with check_residual.
};

}  // namespace harap
