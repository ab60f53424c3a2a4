// SPDX-License-Identifier: MIT
// Compiled into harap_solvers only when CHOLMOD was found (like cholmod_solver.cpp).
#ifdef HARAP_HAVE_CHOLMOD

#include "solvers/linear/adaptive_solver.h"

#include <unistd.h>

#include <string>
#include <vector>

#include "framework/error.h"

namespace harap {
namespace {

constexpr EnumNames<AdaptiveSolver::Choice, 3> kChoiceNames = {{
    {AdaptiveSolver::Choice::kAuto, "auto"},
    {AdaptiveSolver::Choice::kDirect, "direct"},
    {AdaptiveSolver::Choice::kIterative, "iterative"},
}};

// Right-hand sides per solve: the global step's three coordinates.
constexpr double kColumns = 3.0;

}  // namespace

AdaptiveSolver::Options AdaptiveSolver::Options::FromConfig(OptionReader node) {
  Options options;
  options.choose = node.GetEnum(
      "choose", options.choose, kChoiceNames,
      "auto = factor unless CHOLMOD's analysis says the factor exceeds max_factor_megabytes or "
      "costs more arithmetic than expected_solves CG solves; direct = always cholmod; "
      "iterative = always cg");
  options.max_factor_megabytes =
      node.Get("max_factor_megabytes", options.max_factor_megabytes,
               "memory budget of the Cholesky factor in MB (0: half the physical memory)",
               Range::AtLeast(0.0));
  options.expected_solves = node.Get(
      "expected_solves", options.expected_solves,
      "global steps the matrix is expected to serve (weighs the factorization against solves)",
      Range::Above(0.0));
  options.max_unresolved = node.Get(
      "max_unresolved", options.max_unresolved,
      "while it iterates: factor once a CG solve left more than this share of its correction "
      "undone (CG's own estimate, A-norm squared): before the next solve after the first one, at "
      "once after a later one, solving that system again (1: never)",
      Range::Closed(0.0, 1.0));
  options.direct = CholmodSolver::Options::FromConfig(
      node.Child("direct", "table: the cholmod options used when it factors"));
  options.iterative = ConjugateGradientSolver::Options::FromConfig(
      node.Child("iterative",
                 "table: the cg options used when it iterates (default 20 "
                 "Jacobi-preconditioned iterations per solve)"));
  options.direct.check_residual =
      node.Get("check_residual", options.direct.check_residual,
               "measure ‖b − A x‖ / ‖b‖ in every solve also when it factors (cg always does)");
  node.RejectUnknownKeys();
  return options;
}

AdaptiveSolver::AdaptiveSolver(const Options& options) : LinearSolver(kName), options_(options) {}

AdaptiveSolver::~AdaptiveSolver() = default;

double AdaptiveSolver::DefaultBudgetBytes() {
  const long pages = sysconf(_SC_PHYS_PAGES);
  const long page_size = sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page_size <= 0) return 4e9;  // unknown: a budget any 8 GB machine meets
  return 0.5 * static_cast<double>(pages) * static_cast<double>(page_size);
}

void AdaptiveSolver::FactorizeImpl(const SparseMatrix& a, const Context& context) {
  chosen_ = nullptr;
  switched_ = false;
  decision_ = Decision{};
  decision_.direct = options_.choose != Choice::kIterative;
  if (options_.choose == Choice::kAuto && a.rows() > 0) {
    direct_ = std::make_unique<CholmodSolver>(options_.direct);
    if (prepared_for_refactor_) direct_->PrepareForRefactor();
    const CholmodSolver::Estimate estimate = direct_->Analyze(a);
    const double n = static_cast<double>(a.rows());
    const double s = options_.expected_solves;
    const double m = options_.iterative.limits.max_iterations;
    decision_.estimated = true;
    decision_.estimate = estimate;
    decision_.budget_bytes = options_.max_factor_megabytes > 0.0
                                 ? options_.max_factor_megabytes * 1e6
                                 : DefaultBudgetBytes();
    decision_.direct_flops = estimate.flops + s * 4.0 * kColumns * estimate.nnz_l;
    decision_.iterative_flops =
        s * m * kColumns * (2.0 * static_cast<double>(a.nonZeros()) + 12.0 * n);
    decision_.direct = estimate.factor_bytes <= decision_.budget_bytes &&
                       decision_.direct_flops <= decision_.iterative_flops;
  }
  iterated_flops_ = 0.0;
  iterative_solves_ = 0;
  stalled_ = false;
  // Iterating because it looked cheaper (not because the factor does not fit): if the matrix
  // then serves more solves than expected, factor once the iterations have cost as much as the
  // factorization (below, in Solve()).
  may_switch_ = decision_.estimated && !decision_.direct &&
                decision_.estimate.factor_bytes <= decision_.budget_bytes;
  if (decision_.direct) {
    if (!direct_ || options_.choose != Choice::kAuto) {
      direct_ = std::make_unique<CholmodSolver>(options_.direct);
      if (prepared_for_refactor_) direct_->PrepareForRefactor();
    }
    iterative_.reset();
    chosen_ = direct_.get();
  } else {
    if (!may_switch_) direct_.reset();  // frees the analysis; else kept for the switch
    if (!iterative_) iterative_ = std::make_unique<ConjugateGradientSolver>(options_.iterative);
    chosen_ = iterative_.get();
  }
  try {
    chosen_->Factorize(a, context);
  } catch (...) {
    chosen_ = nullptr;
    throw;
  }
  ReportChoice(chosen(), chosen_->is_direct());
}

