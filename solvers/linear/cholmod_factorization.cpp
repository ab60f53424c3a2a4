// SPDX-License-Identifier: MIT
// Compiled into harap_solvers only when CHOLMOD was found (see cholmod_solver.cpp).
#ifdef HARAP_HAVE_CHOLMOD

#include "solvers/linear/cholmod_factorization.h"

#include <fmt/format.h>

#include <algorithm>
#include <new>
#include <string>

#include "framework/error.h"
#include "solvers/linear/blas_work_buffer.h"
#include "solvers/linear/cholmod_native_threads.h"
#include "solvers/linear/cholmod_views.h"
#include "solvers/linear/solver_checks.h"
#include "solvers/linear/sparse_pattern.h"

namespace harap {
namespace {

using cholmod_views::LowerTriangleView;
using cholmod_views::PatternView;

// cholmod_solve2 on a simplicial factor asks for Y as max(4, k)×n (it solves 4 columns at a
// time, row-major) and then reshapes Y's header to the columns of the last chunk (3×n for k = 3).
// On the next call the shapes differ and it frees and reallocates Y, on every solve. Putting the
// header back before each call (the buffer is unchanged and large enough) keeps Solve()
// allocation-free; if a CHOLMOD version asks for another shape, it simply reallocates.
void RestoreSimplicialWorkspaceShape(const cholmod_factor* factor, Eigen::Index columns,
                                     cholmod_dense* y) {
  if (factor->is_super || y == nullptr) return;
  const size_t rows = std::max<size_t>(4, static_cast<size_t>(columns));
  if (y->nzmax < rows * factor->n) return;
  y->nrow = rows;
  y->ncol = factor->n;
  y->d = rows;
}

std::string OutOfMemoryMessage(std::string_view stage, const cholmod_common& common,
                               const SparseMatrix& a, CholmodSolver::Ordering ordering) {
  // After the analysis CHOLMOD knows nnz(L); a simplicial factor stores a value and a row index
  // per entry (a supernodal one a little more, for its dense blocks).
  const std::string factor_size =
      common.lnz > 0 ? fmt::format("; its Cholesky factor has {:.3g} nonzeros (at least {:.0f} MB)",
                                   common.lnz, common.lnz * 12.0 / 1e6)
                     : std::string();
  const std::string less_fill = ordering == CholmodSolver::Ordering::kMetis
                                    ? std::string()
                                    : ", or ordering = \"metis\" (less fill than AMD on meshes)";
  return fmt::format(
      "cholmod: out of memory during the {} of a {}×{} matrix with {} nonzeros{}. "
      "{}{}, or a coarser mesh.",
      stage, a.rows(), a.cols(), a.nonZeros(), factor_size, solver_checks::kOutOfMemoryAdvice,
      less_fill);
}

}  // namespace

CholmodFactorization::CholmodFactorization(const Options& options) : options(options) {
  cholmod_start(&common);
  // Library code never prints: no messages, and errors come back through common.status.
  common.print = 0;
  common.error_handler = nullptr;
  // LDLᵀ for simplicial factors (CHOLMOD's default, kept explicit): no square roots, and the
  // pivots d_k are what the positive-definiteness check reads.
  common.final_ll = 0;
  switch (options.mode) {
    case Mode::kAuto:
      // Supernodal factorization, then converted by cholmod_factorize itself to a packed
      // simplicial LDLᵀ, re-symbolled so the explicit zeros of relaxed supernodes are dropped
      // (without final_resymbol the converted factor keeps them and its solves are slower:
      // docs/benchmarks.md).
      common.supernodal = CHOLMOD_SUPERNODAL;
      common.final_asis = 0;
      common.final_super = 0;
      common.final_pack = 1;
      common.final_monotonic = 1;
      common.final_resymbol = 1;
      break;
    case Mode::kSupernodal:
      common.supernodal = CHOLMOD_SUPERNODAL;
      break;
    case Mode::kSimplicial:
      common.supernodal = CHOLMOD_SIMPLICIAL;
      break;
  }
  switch (options.ordering) {
    case CholmodSolver::Ordering::kMetis:
      common.nmethods = 1;
      common.method[0].ordering = CHOLMOD_METIS;
      break;
    case CholmodSolver::Ordering::kAmd:
      common.nmethods = 1;
      common.method[0].ordering = CHOLMOD_AMD;
      break;
    case CholmodSolver::Ordering::kBest:
      common.nmethods = 0;
      break;  // AMD, then METIS if AMD fills a lot.
  }
  common.postorder = 1;
}

CholmodFactorization::~CholmodFactorization() {
  FreeFactor();
  FreeSymbolic();
  FreeAnalysis();
  FreeSuper();
  cholmod_free_dense(&x, &common);
  cholmod_free_dense(&y, &common);
  cholmod_free_dense(&e, &common);
  cholmod_finish(&common);
}

void CholmodFactorization::Factorize(const SparseMatrix& a, const Context& context) {
  factorized = false;
  use_tree_solve = false;
  FreeFactor();
  FreeSymbolic();
  FreeSuper();
  partial = PartialSupernodalFactor();
  info = CholmodSolver::FactorInfo{};
  matrix = SparseMatrix();
  rows = static_cast<int>(a.rows());
  if (rows == 0) {
    factorized = true;
    return;
  }

  // A diagonal entry ≤ 0 already rules out positive definiteness; the entries also scale the
  // pivot check.
  const Eigen::VectorXd diagonal = solver_checks::PositiveDiagonal(a, "cholmod");

  if (options.mode != Mode::kSimplicial && !EnsureBlasWorkBuffer()) {
    throw NumericalError(fmt::format(
        "cholmod: out of memory before the supernodal factorization of a {}×{} matrix: less "
        "than {} MiB of address space is left for BLAS's work buffer. Try mode = \"simplicial\" "
        "(no BLAS), or {}.",
        a.rows(), a.cols(), kBlasBufferProbeBytes >> 20,
        solver_checks::kOutOfMemoryAdvice.substr(4)));  // "an iterative solver ..."
  }
  const ScopedNativeThreads native_threads(options.native_threads);
  cholmod_sparse view = LowerTriangleView(a);
  factor = TakeOrMakeAnalysis(a);
  if (keeps_copies()) {
    const Stopwatch copy_clock;  // the copy for Refactor() counts as analysis too
    const size_t in_use = common.memory_inuse;
    symbolic = cholmod_copy_factor(factor, &common);
    ThrowOnFailure("copy of the analysis", a);
    info.refactor_bytes = static_cast<double>(common.memory_inuse - in_use) +
                          static_cast<double>(a.nonZeros()) * (sizeof(double) + sizeof(int)) +
                          static_cast<double>(a.cols() + 1) * sizeof(int);
    info.analysis_seconds += copy_clock.Seconds();
  }
  if (keeps_super() && factor->is_super) {
    FactorNumericKeepingSuper(view, a, context);
    info.refactor_bytes += static_cast<double>(super->xsize) * sizeof(double);
  } else {
    FactorNumeric(view, a, context);
  }
  FinishFactor(a, diagonal, context);
}

CholmodSolver::Estimate CholmodFactorization::Analyze(const SparseMatrix& a) {
  FreeAnalysis();
  CholmodSolver::Estimate estimate;
  if (a.rows() == 0) return estimate;
  const ScopedNativeThreads native_threads(options.native_threads);
  cholmod_sparse view = PatternView(a);
  const Stopwatch clock;
  analysis = cholmod_analyze(&view, &common);
  ThrowOnFailure("analysis (ordering)", a);
  HARAP_CHECK(analysis != nullptr, "cholmod_analyze returned no factor (status {})", common.status);
  estimate.analysis_seconds = clock.Seconds();
  estimate.nnz_l = common.lnz;
  estimate.flops = common.fl;
  // A simplicial factor stores a value and a row index per entry plus O(n) column data; the
  // supernodal factor of modes auto and supernodal pads relaxed supernodes, which CHOLMOD's
  // analysis sizes exactly (xsize entries, ssize row indices).
  const cholmod_factor& f = *analysis;
  const double entries =
      f.is_super ? std::max(static_cast<double>(f.xsize), estimate.nnz_l) : estimate.nnz_l;
  estimate.factor_bytes =
      entries * sizeof(double) +
      (f.is_super ? static_cast<double>(f.ssize) : estimate.nnz_l) * sizeof(int) +
      static_cast<double>(a.rows()) * 4 * sizeof(int);
  analysis_of = {common.lnz, common.fl, estimate.analysis_seconds};
  // The pattern, to recognize the matrix (or a copy of it) in Factorize(); without the values
  // (a third of a copy of `a`).
  SparseMatrix compressed;
  const SparseMatrix* pattern = &a;
  if (!a.isCompressed()) {
    compressed = a;
    compressed.makeCompressed();
    pattern = &compressed;
  }
  analysis_outer.assign(pattern->outerIndexPtr(),
                        pattern->outerIndexPtr() + pattern->outerSize() + 1);
  analysis_inner.assign(pattern->innerIndexPtr(), pattern->innerIndexPtr() + pattern->nonZeros());
  return estimate;
}

SolveSummary CholmodFactorization::Solve(const Eigen::Ref<const Eigen::MatrixXd>& b,
                                         Eigen::Ref<Eigen::MatrixXd> x_out,
                                         const Context& context) {
  // A Refactor() that failed midway leaves no factor (LinearSolver only knows the last call
  // threw).
  HARAP_CHECK(factorized, "cholmod: Solve() needs a successful Factorize() first");
  if (use_tree_solve) {
    tree_solve.Solve(b, x_out, context);
    return FinishSolve(b, x_out);
  }

  HARAP_CHECK(!rows_released(), "cholmod: the factor's rows were released for the tree solve");
  // B wraps b's memory; cholmod_solve2 only reads it (permuting it into the Y workspace).
  cholmod_dense rhs = cholmod_views::DenseView(b);
  RestoreSimplicialWorkspaceShape(factor, b.cols(), y);
  if (!cholmod_solve2(CHOLMOD_A, factor, &rhs, nullptr, &x, nullptr, &y, &e, &common)) {
    if (common.status == CHOLMOD_OUT_OF_MEMORY) {
      throw NumericalError(
          fmt::format("cholmod: out of memory allocating the {}×{} solve workspaces. {}.", b.rows(),
                      b.cols(), solver_checks::kOutOfMemoryAdvice));
    }
    throw InternalError(fmt::format("cholmod: solve failed with status {}", common.status));
  }
  x_out = Eigen::Map<const Eigen::MatrixXd, 0, Eigen::OuterStride<>>(
      static_cast<const double*>(x->x), b.rows(), b.cols(),
      Eigen::OuterStride<>(static_cast<Eigen::Index>(x->d)));
  return FinishSolve(b, x_out);
}

bool CholmodFactorization::FactorSupernodal(cholmod_factor* f, cholmod_sparse& view,
                                            const SparseMatrix& a, const Context& context) {
  if (options.numeric == Numeric::kCholmod) {
    const int final_asis = common.final_asis;
    common.final_asis = 1;  // keep the supernodal LLᵀ factor
    cholmod_factorize(&view, f, &common);
    common.final_asis = final_asis;
    return common.status == CHOLMOD_OK || common.status == CHOLMOD_DSMALL;
  }
  if (f->xtype == CHOLMOD_PATTERN &&
      !cholmod_change_factor(CHOLMOD_REAL, /*to_ll=*/1, /*to_super=*/1, /*to_packed=*/1,
                             /*to_monotonic=*/1, f, &common)) {
    return false;  // out of memory (common.status says so)
  }
  const int n = static_cast<int>(f->n);
  const auto* perm = static_cast<const int*>(f->Perm);
  std::vector<int> inverse(n);
  for (int j = 0; j < n; ++j) inverse[perm ? perm[j] : j] = j;
  const SupernodalFactorView layout = cholmod_views::SupernodalView(*f);
  const int threads = options.native_threads == 1 ? context.arena->max_concurrency() : 1;
  PartialSupernodalFactor numeric;
  // Each thread needs its own BLAS work buffer (see EnsureBlasWorkBuffer), the one that
  // Run() runs this on too (an arena worker if the caller's thread could not join the arena).
  // Out of memory in harap's own buffers is reported as CHOLMOD reports its own.
  constexpr int kNoMemory = -2;
  int bad_column = -1;
  try {
    bad_column = context.Run([&] {
      if (!EnsureBlasWorkBuffer()) return kNoMemory;
      return numeric.FactorAll(layout, a, inverse, threads, &EnsureBlasWorkBuffer);
    });
  } catch (const std::bad_alloc&) {
    bad_column = kNoMemory;
  }
  if (bad_column == kNoMemory) {
    common.status = CHOLMOD_OUT_OF_MEMORY;
    return false;
  }
  info.numeric_subtrees = numeric.subtrees();
  info.numeric_subtree_work = numeric.subtree_work_fraction();
  info.numeric_largest_subtree = numeric.largest_subtree_fraction();
  if (bad_column >= 0) {
    f->minor = static_cast<size_t>(bad_column);
    common.status = CHOLMOD_NOT_POSDEF;
    return false;
  }
  f->minor = f->n;
  common.status = CHOLMOD_OK;
  return true;
}

void CholmodFactorization::FactorizeKeptSupernodal(cholmod_sparse& view, const SparseMatrix& a,
                                                   const Context& context) {
  if (!FactorSupernodal(super, view, a, context)) {
    FreeFactor();
    factor = super;
    super = nullptr;
    ThrowOnFailure("factorization", a);
  }
}

void CholmodFactorization::FactorNumericKeepingSuper(cholmod_sparse& view, const SparseMatrix& a,
                                                     const Context& context) {
  const Stopwatch clock;
  FreeSuper();
  super = cholmod_copy_factor(factor, &common);
  ThrowOnFailure("copy of the analysis", a);
  FactorizeKeptSupernodal(view, a, context);
  FreeFactor();
  factor = cholmod_copy_factor(super, &common);
  ThrowOnFailure("copy of the factor", a);
  ConvertToFinal(view, a);
  super_current = true;
  partial.Setup(SuperView());
  info.numeric_seconds = clock.Seconds();
}

void CholmodFactorization::FactorNumeric(cholmod_sparse& view, const SparseMatrix& a,
                                         const Context& context) {
  const Stopwatch clock;
  if (factor->is_super) {
    FactorSupernodal(factor, view, a, context);
    ThrowOnFailure("factorization", a);
    ConvertToFinal(view, a);
  } else {
    cholmod_factorize(&view, factor, &common);
    ThrowOnFailure("factorization", a);
  }
  info.numeric_seconds = clock.Seconds();
}

void CholmodFactorization::ConvertToFinal(cholmod_sparse& view, const SparseMatrix& a) {
  if (common.final_asis) return;
  if (!cholmod_change_factor(CHOLMOD_REAL, common.final_ll, common.final_super, common.final_pack,
                             common.final_monotonic, factor, &common)) {
    ThrowOnFailure("conversion of the factor", a);
  }
  if (common.final_resymbol && !factor->is_super &&
      !cholmod_resymbol(&view, nullptr, 0, common.final_pack, factor, &common)) {
    ThrowOnFailure("symbolic refactorization", a);
  }
}

bool CholmodFactorization::FactorNumericInPlace(cholmod_sparse& view, const SparseMatrix& a,
                                                const Context& context) {
  if (options.mode != Mode::kAuto || symbolic == nullptr || !symbolic->is_super ||
      factor == nullptr || factor->is_super || factor->is_ll || factor->n != symbolic->n) {
    return false;
  }
  const Stopwatch clock;
  // Into the kept supernodal factor if there is one (its structure is the analysis'), else a
  // copy of the analysis freed afterwards.
  if (super == nullptr || !keeps_super()) {
    FreeSuper();
    super = cholmod_copy_factor(symbolic, &common);
    if (super == nullptr) {
      ThrowOnFailure("copy of the analysis", a);
      return false;
    }
  }
  super_current = false;
  FactorizeKeptSupernodal(view, a, context);
  const bool matches = CopySuperToSimplicial(/*all=*/true);
  if (keeps_super() && matches) {
    super_current = true;
    if (!partial.ready()) partial.Setup(SuperView());
  } else {
    FreeSuper();
  }
  if (!matches) return false;  // the caller factors the usual way, overwriting the values
  info.numeric_seconds = clock.Seconds();
  return true;
}

bool CholmodFactorization::CopySuperToSimplicial(bool all) {
  const auto* ls = static_cast<const int*>(super->s);
  const auto* pi = static_cast<const int*>(super->pi);
  const auto* px = static_cast<const int*>(super->px);
  const auto* first = static_cast<const int*>(super->super);
  const auto* sx = static_cast<const double*>(super->x);
  const auto* lp = static_cast<const int*>(factor->p);
  const auto* lnz = static_cast<const int*>(factor->nz);
  const auto* li = static_cast<const int*>(factor->i);
  auto* lx = static_cast<double*>(factor->x);
  const std::vector<char>& marked = partial.marked();
  for (size_t s = 0; s < super->nsuper; ++s) {
    if (!all && !marked[s]) continue;
    const int rows = pi[s + 1] - pi[s];
    for (int j = first[s]; j < first[s + 1]; ++j) {
      const int local = j - first[s];
      const double* column = sx + px[s] + static_cast<size_t>(local) * rows;
      const double diagonal = column[local];
      lx[lp[j]] = diagonal * diagonal;
      // Both row lists are sorted; the simplicial one is a subset of the supernode's.
      int r = local + 1;
      for (int e = lp[j] + 1; e < lp[j] + lnz[j]; ++e) {
        while (r < rows && ls[pi[s] + r] < li[e]) ++r;
        if (r == rows || ls[pi[s] + r] != li[e]) return false;
        lx[e] = column[r] / diagonal;
      }
    }
  }
  return true;
}

void CholmodFactorization::FinishFactor(const SparseMatrix& a, const Eigen::VectorXd& diagonal,
                                        const Context& context, bool same_arrays,
                                        bool same_pattern) {
  CheckPivots(a, diagonal);
  info.supernodal = factor->is_super != 0;
  info.ordering = cholmod_views::OrderingName(factor->ordering);
  info.nnz_l = common.lnz;
  info.flops = common.fl;
  use_tree_solve = false;
  if (options.parallel_solve && !factor->is_super && !factor->is_ll) {
    const LdltFactorView view = cholmod_views::SimplicialView(*factor);
    const Stopwatch setup_clock;
    if (same_arrays && view.row != nullptr && tree_view.row == view.row &&
        tree_view.value == view.value && tree_view.column_start == view.column_start &&
        tree_view.column_count == view.column_count && tree_view.n == view.n) {
      tree_solve.RefreshPivots();
    } else if (!(same_pattern && tree_solve.Rebind(view))) {
      tree_solve.Setup(view, context.arena->max_concurrency());
      plan_seconds = setup_clock.Seconds();
    }
    tree_view = view;
    info.solve_setup_seconds = setup_clock.Seconds();
    use_tree_solve = true;
    info.solve_blocks = tree_solve.num_blocks();
    info.solve_critical_path = tree_solve.critical_path_fraction();
    ReleaseRowsOfOneShotFactor();
  }
  if (options.check_residual || keeps_copies()) {
    if (SamePattern(matrix, a) && matrix.isCompressed() && a.isCompressed()) {
      std::copy(a.valuePtr(), a.valuePtr() + a.nonZeros(), matrix.valuePtr());
    } else {
      matrix = a;
      matrix.makeCompressed();
    }
  }
  factorized = true;
}

cholmod_factor* CholmodFactorization::TakeOrMakeAnalysis(const SparseMatrix& a) {
  if (analysis != nullptr && a.isCompressed() && IsAnalysisPattern(a)) {
    cholmod_factor* kept = analysis;
    analysis = nullptr;
    analysis_outer = {};
    analysis_inner = {};
    common.lnz = analysis_of.lnz;  // restored: other CHOLMOD calls may have changed them
    common.fl = analysis_of.fl;
    info.analysis_seconds = analysis_of.seconds;
    return kept;
  }
  FreeAnalysis();
  const Stopwatch clock;
  cholmod_sparse pattern = PatternView(a);
  cholmod_factor* made = cholmod_analyze(&pattern, &common);
  ThrowOnFailure("analysis (ordering)", a);
  HARAP_CHECK(made != nullptr, "cholmod_analyze returned no factor (status {})", common.status);
  info.analysis_seconds = clock.Seconds();
  return made;
}

bool CholmodFactorization::IsAnalysisPattern(const SparseMatrix& a) const {
  return static_cast<size_t>(a.outerSize()) + 1 == analysis_outer.size() &&
         static_cast<size_t>(a.nonZeros()) == analysis_inner.size() &&
         std::equal(analysis_outer.begin(), analysis_outer.end(), a.outerIndexPtr()) &&
         std::equal(analysis_inner.begin(), analysis_inner.end(), a.innerIndexPtr());
}

bool CholmodFactorization::keeps_copies() const {
  return options.refactor == RefactorChoice::kNumeric ||
         options.refactor == RefactorChoice::kUpdate ||
         options.refactor == RefactorChoice::kPartial ||
         (options.refactor == RefactorChoice::kAuto && prepared_for_refactor);
}

bool CholmodFactorization::keeps_super() const {
  return options.mode == Mode::kAuto && options.refactor != RefactorChoice::kFull &&
         (options.refactor == RefactorChoice::kPartial || prepared_for_refactor);
}

SupernodalFactorView CholmodFactorization::SuperView() const {
  return cholmod_views::SupernodalView(*super);
}

void CholmodFactorization::FreeFactor() {
  if (factor) cholmod_free_factor(&factor, &common);
  factor = nullptr;
}

void CholmodFactorization::FreeSymbolic() {
  if (symbolic) cholmod_free_factor(&symbolic, &common);
  symbolic = nullptr;
}

void CholmodFactorization::FreeAnalysis() {
  if (analysis) cholmod_free_factor(&analysis, &common);
  analysis = nullptr;
  analysis_outer = {};
  analysis_inner = {};
}

void CholmodFactorization::FreeSuper() {
  if (super) cholmod_free_factor(&super, &common);
  super = nullptr;
  super_current = false;
}

void CholmodFactorization::ReleaseRowsOfOneShotFactor() {
  if (!use_tree_solve || symbolic != nullptr || super != nullptr || keeps_copies() ||
      keeps_super() || factor == nullptr || factor->is_super || factor->i == nullptr) {
    return;
  }
  const size_t in_use = common.memory_inuse;
  factor->i = cholmod_free(factor->nzmax, sizeof(int), factor->i, &common);
  // CHOLMOD's workspace (Flag, Head, Iwork, Xwork: O(n)) too; any later call reallocates it.
  cholmod_free_work(&common);
  info.released_bytes = static_cast<double>(in_use - common.memory_inuse);
  tree_view.row = nullptr;  // same_arrays never matches a factor without rows
}

bool CholmodFactorization::rows_released() const {
  return factor != nullptr && !factor->is_super && factor->xtype != CHOLMOD_PATTERN &&
         factor->i == nullptr;
}

void CholmodFactorization::ThrowOnFailure(std::string_view stage, const SparseMatrix& a) const {
  switch (common.status) {
    case CHOLMOD_OK:
    case CHOLMOD_DSMALL:
      return;
    case CHOLMOD_OUT_OF_MEMORY:
      throw NumericalError(OutOfMemoryMessage(stage, common, a, options.ordering));
    case CHOLMOD_TOO_LARGE:
      throw NumericalError(fmt::format(
          "cholmod: the factor of the {}×{} matrix is too large for 32-bit indices (nnz(L) ≈ "
          "{:.3g}). {} or ordering = \"metis\".",
          a.rows(), a.cols(), common.lnz, solver_checks::kOutOfMemoryAdvice));
    case CHOLMOD_NOT_POSDEF: {
      const size_t minor = factor ? factor->minor : 0;
      const int row = factor && factor->Perm && minor < factor->n
                          ? static_cast<const int*>(factor->Perm)[minor]
                          : -1;
      throw NumericalError(fmt::format(
          "cholmod: the matrix is not positive definite: the {} factorization hit a "
          "non-positive pivot at column {} of the factor (row {} of the {}×{} matrix). {}",
          factor && factor->is_super ? "supernodal" : "simplicial", minor, row, a.rows(), a.cols(),
          solver_checks::kNotPositiveDefiniteAdvice));
    }
    default:
      throw InternalError(fmt::format("cholmod: {} failed with status {}", stage, common.status));
  }
}

void CholmodFactorization::CheckPivots(const SparseMatrix& a,
                                       const Eigen::VectorXd& diagonal) const {
  const auto* perm = static_cast<const int*>(factor->Perm);
  int bad_column = -1;
  double bad_pivot = 0.0;
  cholmod_views::ForEachPivot(*factor, [&](int column, double pivot) {
    if (bad_column >= 0) return;
    const int row = perm ? perm[column] : column;
    if (!solver_checks::AcceptablePivot(pivot, diagonal[row], options.pivot_tolerance)) {
      bad_column = column;
      bad_pivot = pivot;
    }
  });
  if (bad_column < 0) return;
  const int row = perm ? perm[bad_column] : bad_column;
  solver_checks::ThrowBadPivot("cholmod", a.rows(), bad_column, row, bad_pivot, diagonal[row],
                               options.pivot_tolerance);
}

SolveSummary CholmodFactorization::FinishSolve(const Eigen::Ref<const Eigen::MatrixXd>& b,
                                               const Eigen::Ref<Eigen::MatrixXd>& x_out) {
  SolveSummary summary;
  if (options.check_residual && x_out.allFinite()) {
    summary.relative_residual = solver_checks::MaxRelativeResidual(matrix, b, x_out, residual);
    summary.outcome = SolveOutcome::kSolvedChecked;
  }
  return summary;
}

}  // namespace harap

#endif  // HARAP_HAVE_CHOLMOD
