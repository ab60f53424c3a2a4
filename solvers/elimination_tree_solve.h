// SPDX-License-Identifier: MIT
#pragma once

#include <Eigen/Dense>

#include <vector>

#include "framework/context.h"
#include "framework/types.h"

namespace harap {

/// A simplicial LDLᵀ factor of P A Pᵀ in compressed-column form, as CHOLMOD stores it: column j
/// holds its diagonal entry d_j first, then the entries L_ij (i > j) of the unit lower triangle.
/// The view does not own the arrays.
struct LdltFactorView {
  Index n = 0;
  const int* column_start = nullptr;  ///< n+1 offsets (the column's entries start here)
  const int* column_count = nullptr;  ///< n counts (entries may be followed by unused slack)
  const int* row = nullptr;
  const double* value = nullptr;
  const int* permutation = nullptr;   ///< row k of P A Pᵀ is row permutation[k] of A; may be null
};

/// Solves A X = B with a simplicial LDLᵀ factor by forward and backward substitution that runs
/// independent subtrees of the elimination tree on different threads.
///
/// Why: the global step solves with the same factor hundreds of times, three columns at once, and
/// a single-threaded triangular solve is the largest part of an iteration on large meshes
/// (armadillo, 173K vertices: 31 ms of ~65 ms). Columns in disjoint subtrees of the elimination
/// tree never touch each other's unknowns, so after a fill-reducing, post-ordered analysis
/// (CHOLMOD's default) each subtree is a contiguous index range that one thread can solve alone;
/// only the columns above the chosen subtrees (the top separators) remain sequential.
///
///   forward  L z = P b:  row-oriented inside each subtree (a row reads only its descendants),
///                        then the top rows: their sums over subtree columns in parallel, the
///                        top-to-top part in order;
///   backward Lᵀ w = D⁻¹ z: the top columns in reverse order (they read only top ancestors), then
///                        each subtree in parallel;   x = Pᵀ w.
///
/// The result does not depend on the scheduling, nor on the thread count up to 8 threads: every
/// entry is summed by one thread in an order fixed by the factor. Setup() copies the factor (a transposed copy for the forward pass);
/// Solve() is allocation-free after its first call with a given column count.
class EliminationTreeSolve {
 public:
  /// Copies the factor and splits its elimination tree into independent subtrees for
  /// `num_threads` threads. Throws InternalError if the factor is not a valid unit-lower LDLᵀ
  /// with positive pivots.
  void Setup(const LdltFactorView& factor, int num_threads);

  void Solve(const Eigen::Ref<const Eigen::MatrixXd>& b, Eigen::Ref<Eigen::MatrixXd> x,
             const Context& context);

  Index rows() const { return n_; }
  /// Fraction of the factor's entries solved sequentially (top of the tree), for benchmarks.
  double sequential_fraction() const { return sequential_fraction_; }
  int num_subtrees() const { return static_cast<int>(subtrees_.size()); }

 private:
  struct ColumnRange {
    Index begin = 0;  ///< first column of the subtree (its first descendant)
    Index end = 0;    ///< one past its root
  };

  template <int kColumns>
  void SolveInPlace(int columns, const Context& context);

  Index n_ = 0;
  // Strictly lower L, by column (backward pass) and by row (forward pass).
  std::vector<int> column_start_, column_row_;
  std::vector<double> column_value_;
  std::vector<int> row_start_, row_column_;
  std::vector<double> row_value_;
  // For top rows, row entries from subtree columns come first and end at row_top_begin_[k] (k =
  // position of the row in top_); the rest are top columns.
  std::vector<int> row_top_begin_;
  std::vector<double> inverse_pivot_;
  std::vector<int> permutation_;
  std::vector<ColumnRange> subtrees_;  ///< independent, largest first
  std::vector<Index> top_;             ///< columns outside all subtrees, ascending
  double sequential_fraction_ = 0.0;
  // Solve workspace: the permuted right-hand side, row-major (the columns of a row together).
  std::vector<double> work_;
};

}  // namespace harap
