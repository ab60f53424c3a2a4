// SPDX-License-Identifier: MIT
#include "solvers/linear/spectral_bounds.h"

#include <Spectra/SymEigsShiftSolver.h>
#include <Spectra/SymEigsSolver.h>
#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <memory>

#include "framework/config.h"
#include "framework/error.h"
#include "solvers/linear/eigen_ldlt_solver.h"
#include "solvers/linear/iterative_kernels.h"
#include "solvers/linear/solver_checks.h"
#ifdef HARAP_HAVE_CHOLMOD
#include "solvers/linear/cholmod_solver.h"
#endif

namespace harap {

namespace {

/// The diagonal scaling s of B = S A S (S = diag s): all ones, or D^{-1/2}.
Eigen::VectorXd ScalingVector(const SparseMatrix& a, SpectrumScaling scaling) {
  if (scaling == SpectrumScaling::kNone) return Eigen::VectorXd::Ones(a.rows());
  return solver_checks::PositiveDiagonal(a, "spectral bounds").cwiseSqrt().cwiseInverse();
}

/// y = S A S x for Spectra (one vector at a time, rows in parallel).
class ScaledProduct {
 public:
  using Scalar = double;
  ScaledProduct(const SparseMatrix& a, const Eigen::VectorXd& s) : a_(a), s_(s), sx_(a.rows()) {}
  Eigen::Index rows() const { return a_.rows(); }
  Eigen::Index cols() const { return a_.cols(); }
  void perform_op(const double* x, double* y) const {
    const Index n = static_cast<Index>(a_.rows());
    iterative::ForRows(n, [&](Index i) { sx_[i] = s_[i] * x[i]; });
    iterative::ForRows(n, [&](Index i) {
      double ax;
      iterative::RowProduct<1>(a_, i, sx_.data(), &ax);
      y[i] = s_[i] * ax;
    });
    ++products_;
  }
  long long products() const { return products_; }

 private:
  const SparseMatrix& a_;
  const Eigen::VectorXd& s_;
  mutable Eigen::VectorXd sx_;
  mutable long long products_ = 0;
};

/// y = (S A S)⁻¹ x = S⁻¹ A⁻¹ S⁻¹ x with a factored A, for Spectra's shift-invert mode (σ = 0).
class ScaledInverse {
 public:
  using Scalar = double;
  ScaledInverse(LinearSolver& cholesky, const Eigen::VectorXd& s, const Context& context)
      : cholesky_(cholesky), s_(s), context_(context), rhs_(s.size(), 1), x_(s.size(), 1) {}
  Eigen::Index rows() const { return s_.size(); }
  Eigen::Index cols() const { return s_.size(); }
  void set_shift(double sigma) {
    HARAP_CHECK(sigma == 0.0, "only σ = 0 is supported, got {}", sigma);
  }
  void perform_op(const double* x, double* y) const {
    const Eigen::Index n = s_.size();
    for (Eigen::Index i = 0; i < n; ++i) rhs_(i, 0) = x[i] / s_[i];
    const SolveSummary summary = cholesky_.Solve(rhs_, x_, context_);
    if (!summary.success()) throw NumericalError("spectral bounds: " + summary.message);
    for (Eigen::Index i = 0; i < n; ++i) y[i] = x_(i, 0) / s_[i];
    ++solves_;
  }
  long long solves() const { return solves_; }

