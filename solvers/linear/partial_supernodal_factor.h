// SPDX-License-Identifier: MIT
#pragma once

#include <utility>
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
/// local edit still recomputes a large share of the work: Mark() returns it (the share measured
/// for small and large edits: docs/solvers.md, "Refactoring after handle edits", and
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
  /// The last FactorAll()'s independent subtrees (0: factored in order), their share of the
  /// work and the heaviest one's share.
  int subtrees() const { return subtrees_; }
  double subtree_work_fraction() const { return subtree_work_fraction_; }
  double largest_subtree_fraction() const { return largest_subtree_fraction_; }
  /// The marked supernodes' flops (as counted for Mark()).
  double marked_work() const { return marked_work_; }
  const std::vector<char>& marked() const { return marked_; }

  /// Recomputes the marked supernodes of `factor` for `a` (full symmetric storage, same pattern
  /// as the factored matrix; `inverse_permutation[r]` = the factor column of row r of A).
  /// Returns -1, or the first factor column whose pivot was not positive (the factor is then
  /// partly updated; factor again).
  int Refactor(const SupernodalFactorView& factor, const SparseMatrix& a,
               const std::vector<int>& inverse_permutation);

  /// The whole numeric factorization of `factor` (a supernodal analysis whose values need not be
  /// initialized) for `a`, arguments as Refactor()'s; runs Setup() first. Independent subtrees
  /// of the supernodal elimination tree are factored on up to `threads` threads of the calling
  /// arena, the supernodes above them in order afterwards.
  ///
  /// Bit-identical for every thread count, and to the sequential left-looking order (which is
  /// CHOLMOD's cholmod_super_numeric's: same values, tested): a supernode receives its
  /// descendants' updates in the order of the lists the sequential loop builds, because the
  /// subtrees keep their links to the supernodes above them in lists of their own that are
  /// spliced in where the sequential loop would have made them. Returns what Refactor() returns
  /// (the first failing column in that order).
  ///
  /// `thread_ready` (if set) is asked before each range of subtrees a thread takes, and may say
  /// no (e.g. no memory left for the BLAS's per-thread buffer): those subtrees are then factored
  /// by the calling thread, in order. The calling thread itself must be ready (the caller asks).
  int FactorAll(const SupernodalFactorView& factor, const SparseMatrix& a,
                const std::vector<int>& inverse_permutation, int threads,
                bool (*thread_ready)() = nullptr);

 private:
  // Per thread: the row map of the supernode being computed and the update block.
  struct Workspace {
    std::vector<int> map;
    std::vector<double> update;
  };
  // A subtree factored on its own (FactorAll): supernodes [begin, end) in postorder, and its
  // links to supernodes above the pieces (ancestor, descendant) in the order it made them.
  struct Piece {
    int begin = 0, end = 0;
    double work = 0.0;  ///< flops, as work_ counts them
    std::vector<std::pair<int, int>> links;
    bool factored = false;  ///< on its own (else by the calling thread, in order)
    int failed_column = -1;
  };
  // Factors (if `recompute`) supernode s after its descendants: what one step of the
  // left-looking loop does. Links into supernodes above the pieces go to `piece`'s own list.
  int FactorSupernode(int s, bool recompute, const SupernodalFactorView& f, const SparseMatrix& a,
                      const std::vector<int>& inverse_permutation, Workspace& workspace,
                      Piece* piece);
  void Link(int d, int ancestor, Piece* piece);
  // Empty left-looking lists and the caller's workspace, for a pass over the supernodes.
  void ResetLists();
  // Subtrees of at most about total/(4 threads) work each (none for one thread).
  std::vector<Piece> SplitIntoPieces(int threads);

  int n_ = 0;
  int num_supernodes_ = 0;
  std::vector<int> parent_;        ///< supernodal elimination tree (-1: root)
  std::vector<int> supernode_of_;  ///< per column
  std::vector<double> work_;       ///< flops per target supernode
  double total_work_ = 0.0;
  std::vector<char> marked_;
  int marked_count_ = 0;
  double marked_work_ = 0.0;
  // The left-looking lists and the caller's workspace (Refactor(), FactorAll(); ResetLists()).
  std::vector<int> head_, next_, position_, map_;
  Workspace workspace_;
  std::vector<char> above_pieces_;  ///< per supernode: 1 if above the pieces (FactorAll)
  int subtrees_ = 0;
  double subtree_work_fraction_ = 0.0;
  double largest_subtree_fraction_ = 0.0;
};

}  // namespace harap
