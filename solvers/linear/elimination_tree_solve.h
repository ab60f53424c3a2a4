// SPDX-License-Identifier: MIT
#pragma once

#include <Eigen/Dense>
#include <cstdint>
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
  const int* permutation = nullptr;  ///< row k of P A Pᵀ is row permutation[k] of A; may be null
};

/// Solves A X = B with a simplicial LDLᵀ factor by forward and backward substitution that runs
/// independent subtrees of the elimination tree on different threads.
///
/// Why: the global step solves with the same factor hundreds of times, three columns at once, and
/// a single-threaded triangular solve is the largest part of an iteration on large meshes
/// (docs/benchmarks.md, "One classic iteration"). Columns in disjoint subtrees of the elimination
/// tree never touch each other's unknowns. After a post-ordered analysis (CHOLMOD's default)
/// every subtree is a contiguous column range, and so is every chain of the tree (a column whose
/// parent has no other child). Setup() cuts the tree into blocks: leaf subtrees small enough to
/// balance the threads, and the chains above them (the separators of a nested dissection). Blocks
/// form a tree; sibling blocks run in parallel, recursively, so only the root chain is
/// inherently sequential (each level of a nested dissection holds a similar share of the factor,
/// so a fixed "sequential top" would cost a lot).
///
/// Both passes are column-oriented and read the factor in place (no transposed copy). Updates of
/// a block's columns to rows above the block go to slots owned by the block (Setup() renumbers
/// those row indices once), so sibling blocks never write to the same place:
///
///   forward  L z = P b:  a block, after its children: its rows += the slots aimed at them (fixed
///                        order), then its columns in ascending order;
///   backward Lᵀ w = D⁻¹ z: a block, before its children: its slots := the finished rows they
///                        stand for, then its columns in descending order;   x = Pᵀ w.
///
/// The result does not depend on the scheduling, nor on the thread count up to 8 threads (the cut
/// is the same): every entry is summed in an order fixed by the factor. Solve() is
/// allocation-free after its first call with a given column count.
class EliminationTreeSolve {
 public:
  /// Cuts the factor's elimination tree into blocks for `num_threads` threads and renumbers the
  /// rows the blocks update outside themselves. The factor's values and offsets are used in place
  /// and must outlive this object (or the next Setup()). Throws InternalError if the factor is not
  /// a unit-lower LDLᵀ with positive pivots and the diagonal first in each column.
  void Setup(const LdltFactorView& factor, int num_threads);

  /// After the factor's values changed in place (same arrays, same pattern, e.g. a row
  /// update/downdate): takes the new pivots, keeping the cut and the renumbered rows. O(n).
  /// Throws InternalError like Setup() if a pivot is not positive.
  void RefreshPivots();

  /// The same for a factor in other arrays: if `factor` has the pattern Setup() saw (compared by
  /// size and a 64-bit hash of its offsets, counts and rows), solves with its arrays from now on
  /// and refreshes the pivots; returns false (and changes nothing) otherwise. A numeric
  /// refactorization with the same analysis produces the same pattern, and this saves the cut.
  bool Rebind(const LdltFactorView& factor);

  void Solve(const Eigen::Ref<const Eigen::MatrixXd>& b, Eigen::Ref<Eigen::MatrixXd> x,
             const Context& context);

  Index rows() const { return n_; }
  int num_blocks() const { return static_cast<int>(blocks_.size()); }
  /// The heaviest root-to-leaf path of the block tree as a fraction of all work: the part no
  /// number of threads can shorten (for benchmarks and tests).
  double critical_path_fraction() const { return critical_path_fraction_; }

 private:
  struct Block {
    Index begin = 0, end = 0;                  ///< its columns
    int children_begin = 0, children_end = 0;  ///< into block_children_
    int slots_begin = 0, slots_end = 0;        ///< its slots (they stand for rows ≥ end)
    int gather_begin = 0, gather_end = 0;      ///< into gather_slot_: slots aimed at its rows
  };

  struct Tree;  // elimination_tree_solve.cpp

  // Setup()'s steps: the tree of factor_ (and the pivots); the cut into blocks (block_of: each
  // column's block); the block tree and its critical path; the slots and their gather order.
  Tree ReadTree();
  void MakeBlocks(const Tree& tree, int num_threads, std::vector<int>& block_of);
  void LinkBlocks(const Tree& tree, const std::vector<int>& block_of);
  void AssignSlots(const std::vector<int>& block_of);

  template <int kColumns>
  void SolveInPlace(int columns, const Context& context);

  Index n_ = 0;
  LdltFactorView factor_;
  // Row index of each factor entry (same positions as factor_.value); entries in rows outside
  // their column's block hold n_ + the block's slot for that row.
  std::vector<int> row_;
  std::vector<double> inverse_pivot_;
  std::vector<int> permutation_;
  std::vector<Block> blocks_;
  std::vector<int> block_children_, root_blocks_;
  std::vector<int> slot_row_;     ///< the row each slot stands for
  std::vector<int> gather_slot_;  ///< per block, sorted by (row, slot)
  double critical_path_fraction_ = 0.0;
  std::uint64_t pattern_hash_ = 0;
  // Solve workspace: the permuted right-hand side (n_ rows) and the slots, row-major.
  std::vector<double> work_;
};

}  // namespace harap
