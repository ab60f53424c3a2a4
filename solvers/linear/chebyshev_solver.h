// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <memory>
#include <string_view>

#include "framework/config.h"
#include "framework/linear_solver.h"
#include "solvers/linear/iterative_kernels.h"
#include "solvers/linear/spectral_bounds.h"

namespace harap {

/// Chebyshev semi-iterative acceleration of Jacobi [Golub & Varga 1961; Saad, Iterative Methods
/// for Sparse Linear Systems, Alg. 12.1], the method Wang [2015] uses to accelerate projective
/// dynamics, warm-started from `x`.
///
/// With [λ_lo, λ_hi] ⊇ spectrum of D⁻¹A (D = diag A), θ = (λ_hi + λ_lo)/2, δ = (λ_hi − λ_lo)/2,
/// σ = θ/δ and ρ₀ = 1/σ:
///   r₀ = b − A x₀,  d₀ = D⁻¹ r₀ / θ;
///   x_{k+1} = x_k + d_k,  r_{k+1} = r_k − A d_k,  ρ_{k+1} = 1/(2σ − ρ_k),
///   d_{k+1} = ρ_{k+1} ρ_k d_k + (2 ρ_{k+1}/δ) D⁻¹ r_{k+1}.
/// After k steps the error is p_k(D⁻¹A) e₀ with p_k the scaled Chebyshev polynomial, the
/// smallest max-norm on [λ_lo, λ_hi] of any degree-k polynomial with p(0) = 1. No inner products
/// are needed (except for the tolerance test), and d_{k+1} only needs row i's own data, so one
/// iteration is one parallel pass over A (A d_k is read from a second buffer while d_{k+1} is
/// written). Wang's form, x_{k+1} = ω_{k+1}(γ (Jacobi(x_k) − x_k) + x_k − x_{k−1}) + x_{k−1}
/// with ω from the spectral radius ρ of the (γ-damped) Jacobi iteration, is this iteration on
/// the interval [(1 − ρ)/γ, (1 + ρ)/γ], symmetric about 1/γ; it needs a convergent damped
/// Jacobi (for mesh matrices λ_max(D⁻¹A) often exceeds 2) and is never better than the tight
/// interval used here. Wang also carries the recurrence across the outer local/global
/// iterations; a LinearSolver sees one system per global step, so here each Solve() starts a
/// new polynomial from its warm start (which keeps every global step an A-norm descent).
///
/// The upper bound λ_hi is the largest eigenvalue of D^{-1/2} A D^{-1/2} (same spectrum as
/// D⁻¹A), computed by Spectra's Lanczos in Factorize() (spectral_bounds.h), widened by
/// upper_margin and capped by Gershgorin's bound (which is guaranteed); underestimating λ_max
/// would make the iteration diverge. The lower bound λ_lo (`lower_bound`):
///  - "shift_invert": the smallest eigenvalue by Spectra's shift-invert mode with a Cholesky
///    factorization, times (1 − lower_margin): the textbook interval, right when solving to a
///    tolerance, but it costs a factorization — the cost an iterative solver is meant to avoid.
///  - "budget": λ_hi / max_iterations², no factorization (for fixed budgets, tolerance = 0).
///  - "auto" (default): budget without a tolerance, shift_invert with one.
/// Why "budget": A degree-k Chebyshev
///    polynomial cannot damp modes below about λ_hi/k² anyway; spreading it over the whole
///    spectrum [λ_min, λ_hi] of a mesh matrix (κ ≈ 1e5) leaves every mode nearly undamped
///    (|p| ≤ 1/T_k(σ) ≈ 0.99 for k = 30). On the armadillo's finest level a λ_lo near λ_hi/k²
///    leaves a smaller A-norm error after 30 steps than the exact λ_min (docs/solvers.md,
///    "chebyshev", has the table).
/// Either interval may extend below the spectrum's true low end: modes there are still damped
/// (|p| < 1 on (0, λ_hi]), only more slowly, so the A-norm error never grows.
/// The bounds are computed once per matrix (a hash of it is kept, so refactoring the same matrix
/// reuses them).
///
/// Solve() allocates nothing after its first call with a given column count. Not thread-safe.
class ChebyshevSolver final : public iterative::MatrixIterativeSolver<ChebyshevSolver> {
 public:
  static constexpr std::string_view kName = "chebyshev";

  enum class LowerBound { kAuto, kBudget, kShiftInvert };

  struct Options {
    /// max_iterations: Chebyshev steps per solve (a cap when tolerance > 0). Default 30, no
    /// tolerance.
    iterative::IterationLimits limits{30, 0.0};
    LowerBound lower_bound = LowerBound::kAuto;
    /// λ_hi = min((1 + upper_margin) · λ_max estimate, Gershgorin bound).
    double upper_margin = 0.01;
    /// With shift_invert: λ_lo = (1 − lower_margin) · λ_min estimate, in [0, 1). Spectra's
    /// estimate of λ_min is an upper bound (a Ritz value of A⁻¹ is ≤ 1/λ_min); the margin makes
    /// the interval enclose the spectrum.
    double lower_margin = 0.01;

    static Options FromConfig(OptionReader node);
  };

  explicit ChebyshevSolver(const Options& options)
      : MatrixIterativeSolver(kName), options_(options) {}

  const Options& options() const { return options_; }

  /// The interval the iteration uses and the eigenvalue estimates it came from.
  struct Bounds {
    double lower = 0.0;  ///< λ_lo
    double upper = 0.0;  ///< λ_hi
    /// Spectra's estimates for D^{-1/2} A D^{-1/2} (smallest = 0 unless shift_invert).
    ExtremeEigenvalues estimate;
    double gershgorin = 0.0;  ///< Gershgorin's bound on λ_max.
  };
  const Bounds& bounds() const { return bounds_; }

 private:
  friend class iterative::MatrixIterativeSolver<ChebyshevSolver>;
  /// Computes the bounds, unless they belong to this matrix already (Factorize()).
  void Prepare(const Context& context);
  /// The Chebyshev iteration on the row-major blocks b and x.
  template <int K>
  SolveSummary SolveGathered(const double* b, double* x, Eigen::Index first);

  Options options_;
  Bounds bounds_;
  uint64_t matrix_hash_ = 0;  ///< Of the matrix bounds_ belongs to (0: none).
  iterative::Block r_, d_, d_next_;
};

// SolveImpl() calls SolveGathered<K>, defined in the .cpp: instantiated there only.
extern template class iterative::BlockIterativeSolver<ChebyshevSolver>;
extern template class iterative::MatrixIterativeSolver<ChebyshevSolver>;

}  // namespace harap
