// SPDX-License-Identifier: MIT
#include "solvers/linear/chebyshev_solver.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <string>
#include <utility>

#include "framework/error.h"

namespace harap {

namespace {

using iterative::ColumnValues;
using iterative::RowProduct;
using iterative::SumRows;

/// FNV-1a over the matrix's size, pattern and values: identifies the matrix the cached bounds
/// belong to.
uint64_t MatrixHash(const SparseMatrix& a) {
  uint64_t hash = 1469598103934665603ull;
  auto mix = [&hash](const void* data, size_t bytes) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < bytes; ++i) {
      hash ^= p[i];
      hash *= 1099511628211ull;
    }
  };
  const Eigen::Index rows = a.rows();
  mix(&rows, sizeof(rows));
  mix(a.outerIndexPtr(), sizeof(Index) * static_cast<size_t>(a.outerSize() + 1));
  mix(a.innerIndexPtr(), sizeof(Index) * static_cast<size_t>(a.nonZeros()));
  mix(a.valuePtr(), sizeof(double) * static_cast<size_t>(a.nonZeros()));
  return hash == 0 ? 1 : hash;
}

/// Spectra's tolerance for the bounds. The margins (1% by default) dwarf the error of a Ritz
/// value with relative residual 1e-3: on the armadillo's finest level λ_max = 2.2180109 after
/// 51 products at 1e-3, 2.2180121 after 81 at 1e-6 (an underestimate beyond the margin would
/// show as a diverging solve, which fails loudly).
EigenSolverOptions BoundsEstimateOptions() {
  EigenSolverOptions options;
  options.tolerance = 1e-3;
  return options;
}

constexpr EnumNames<ChebyshevSolver::LowerBound, 3> kLowerBoundNames = {{
    {ChebyshevSolver::LowerBound::kAuto, "auto"},
    {ChebyshevSolver::LowerBound::kBudget, "budget"},
    {ChebyshevSolver::LowerBound::kShiftInvert, "shift_invert"},
}};

}  // namespace

ChebyshevSolver::Options ChebyshevSolver::Options::FromConfig(OptionReader node) {
  return iterative::ReadIterativeOptions<Options>(node, "Chebyshev step", [&](Options& options) {
    options.lower_bound = node.GetEnum(
        "lower_bound", options.lower_bound, kLowerBoundNames,
        "λ_lo: budget = λ_hi / max_iterations² (no factorization; damps what k steps can damp); "
        "shift_invert = smallest eigenvalue of D^-1/2 A D^-1/2 by Spectra's shift-invert mode "
        "(costs a Cholesky factorization); auto = budget if tolerance is 0, else shift_invert");
    options.upper_margin =
        node.Get("upper_margin", options.upper_margin,
                 "safety margin on λ_max: λ_hi = min((1 + upper_margin) λ_max, Gershgorin bound)",
                 Range::AtLeast(0.0));
    options.lower_margin =
        node.Get("lower_margin", options.lower_margin,
                 "with shift_invert: λ_lo = (1 − lower_margin) λ_min", Range::HalfOpen(0.0, 1.0));
  });
}

void ChebyshevSolver::Prepare(const Context& context) {
  if (a_.rows() == 0) return;
  LowerBound lower_bound = options_.lower_bound;
  if (lower_bound == LowerBound::kAuto) {
    lower_bound = options_.limits.tolerance > 0.0 ? LowerBound::kShiftInvert : LowerBound::kBudget;
  }
  const uint64_t hash = MatrixHash(a_);
  if (hash != matrix_hash_) {
    matrix_hash_ = 0;
    Bounds bounds;
    try {
      bounds.estimate = ComputeExtremeEigenvalues(a_, SpectrumScaling::kJacobi,
                                                  lower_bound == LowerBound::kShiftInvert
                                                      ? SmallestEigenvalue::kShiftInvert
                                                      : SmallestEigenvalue::kSkip,
                                                  BoundsEstimateOptions(), context);
    } catch (const NumericalError& error) {
      throw NumericalError(fmt::format("chebyshev: {}", error.what()));
    }
    bounds.gershgorin = GershgorinUpperBound(a_, SpectrumScaling::kJacobi);
    bounds.upper =
        std::min((1.0 + options_.upper_margin) * bounds.estimate.largest, bounds.gershgorin);
    if (lower_bound == LowerBound::kShiftInvert) {
      bounds.lower = (1.0 - options_.lower_margin) * bounds.estimate.smallest;
    } else {
      const double k = options_.limits.max_iterations;
      bounds.lower = bounds.upper / (k * k);
    }
    HARAP_CHECK(bounds.lower > 0.0 && bounds.upper >= bounds.lower,
                "invalid Chebyshev interval [{}, {}]", bounds.lower, bounds.upper);
    bounds_ = bounds;
    matrix_hash_ = hash;
  }
}