 private:
  LinearSolver& cholesky_;
  const Eigen::VectorXd& s_;
  const Context& context_;
  mutable Eigen::MatrixXd rhs_;
  mutable Eigen::MatrixXd x_;
  mutable long long solves_ = 0;
};

/// A sparse Cholesky of `a` for shift-invert (CHOLMOD when built with it). Throws NumericalError
/// (not positive definite) from the factorization.
std::unique_ptr<LinearSolver> FactorCholesky(const SparseMatrix& a, const Context& context) {
  std::unique_ptr<LinearSolver> solver;
#ifdef HARAP_HAVE_CHOLMOD
  solver = std::make_unique<CholmodSolver>(CholmodSolver::Options{});
#else
  solver = std::make_unique<EigenLdltSolver>(EigenLdltSolver::Options{});
#endif
  solver->Factorize(a, context);
  return solver;
}

Eigen::Index BasisSize(int vectors, Eigen::Index n) {
  return std::clamp<Eigen::Index>(vectors, 3, n);
}

/// Largest eigenvalue of S A S by Lanczos. Without convergence the best Ritz value is still an
/// inner estimate (≤ λ_max); Spectra only reports converged values, so then one more cycle with
/// an infinite tolerance reads it.
double LanczosLargest(const ScaledProduct& op, const EigenSolverOptions& options, bool& converged) {
  const Spectra::SortRule selection = Spectra::SortRule::LargestAlge;
  Spectra::SymEigsSolver<ScaledProduct> eigs(const_cast<ScaledProduct&>(op), 1,
                                             BasisSize(options.lanczos_vectors, op.rows()));
  eigs.init();
  eigs.compute(selection, options.max_restarts, options.tolerance);
  if (eigs.info() == Spectra::CompInfo::Successful) return eigs.eigenvalues()[0];
  converged = false;
  // One more restart cycle with an infinite tolerance marks the current Ritz value converged.
  eigs.compute(selection, 1, std::numeric_limits<double>::infinity());
  HARAP_CHECK(eigs.info() == Spectra::CompInfo::Successful, "Spectra returned no Ritz value");
  return eigs.eigenvalues()[0];
}

/// Smallest eigenvalue of S A S by shift-invert with the factored A.
double ShiftInvertSmallest(const ScaledInverse& op, const EigenSolverOptions& options,
                           bool& converged) {
  Spectra::SymEigsShiftSolver<ScaledInverse> eigs(
      const_cast<ScaledInverse&>(op), 1, BasisSize(options.shift_invert_vectors, op.rows()), 0.0);
  eigs.init();
  eigs.compute(Spectra::SortRule::LargestMagn, options.max_restarts, options.tolerance);
  if (eigs.info() == Spectra::CompInfo::Successful) return eigs.eigenvalues()[0];
  converged = false;
  eigs.compute(Spectra::SortRule::LargestMagn, 1, std::numeric_limits<double>::infinity());
  HARAP_CHECK(eigs.info() == Spectra::CompInfo::Successful, "Spectra returned no Ritz value");
  return eigs.eigenvalues()[0];
}

ExtremeEigenvalues DenseExtremes(const SparseMatrix& a, const Eigen::VectorXd& s) {
  const Stopwatch clock;
  ExtremeEigenvalues result;
  result.dense = true;
  if (a.rows() == 0) return result;
  const Eigen::MatrixXd scaled = s.asDiagonal() * Eigen::MatrixXd(a) * s.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(scaled, Eigen::EigenvaluesOnly);
  HARAP_CHECK(eigen.info() == Eigen::Success, "dense eigenvalue computation failed");
  result.smallest = eigen.eigenvalues()[0];
  result.largest = eigen.eigenvalues()[a.rows() - 1];
  result.seconds = clock.Seconds();
  return result;
}

void CheckPositive(double eigenvalue, Eigen::Index rows) {
  if (eigenvalue > 0.0 && std::isfinite(eigenvalue)) return;
  throw NumericalError(fmt::format(
      "spectral bounds: the {}×{} matrix is not positive definite (it has the eigenvalue {:.6g}). "
      "{}",
      rows, rows, eigenvalue, solver_checks::kNotPositiveDefiniteAdvice));
}

}  // namespace

ExtremeEigenvalues ComputeExtremeEigenvalues(const SparseMatrix& a_in, SpectrumScaling scaling,
                                             SmallestEigenvalue smallest,
                                             const EigenSolverOptions& options,
                                             const Context& context) {
  HARAP_CHECK(a_in.rows() == a_in.cols(), "matrix is {}×{}, not square", a_in.rows(), a_in.cols());
  const Stopwatch clock;
  const SparseMatrix a = iterative::CompressedCopy(a_in);
  const Eigen::VectorXd s = ScalingVector(a, scaling);
  ExtremeEigenvalues result;
  if (a.rows() <= kDenseSpectrumLimit) {
    result = DenseExtremes(a, s);
    if (smallest == SmallestEigenvalue::kSkip) result.smallest = 0.0;
  } else {
    context.Run([&] {
      const ScaledProduct product(a, s);
      result.largest = LanczosLargest(product, options, result.converged);
      result.products = product.products();
      if (smallest == SmallestEigenvalue::kShiftInvert) {
        const auto cholesky = FactorCholesky(a, context);
        const ScaledInverse inverse(*cholesky, s, context);
        result.smallest = ShiftInvertSmallest(inverse, options, result.converged);
        result.solves = inverse.solves();
      }
    });
  }
  if (a.rows() > 0) {
    CheckPositive(result.largest, a.rows());
    if (smallest == SmallestEigenvalue::kShiftInvert) CheckPositive(result.smallest, a.rows());
  }
  result.seconds = clock.Seconds();
  return result;
}

SystemSpectrum AnalyzeSystemSpectrum(const SparseMatrix& a_in, const EigenSolverOptions& options,
                                     const Context& context) {
  HARAP_CHECK(a_in.rows() == a_in.cols(), "matrix is {}×{}, not square", a_in.rows(), a_in.cols());
  const Stopwatch clock;
  SystemSpectrum spectrum;
  const SparseMatrix a = iterative::CompressedCopy(a_in);
  const Eigen::VectorXd ones = ScalingVector(a, SpectrumScaling::kNone);
  const Eigen::VectorXd jacobi = ScalingVector(a, SpectrumScaling::kJacobi);
  if (a.rows() <= kDenseSpectrumLimit) {
    spectrum.matrix = DenseExtremes(a, ones);
    spectrum.jacobi = DenseExtremes(a, jacobi);
  } else {
    context.Run([&] {
      const auto cholesky = FactorCholesky(a, context);
      for (const auto& [s, result] :
           {std::pair{&ones, &spectrum.matrix}, std::pair{&jacobi, &spectrum.jacobi}}) {
        const Stopwatch part;
        const ScaledProduct product(a, *s);
        result->largest = LanczosLargest(product, options, result->converged);
        const ScaledInverse inverse(*cholesky, *s, context);
        result->smallest = ShiftInvertSmallest(inverse, options, result->converged);
        result->products = product.products();
        result->solves = inverse.solves();
        result->seconds = part.Seconds();
      }
    });
  }
  spectrum.seconds = clock.Seconds();
  return spectrum;
}

double GershgorinUpperBound(const SparseMatrix& a_in, SpectrumScaling scaling) {
  const SparseMatrix a = iterative::CompressedCopy(a_in);
  const Eigen::VectorXd s = ScalingVector(a, scaling);
  double bound = 0.0;
  for (Index i = 0; i < a.outerSize(); ++i) {
    double row = 0.0;
    for (SparseMatrix::InnerIterator it(a, i); it; ++it) {
      row += std::abs(it.value()) * s[it.row()] * s[i];
    }
    bound = std::max(bound, row);
  }
  return bound;
}

}  // namespace harap