SolveSummary AdaptiveSolver::SolveImpl(const Eigen::Ref<const Eigen::MatrixXd>& b,
                                       Eigen::Ref<Eigen::MatrixXd> x, const Context& context) {
  HARAP_CHECK(chosen_ != nullptr, "adaptive: Solve() needs a successful Factorize() first");
  if (may_switch_ && (iterated_flops_ >= decision_.estimate.flops ||
                      iterative_solves_ >= options_.expected_solves || stalled_)) {
    // Factor (with the kept analysis) and solve directly from here on, as soon as either
    // - the iterations have cost as much arithmetic as the factorization: like renting until the
    //   rent paid equals the price, this costs at most about twice what the better choice made
    //   in hindsight would have (ski rental); or
    // - the matrix serves more solves than the expected_solves the choice assumed. Counting
    //   flops alone underrates CG: its sparse products run at a fraction of the factorization's
    //   dense-kernel speed, and its inexact steps cost the caller extra global steps, each with
    //   its own local step (dragon-lift refined to 1.75M/7M vertices iterated 17/38 steps at
    //   level 0 before the flops caught up; docs/solvers.md, "Per-level choice"); or
    // - the level's first CG solve left more than max_unresolved of its correction undone (below).
    SwitchToDirect(context);
  }
  SolveSummary summary = chosen_->Solve(b, x, context);
  if (chosen_ != iterative_.get()) return summary;
  ++iterative_solves_;
  const double n = static_cast<double>(b.rows());
  const double nnz = static_cast<double>(iterative_->matrix().nonZeros());
  iterated_flops_ += summary.iterations * static_cast<double>(b.cols()) * (2.0 * nnz + 12.0 * n);
  if (!may_switch_ || !summary.success() ||
      iterative_->unresolved_fraction() <= options_.max_unresolved) {
    return summary;
  }
  if (iterative_solves_ == 1) {
    // The first step from the up-sampled start: the level often stops after it, so factor only
    // if another solve follows (a factorization there would mostly be wasted).
    stalled_ = true;
  } else {
    // A later step left most of its correction undone (dragon-lift's second step from 437K
    // vertices up) and the level is still moving: a step that inexact would cost the caller
    // several more global steps for its smooth part. Factor now and solve this system again.
    SwitchToDirect(context);
    const int cg_iterations = summary.iterations;
    summary = chosen_->Solve(b, x, context);
    summary.iterations += cg_iterations;
  }
  return summary;
}

void AdaptiveSolver::SwitchToDirect(const Context& context) {
  may_switch_ = false;
  direct_->Factorize(iterative_->matrix(), context);
  chosen_ = direct_.get();
  iterative_.reset();
  switched_ = true;
  ReportChoice(chosen(), false);  // the level's solves were not all direct
}

bool AdaptiveSolver::is_direct() const { return chosen_ != nullptr && chosen_->is_direct(); }

void AdaptiveSolver::PrepareForRefactor() {
  prepared_for_refactor_ = true;
  if (direct_) direct_->PrepareForRefactor();
}

LinearSolver::RefactorSummary AdaptiveSolver::RefactorImpl(const SparseMatrix& a,
                                                           const std::vector<Index>& changed_rows,
                                                           const Context& context) {
  // A direct choice stays (the pattern, and so the factor's size, did not change); an
  // iterative one decides anew, as a Factorize() would.
  if (chosen_ == direct_.get() && direct_ != nullptr) {
    try {
      return direct_->Refactor(a, changed_rows, context);
    } catch (...) {
      chosen_ = nullptr;
      throw;
    }
  }
  FactorizeImpl(a, context);
  return {RefactorRoute::kFull, static_cast<Index>(changed_rows.size()), 0.0};
}

std::string_view AdaptiveSolver::chosen() const {
  if (chosen_ == nullptr) return {};
  if (chosen_ != direct_.get()) return ConjugateGradientSolver::kName;
  return switched_ ? "cg>cholmod" : CholmodSolver::kName;
}

}  // namespace harap

#endif  // HARAP_HAVE_CHOLMOD
