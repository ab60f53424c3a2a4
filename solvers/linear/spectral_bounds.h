// SPDX-License-Identifier: MIT
#pragma once

// Extreme eigenvalues of a sparse SPD matrix with Spectra [Qiu, Spectra: C++ library for large
// scale eigenvalue problems], for the chebyshev solver's bounds and for `harap deform
// --diagnostics`. Not a component: a function library of the solvers module.

#include <string_view>

#include "framework/context.h"
#include "framework/types.h"

namespace harap {

/// Which matrix's spectrum: A itself, or the Jacobi-preconditioned D^{-1/2} A D^{-1/2}
/// (D = diag A; same eigenvalues as D⁻¹A, the matrix Jacobi, Chebyshev–Jacobi and Jacobi-PCG
/// iterate with).
enum class SpectrumScaling { kNone, kJacobi };

/// Whether to find the smallest eigenvalue too (the largest is always found, by Lanczos).
enum class SmallestEigenvalue {
  /// Lanczos on the inverse (Spectra's shift-invert mode at σ = 0), each product one solve with
  /// a sparse Cholesky factor of A (CHOLMOD, else Eigen's SimplicialLDLT). Converges in a few
  /// dozen solves because 1/λ_min is well separated; costs one factorization. (Lanczos on A
  /// itself is no alternative on meshes: their small eigenvalues are clustered, so it converges
  /// to λ_min only after far more products than a shift-invert run needs solves.)
  kShiftInvert,
  /// Skip it: `smallest` is left at 0 (for users that only need λ_max).
  kSkip,
};

struct EigenSolverOptions {
  /// Spectra's convergence test: Ritz residual ‖A y − θ y‖ < tolerance · |θ|.
  double tolerance = 1e-6;
  /// Lanczos basis size (Spectra's ncv) for λ_max: the top of a mesh matrix's spectrum is
  /// clustered, and a larger basis needs fewer products (armadillo, D^{-1/2} A D^{-1/2} to 1e-6:
  /// 81 products with 20 vectors, 117 with 8).
  int lanczos_vectors = 20;
  /// Basis size for shift-invert: 1/λ_min is well separated, so a small basis converges in one
  /// cycle (armadillo: 9 solves with 8 vectors, 21 with 20; same eigenvalue to 8 digits).
  int shift_invert_vectors = 8;
  /// Restarts (Spectra's maxit) before giving up.
  int max_restarts = 300;
};

/// The extreme eigenvalues and what finding them cost.
struct ExtremeEigenvalues {
  double smallest = 0.0;
  double largest = 0.0;
  /// Whether both Spectra runs met the tolerance (dense computation: always).
  bool converged = true;
  long long products = 0;  ///< Products with the matrix (Lanczos).
  long long solves = 0;    ///< Solves with the Cholesky factor (shift-invert).
  double seconds = 0.0;
  bool dense = false;  ///< Small matrices (≤ kDenseLimit rows) are solved densely.

  double condition_number() const { return largest / smallest; }
};

/// Matrices with at most this many rows are handled by Eigen's dense SelfAdjointEigenSolver
/// (Spectra needs nev < ncv ≤ n, and dense is exact and instant there).
inline constexpr Index kDenseSpectrumLimit = 200;

/// Extreme eigenvalues of the SPD matrix `a` (full symmetric storage) or of its Jacobi scaling.
/// Throws NumericalError if `a` has a non-positive diagonal entry (Jacobi scaling), its Cholesky
/// factorization fails (shift-invert) or an eigenvalue found is ≤ 0: it is not positive definite.
ExtremeEigenvalues ComputeExtremeEigenvalues(const SparseMatrix& a, SpectrumScaling scaling,
                                             SmallestEigenvalue smallest,
                                             const EigenSolverOptions& options,
                                             const Context& context);

/// Diagnostics of a global-step matrix: the extreme eigenvalues of A and of D^{-1/2} A D^{-1/2}
/// (shift-invert for both, sharing one Cholesky factorization).
struct SystemSpectrum {
  ExtremeEigenvalues matrix;
  ExtremeEigenvalues jacobi;
  double seconds = 0.0;  ///< Both, factorization included.
};
SystemSpectrum AnalyzeSystemSpectrum(const SparseMatrix& a, const EigenSolverOptions& options,
                                     const Context& context);

/// Gershgorin's bound max_i Σ_j |B_ij| ≥ λ_max(B) for B = A or its Jacobi scaling: a guaranteed
/// upper bound (for Laplacian-like matrices with Jacobi scaling it is close to λ_max ≈ 2).
double GershgorinUpperBound(const SparseMatrix& a, SpectrumScaling scaling);

}  // namespace harap