template <int K>
SolveSummary ChebyshevSolver::SolveGathered(const double* b, double* x, Eigen::Index /*first*/) {
  const Index n = static_cast<Index>(a_.rows());
  double* r = r_.Reserve(n, K);
  double* d = d_.Reserve(n, K);
  double* d_next = d_next_.Reserve(n, K);
  const double* inverse_diagonal = inverse_diagonal_.data();

  // A single-point interval (D⁻¹A = c·I) makes δ = 0: then one step x += D⁻¹r/θ is exact.
  const double theta = 0.5 * (bounds_.upper + bounds_.lower);
  const double delta = std::max(0.5 * (bounds_.upper - bounds_.lower), 1e-300);
  const double sigma = theta / delta;
  double rho = 1.0 / sigma;

  // r₀ = b − A x₀, d₀ = D⁻¹ r₀ / θ.
  const auto start = SumRows<2>(n, [&](Index i, auto& sums) {
    double ax[K];
    RowProduct<K>(a_, i, x, ax);
    for (int c = 0; c < K; ++c) {
      const double ri = b[i * K + c] - ax[c];
      r[i * K + c] = ri;
      d[i * K + c] = inverse_diagonal[i] * ri / theta;
      sums[0][c] += b[i * K + c] * b[i * K + c];
      sums[1][c] += ri * ri;
    }
  });
  iterative::ColumnConvergence convergence(K, start[0], start[1], options_.limits.tolerance);

  SolveSummary summary;
  std::array<bool, 3> active{};
  while (convergence.any_active() && summary.iterations < options_.limits.max_iterations) {
    for (int c = 0; c < K; ++c) active[c] = convergence.active(c);
    const double rho_next = 1.0 / (2.0 * sigma - rho);
    const double keep = rho_next * rho;
    const double gain = 2.0 * rho_next / delta;
    // One pass: A d_k (neighbours' d_k from the old buffer), x, r, d_{k+1} of row i, ‖r‖².
    const ColumnValues rr = SumRows<1>(n, [&](Index i, auto& sums) {
      double ad[K];
      RowProduct<K>(a_, i, d, ad);
      for (int c = 0; c < K; ++c) {
        if (!active[c]) continue;
        x[i * K + c] += d[i * K + c];
        const double ri = r[i * K + c] - ad[c];
        r[i * K + c] = ri;
        d_next[i * K + c] = keep * d[i * K + c] + gain * inverse_diagonal[i] * ri;
        sums[0][c] += ri * ri;
      }
    })[0];
    std::swap(d, d_next);
    rho = rho_next;
    ++summary.iterations;
    if (!convergence.Update(rr)) {
      summary.outcome = SolveOutcome::kFailed;
      summary.message = iterative::DivergenceMessage(
          "chebyshev", summary.iterations,
          fmt::format("the eigenvalue interval [{:.6g}, {:.6g}] does not contain the spectrum of "
                      "D⁻¹A (raise upper_margin), or the matrix is not positive definite",
                      bounds_.lower, bounds_.upper));
      break;
    }
  }
  if (summary.success()) summary.outcome = iterative::BlockOutcome(convergence);
  summary.relative_residual = convergence.max_relative_residual();
  return summary;
}

template class iterative::BlockIterativeSolver<ChebyshevSolver>;
template class iterative::MatrixIterativeSolver<ChebyshevSolver>;

}  // namespace harap
