// SPDX-License-Identifier: MIT
#pragma once

#include <vector>

#include "framework/types.h"

namespace harap {

/// A numeric supernodal LLᵀ factor of P A Pᵀ in CHOLMOD's layout: supernode s holds the columns
/// [first[s], first[s+1]) as one dense column-major block at value + value_start[s] whose rows are
/// row[row_start[s] .. row_start[s+1]) (sorted, its own columns first); the upper triangle of the
/// diagonal block is not used. The view does not own the arrays.
struct SupernodalFactorView {
  int n = 0;
  int num_supernodes = 0;
  const int* first = nullptr;        ///< num_supernodes + 1 column offsets
  const int* row_start = nullptr;    ///< num_supernodes + 1 offsets into `row`
  const int* value_start = nullptr;  ///< num_supernodes + 1 offsets into `value`
  const int* row = nullptr;
  double* value = nullptr;
  const int* permutation = nullptr;  ///< row k of P A Pᵀ is row permutation[k] of A; may be null
};

/// Partial numeric refactorization of a supernodal Cholesky factor after A changed in a few rows
/// and columns (the handle edits of an interactive session), keeping the analysis and every
/// column of L the change cannot reach.
///
/// Why it is exact: with C the changed columns (factor order), column j of L depends on A(:, j)
/// and on the columns k < j with L(j, k) ≠ 0, which are j's descendants in the elimination tree.
/// So the columns that change are C and its ancestors (closed upwards), and in every other
/// column k only the entries in rows of C can change (the rest of column k is computed from
/// columns that are not ancestors of C either). Refactor() therefore recomputes (left-looking,
/// with BLAS, as CHOLMOD's supernodal factorization does) the supernodes on the elimination-tree
/// paths from C to the roots and the supernodes with a row in C, from A and from the kept
/// values of all other supernodes; the rest of the factor is left as it is.
///
/// What it saves: on a mesh the paths to the root hold the large separator supernodes, so a
/// local edit still recomputes a large share of the work: Mark() returns it (measured on
/// armadillo-bend's finest level, AMD: 40–45% of the flops for balls of 17 to 1,729 vertices,
/// docs/session.md).
class PartialSupernodalFactor {
 public:
  /// Prepares for a factor with this structure (the supernodal tree, each supernode's work).
  void Setup(const SupernodalFactorView& factor);
  bool ready() const { return !parent_.empty() || num_supernodes_ == 0; }

  /// Marks the supernodes that a change of the rows and columns `changed` (factor order) of
  /// P A Pᵀ reaches (see the class comment) and returns their share of the factorization's
  /// work (flops of the left-looking factorization counted per target supernode).
  double Mark(const SupernodalFactorView& factor, const std::vector<int>& changed);
  int marked_supernodes() const { return marked_count_; }
  /// The marked supernodes' flops (as counted for Mark()).
  double marked_work() const { return marked_work_; }
  const std::vector<char>& marked() const { return marked_; }

  /// Recomputes the marked supernodes of `factor` for `a` (full symmetric storage, same pattern
  /// as the factored matrix; `inverse_permutation[r]` = the factor column of row r of A).
  /// Returns -1, or the first factor column whose pivot was not positive (the factor is then
  /// partly updated; factor again).
  int Refactor(const SupernodalFactorView& factor, const SparseMatrix& a,
               const std::vector<int>& inverse_permutation);

 private:
  int n_ = 0;
  int num_supernodes_ = 0;
  std::vector<int> parent_;        ///< supernodal elimination tree (-1: root)
  std::vector<int> supernode_of_;  ///< per column
  std::vector<double> work_;       ///< flops per target supernode
  double total_work_ = 0.0;
  std::vector<char> marked_;
  int marked_count_ = 0;
  double marked_work_ = 0.0;
  // Refactor() workspaces.
  std::vector<int> head_, next_, position_, map_;
  std::vector<double> update_;
};

}  // namespace harap
