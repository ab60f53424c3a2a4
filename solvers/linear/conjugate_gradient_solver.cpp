// SPDX-License-Identifier: MIT
#include "solvers/linear/conjugate_gradient_solver.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "framework/error.h"
#include "solvers/linear/solver_checks.h"

namespace harap {

namespace {

using iterative::ColumnValues;
using iterative::ForRows;
using iterative::RowProduct;
using iterative::SumRows;

constexpr EnumNames<ConjugateGradientSolver::Preconditioner, 2> kPreconditionerNames = {{
    {ConjugateGradientSolver::Preconditioner::kJacobi, "jacobi"},
    {ConjugateGradientSolver::Preconditioner::kIncompleteCholesky, "incomplete_cholesky"},
}};

}  // namespace

ConjugateGradientSolver::Options ConjugateGradientSolver::Options::FromConfig(OptionReader node) {
  return iterative::ReadIterativeOptions<Options>(node, "CG iteration", [&](Options& options) {
    options.preconditioner = node.GetEnum(
        "preconditioner", options.preconditioner, kPreconditionerNames,
        "jacobi = diagonal scaling (parallel, fused into the vector updates); incomplete_cholesky "
        "= Eigen's threshold IC with AMD ordering (fewer iterations, sequential triangular "
        "solves)");
  });
}

void ConjugateGradientSolver::Prepare(const Context& /*context*/) {
  incomplete_cholesky_.reset();
  if (options_.preconditioner == Preconditioner::kIncompleteCholesky && a_.rows() > 0) {
    incomplete_cholesky_ = std::make_unique<IncompleteCholesky>();
    incomplete_cholesky_->compute(a_);
    if (incomplete_cholesky_->info() != Eigen::Success) {
      throw NumericalError(fmt::format(
          "cg: the incomplete Cholesky factorization of the {}×{} matrix failed even with "
          "diagonal shifts; use preconditioner = \"jacobi\". {}",
          a_.rows(), a_.rows(), solver_checks::kNotPositiveDefiniteAdvice));
    }
    // The triangular solves below expect each column of L to start with its diagonal entry.
    const SparseMatrix& l = incomplete_cholesky_->matrixL();
    for (Index j = 0; j < l.cols(); ++j) {
      HARAP_CHECK(l.outerIndexPtr()[j] < l.outerIndexPtr()[j + 1] &&
                      l.innerIndexPtr()[l.outerIndexPtr()[j]] == j,
                  "incomplete Cholesky column {} does not start with its diagonal", j);
    }
  }
}

template <int K>
void ConjugateGradientSolver::ApplyIncompleteCholesky(const double* r, double* z) {
  // Eigen factors S P A Pᵀ S ≈ L Lᵀ (P: AMD permutation, S: diagonal scaling in permuted order),
  // so M⁻¹ r = Pᵀ S L⁻ᵀ L⁻¹ S P r. The workspace w is in the permuted order.
  const IncompleteCholesky& ic = *incomplete_cholesky_;
  const SparseMatrix& l = ic.matrixL();
  const auto& perm = ic.permutationP().indices();
  const Eigen::VectorXd& scale = ic.scalingS();
  const Index n = static_cast<Index>(l.rows());
  double* w = w_.Reserve(n, K);
  ForRows(n, [&](Index i) {
    const Index pi = perm[i];
    for (int c = 0; c < K; ++c) w[pi * K + c] = scale[pi] * r[i * K + c];
  });
  const Index* outer = l.outerIndexPtr();
  const Index* inner = l.innerIndexPtr();
  const double* value = l.valuePtr();
  for (Index j = 0; j < n; ++j) {  // L y = w, column by column
    double* wj = w + j * K;
    const double inverse_pivot = 1.0 / value[outer[j]];
    for (int c = 0; c < K; ++c) wj[c] *= inverse_pivot;
    for (Index p = outer[j] + 1; p < outer[j + 1]; ++p) {
      double* wi = w + inner[p] * K;
      for (int c = 0; c < K; ++c) wi[c] -= value[p] * wj[c];
    }
  }
  for (Index j = n - 1; j >= 0; --j) {  // Lᵀ v = y; row j of Lᵀ is column j of L
    double sum[K];
    for (int c = 0; c < K; ++c) sum[c] = w[j * K + c];
    for (Index p = outer[j] + 1; p < outer[j + 1]; ++p) {
      const double* wi = w + inner[p] * K;
      for (int c = 0; c < K; ++c) sum[c] -= value[p] * wi[c];
    }
    const double inverse_pivot = 1.0 / value[outer[j]];
    for (int c = 0; c < K; ++c) w[j * K + c] = sum[c] * inverse_pivot;
  }
  ForRows(n, [&](Index i) {
    const Index pi = perm[i];
    for (int c = 0; c < K; ++c) z[i * K + c] = scale[pi] * w[pi * K + c];
  });
}

template <int K>
std::array<iterative::ColumnValues, 3> ConjugateGradientSolver::Start(const double* b,
                                                                      const double* x) {
  const Index n = static_cast<Index>(a_.rows());
  double* r = r_.Reserve(n, K);
  double* z = z_.Reserve(n, K);
  double* p = p_.Reserve(n, K);
  const bool jacobi = incomplete_cholesky_ == nullptr;
  const double* inverse_diagonal = inverse_diagonal_.data();
  // r = b − A x, and with Jacobi z = D⁻¹ r, p = z.
  auto start = SumRows<3>(n, [&](Index i, auto& sums) {
    double ax[K];
    RowProduct<K>(a_, i, x, ax);
    for (int c = 0; c < K; ++c) {
      const double ri = b[i * K + c] - ax[c];
      r[i * K + c] = ri;
      sums[0][c] += b[i * K + c] * b[i * K + c];
      sums[1][c] += ri * ri;
      if (jacobi) {
        const double zi = inverse_diagonal[i] * ri;
        z[i * K + c] = p[i * K + c] = zi;
        sums[2][c] += ri * zi;
      }
    }
  });
  if (!jacobi) {
    ApplyIncompleteCholesky<K>(r, z);
    start[2] = SumRows<1>(n, [&](Index i, auto& sums) {
      for (int c = 0; c < K; ++c) {
        p[i * K + c] = z[i * K + c];
        sums[0][c] += r[i * K + c] * z[i * K + c];
      }
    })[0];
  }
  return start;
}

template <int K>
void ConjugateGradientSolver::EstimateUnresolved(
    const iterative::ColumnConvergence& convergence, const ColumnValues& step_energy,
    const std::array<std::array<double, 2 * kUnresolvedWindow>, K>& last_terms, int iterations,
    Eigen::Index first) {
  // The terms after the last ones, extrapolated as a geometric series of blocks of
  // kUnresolvedWindow terms whose ratio is that of the last two blocks' sums (sums, not single
  // terms: CG's terms are not monotone).
  if (first == 0) unresolved_fraction_ = 0.0;
  const int m = iterations;
  constexpr int kRing = 2 * kUnresolvedWindow;
  if (m < kRing) return;
  for (int c = 0; c < K; ++c) {
    if (!convergence.active(c) || !(step_energy[c] > 0.0)) continue;
    double recent = 0.0, previous = 0.0;
    for (int j = 0; j < kUnresolvedWindow; ++j) {
      recent += last_terms[c][(m - 1 - j) % kRing];
      previous += last_terms[c][(m - 1 - kUnresolvedWindow - j) % kRing];
    }
    const double ratio = recent / previous;
    if (!(ratio < 1.0)) {  // not decaying (or no terms to compare)
      unresolved_fraction_ = 1.0;
      continue;
    }
    const double tail = recent * ratio / (1.0 - ratio);
    unresolved_fraction_ = std::max(unresolved_fraction_, tail / (tail + step_energy[c]));
  }
}

template <int K>
SolveSummary ConjugateGradientSolver::SolveGathered(const double* b, double* x,
                                                    Eigen::Index first) {
  const Index n = static_cast<Index>(a_.rows());
  const auto start = Start<K>(b, x);
  double* r = r_.data();
  double* z = z_.data();
  double* p = p_.data();
  double* q = q_.Reserve(n, K);
  const bool jacobi = incomplete_cholesky_ == nullptr;
  const double* inverse_diagonal = inverse_diagonal_.data();
  ColumnValues rz = start[2];
  iterative::ColumnConvergence convergence(K, start[0], start[1], options_.limits.tolerance);

  SolveSummary summary;
  // Per column: Σ α_j r_jᵀz_j so far (‖x_k − x₀‖²_A) and the last terms (unresolved_fraction()).
  ColumnValues step_energy{};
  std::array<std::array<double, 2 * kUnresolvedWindow>, K> last_terms{};
  while (convergence.any_active() && summary.iterations < options_.limits.max_iterations) {
    // q = A p and pᵀq, one pass over A for all columns.
    const ColumnValues pq = SumRows<1>(n, [&](Index i, auto& sums) {
      RowProduct<K>(a_, i, p, q + i * K);
      for (int c = 0; c < K; ++c) sums[0][c] += p[i * K + c] * q[i * K + c];
    })[0];
    ColumnValues alpha{};
    for (int c = 0; c < K; ++c) {
      if (!convergence.active(c)) continue;
      if (!(pq[c] > 0.0)) {
        summary.outcome = SolveOutcome::kFailed;
        summary.message = fmt::format(
            "cg: non-positive curvature pᵀAp = {:.3g} at iteration {} (column {}): the matrix "
            "is not positive definite. {}",
            pq[c], summary.iterations + 1, first + c, solver_checks::kNotPositiveDefiniteAdvice);
        break;
      }
      alpha[c] = rz[c] / pq[c];
      const double term = alpha[c] * rz[c];
      step_energy[c] += term;
      last_terms[c][summary.iterations % (2 * kUnresolvedWindow)] = term;
    }
    if (!summary.success()) break;

    // x += α p, r −= α q (and z = D⁻¹ r, rᵀz with Jacobi).
    const auto update = SumRows<2>(n, [&](Index i, auto& sums) {
      for (int c = 0; c < K; ++c) {
        x[i * K + c] += alpha[c] * p[i * K + c];
        const double ri = r[i * K + c] - alpha[c] * q[i * K + c];
        r[i * K + c] = ri;
        sums[0][c] += ri * ri;
        if (jacobi) {
          const double zi = inverse_diagonal[i] * ri;
          z[i * K + c] = zi;
          sums[1][c] += ri * zi;
        }
      }
    });
    ColumnValues rz_next = update[1];
    if (!jacobi) {
      ApplyIncompleteCholesky<K>(r, z);
      rz_next = SumRows<1>(n, [&](Index i, auto& sums) {
        for (int c = 0; c < K; ++c) sums[0][c] += r[i * K + c] * z[i * K + c];
      })[0];
    }
    ++summary.iterations;
    if (!iterative::RecordCgResiduals(convergence, update[0], "cg", summary)) break;
    if (!convergence.any_active()) break;
    ColumnValues beta{};
    for (int c = 0; c < K; ++c) {
      if (convergence.active(c)) beta[c] = rz_next[c] / rz[c];
      rz[c] = rz_next[c];
    }
    // p = z + β p for the columns still iterating (the others keep a finite p and α = 0).
    ForRows(n, [&](Index i) {
      for (int c = 0; c < K; ++c) {
        if (convergence.active(c)) p[i * K + c] = z[i * K + c] + beta[c] * p[i * K + c];
      }
    });
  }
  if (summary.success()) {
    EstimateUnresolved<K>(convergence, step_energy, last_terms, summary.iterations, first);
  } else if (first == 0) {
    unresolved_fraction_ = 0.0;
  }
  // The recurrence residual r_k drifts from b − A x_k (badly so on singular systems); report
  // the true one, for one more pass over A per solve.
  if (summary.success()) summary.outcome = iterative::BlockOutcome(convergence);
  summary.relative_residual = iterative::MaxRelativeResidual<K>(a_, b, x, start[0]);
  return summary;
}

template class iterative::BlockIterativeSolver<ConjugateGradientSolver>;
template class iterative::MatrixIterativeSolver<ConjugateGradientSolver>;

}  // namespace harap
