// SPDX-License-Identifier: MIT
#pragma once

#include <memory>
#include <string_view>
#include <vector>

#include "framework/config.h"
#include "framework/linear_solver.h"
#include "solvers/linear/iterative_kernels.h"

namespace harap {

/// Gauss–Seidel (or SOR with relaxation ω ≠ 1) sweeps on the reduced SPD system, warm-started
/// from `x`: row by row, x_i ← x_i + ω ((b_i − Σ_{j≠i} A_ij x_j) / A_ii − x_i). For SPD A and
/// 0 < ω < 2 every sweep decreases the A-norm of the error, whatever the row order.
///
/// Orderings: "colored" (default) colours the matrix graph greedily (rows of one colour share no
/// non-zero, so they are updated in parallel; 6–7 colours on the shared meshes) and sweeps
/// colour by colour — a valid Gauss–Seidel ordering, just not the natural one; "natural" sweeps
/// rows 0..n−1 sequentially (the textbook method, one thread); "blocks" cuts the rows into
/// blocks of `block_rows` consecutive rows, colours the graph of the blocks (two blocks are
/// coupled when a non-zero joins their rows) and sweeps colour by colour, the blocks of one colour
/// in parallel and the rows of a block in order (multicolour block Gauss–Seidel). On a matrix
/// whose rows follow a space-filling curve (the optimizers' locality ordering) a block is a patch
/// of the mesh and the sweep within it is the natural one: the multigrid solver, whose smoother
/// it is, needs one iteration fewer than with the row colouring (docs/solvers.md, "multigrid").
/// A symmetric sweep is a forward sweep followed by a backward one (SGS/SSOR: a symmetric
/// iteration; counts as one iteration).
///
/// Factorize() colours the graph and stores the rows colour by colour (off-diagonal entries and
/// inverse diagonal, permuted so that each colour is contiguous). Solve() runs max_iterations
/// sweeps, or stops earlier once every column reaches `tolerance` (then each sweep is followed by
/// one residual pass); the final relative residual ‖b − A x‖ / ‖b‖ is always computed (one extra
/// pass over A) and reported. Allocation-free after the first Solve() with a given column count.
/// A residual that grows by 1e8 proves A is not positive definite (for SPD A, ‖r‖ can grow by at
/// most √κ(A)): the solve fails with that message. Not thread-safe.
class GaussSeidelSolver final : public iterative::BlockIterativeSolver<GaussSeidelSolver> {
 public:
  static constexpr std::string_view kName = "gauss_seidel";

  enum class Sweep { kForward, kSymmetric };
  enum class Ordering { kColored, kNatural, kBlocks };

  struct Options {
    /// max_iterations: sweeps per solve (a cap when tolerance > 0). Default 10 forward sweeps
    /// per global step, no tolerance.
    iterative::IterationLimits limits{10, 0.0};
    Sweep sweep = Sweep::kForward;
    Ordering ordering = Ordering::kColored;
    /// ω: 1 is Gauss–Seidel, (1, 2) over-relaxes (SOR); must lie in (0, 2).
    double relaxation = 1.0;
    /// Rows per block of the blocks ordering (not used by the others): a patch of a few hundred
    /// vertices, which still leaves thousands of blocks per colour on a large mesh to share among
    /// the threads.
    Index block_rows = 512;
    /// Without a tolerance, one residual pass after the sweeps catches a diverging iteration
    /// (and gives relative_residual). Not a configuration key: the multigrid solver's smoothers
    /// turn it off, since its CG detects divergence itself and the pass would cost a third of
    /// each smoothing step (relative_residual is then 0 and the outcome kIterationLimit).
    bool check_without_tolerance = true;

    static Options FromConfig(OptionReader node);
  };

  explicit GaussSeidelSolver(const Options& options)
      : BlockIterativeSolver(kName), options_(options) {}

  const Options& options() const { return options_; }
  /// Colours of the last factorized matrix (1 for the natural ordering, of the blocks for
  /// blocks; 0 for an empty matrix).
  int num_colors() const { return static_cast<int>(color_begin_.size()) - 1; }

 private:
  void FactorizeImpl(const SparseMatrix& a, const Context& context) override;
  friend class iterative::BlockIterativeSolver<GaussSeidelSolver>;
  template <int K>
  SolveSummary SolveBlock(const Eigen::Ref<const Eigen::MatrixXd>& b, Eigen::Ref<Eigen::MatrixXd> x,
                          Eigen::Index first);
  template <int K>
  void RunSweep(const double* b, double* x, const std::array<bool, 3>& active, bool backward) const;
  template <int K>
  void UpdateRow(Index k, const double* b, double* x, const std::array<bool, 3>& active) const;
  template <int K>
  iterative::ColumnValues SquaredResidual(const double* b, const double* x) const;

  Options options_;
  // The matrix in sweep order: row k of the stored matrix is row order_[k] of A.
  std::vector<Index> order_;
  std::vector<Index> color_begin_;  ///< Rows [color_begin_[c], color_begin_[c+1]) share colour c.
  /// Rows per coloured group: 1 (colored), block_rows (blocks) or all rows (natural). Within a
  /// colour the groups are stored in order, each full but the last.
  Index block_rows_ = 1;
  std::vector<Index> offsets_;  ///< Off-diagonal entries of each row (CSR).
  std::vector<Index> columns_;  ///< In sweep order.
  std::vector<double> values_;
  std::vector<double> diagonal_;
  std::vector<double> inverse_diagonal_;
  iterative::Block b_, x_;
};

// SolveImpl() calls SolveBlock<K>, defined in the .cpp: instantiated there only.
extern template class iterative::BlockIterativeSolver<GaussSeidelSolver>;

}  // namespace harap
