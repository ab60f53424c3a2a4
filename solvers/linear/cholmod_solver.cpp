// SPDX-License-Identifier: MIT
// Compiled into harap_solvers only when CHOLMOD was found (solvers/CMakeLists.txt defines
// HARAP_HAVE_CHOLMOD); register_solvers.cpp registers it under the same condition.
//
// The solver is made of: its options (here), CholmodFactorization (cholmod_factorization.h: the
// factors and the steps of Factorize(), Analyze() and Solve()), the routes of Refactor()
// (cholmod_refactor_routes.h), the views between harap's and CHOLMOD's arrays (cholmod_views.h),
// the caps on CHOLMOD's own threads (cholmod_native_threads.h) and the BLAS work-buffer probe
// (blas_work_buffer.h).
#ifdef HARAP_HAVE_CHOLMOD

#include "solvers/linear/cholmod_solver.h"

#include <fmt/format.h>

#include "framework/error.h"
#include "solvers/linear/blas_work_buffer.h"
#include "solvers/linear/cholmod_factorization.h"
#include "solvers/linear/cholmod_refactor_routes.h"
#include "solvers/linear/solver_checks.h"

namespace harap {
namespace {

// The option names, for FromConfig() and ToString().
constexpr EnumNames<CholmodSolver::Mode, 3> kModeNames = {{
    {CholmodSolver::Mode::kAuto, "auto"},
    {CholmodSolver::Mode::kSimplicial, "simplicial"},
    {CholmodSolver::Mode::kSupernodal, "supernodal"},
}};
constexpr EnumNames<CholmodSolver::Ordering, 3> kOrderingNames = {{
    {CholmodSolver::Ordering::kMetis, "metis"},
    {CholmodSolver::Ordering::kAmd, "amd"},
    {CholmodSolver::Ordering::kBest, "best"},
}};
constexpr EnumNames<CholmodSolver::Numeric, 2> kNumericNames = {{
    {CholmodSolver::Numeric::kParallel, "parallel"},
    {CholmodSolver::Numeric::kCholmod, "cholmod"},
}};
constexpr EnumNames<CholmodSolver::RefactorChoice, 5> kRefactorNames = {{
    {CholmodSolver::RefactorChoice::kAuto, "auto"},
    {CholmodSolver::RefactorChoice::kFull, "full"},
    {CholmodSolver::RefactorChoice::kNumeric, "numeric"},
    {CholmodSolver::RefactorChoice::kUpdate, "update"},
    {CholmodSolver::RefactorChoice::kPartial, "partial"},
}};

}  // namespace

CholmodSolver::Options CholmodSolver::Options::FromConfig(OptionReader node) {
  Options options;
  options.mode = node.GetEnum("mode", options.mode, kModeNames,
                              "simplicial = up-looking LDLᵀ, supernodal = BLAS LLᵀ (fastest "
                              "factorization, slower 3-column solves), auto = supernodal "
                              "factorization converted to simplicial form for the solves (both "
                              "fast)");
  options.ordering = node.GetEnum("ordering", options.ordering, kOrderingNames,
                                  "fill-reducing ordering; best = CHOLMOD's default (AMD, then "
                                  "METIS if AMD fills a lot)");
  options.parallel_solve =
      node.Get("parallel_solve", options.parallel_solve,
               "solve with a simplicial factor by substitution over independent subtrees of the "
               "elimination tree on all threads (false = CHOLMOD's sequential cholmod_solve2)");
  solver_checks::ReadFactorizationOptions(node, options.pivot_tolerance, options.check_residual);
  options.refactor = node.GetEnum(
      "refactor", options.refactor, kRefactorNames,
      "how Refactor() (handle edits of a session) updates the factor: numeric = reuse the "
      "analysis, factor the values; update = modify the factor row by row (cholmod_rowdel/rowadd; "
      "not with mode supernodal); partial = refactor only the supernodes the changed rows reach "
      "(mode auto; keeps the supernodal factor); auto = the cheapest of these by estimates from "
      "the factor's elimination tree and measured times; full = factor from scratch (keeps no "
      "copies)");
  options.numeric = node.GetEnum(
      "numeric", options.numeric, kNumericNames,
      "who computes a supernodal numeric factorization: parallel = harap's left-looking "
      "factorization (CHOLMOD's algorithm and values, independent subtrees on the run's threads, "
      "no permuted copies of A); cholmod = cholmod_factorize");
  options.native_threads = node.Get(
      "native_threads", options.native_threads,
      "threads for CHOLMOD's OpenMP loops and its BLAS (0: as the environment sets them; harap's "
      "own parallelism is TBB's, which native threads compete with)");
  node.RejectUnknownKeys();
  if (options.refactor == RefactorChoice::kUpdate && options.mode == Mode::kSupernodal) {
    throw ConfigError(fmt::format(
        "{}: refactor = \"update\" modifies a simplicial LDLᵀ factor, but mode = \"supernodal\" "
        "keeps a supernodal one; use mode = \"auto\" or \"simplicial\", or refactor = "
        "\"numeric\"",
        node.Where("refactor")));
  }
  if (options.native_threads < 0) {
    throw ConfigError(fmt::format("{}: native_threads must be >= 0, got {}",
                                  node.Where("native_threads"), options.native_threads));
  }
  return options;
}

CholmodSolver::CholmodSolver(const Options& options)
    : LinearSolver(kName), factorization_(std::make_unique<CholmodFactorization>(options)) {
  // Early, while memory is likely still free (see EnsureBlasWorkBuffer); Factorize checks again.
  if (options.mode != Mode::kSimplicial) EnsureBlasWorkBuffer();
}

CholmodSolver::~CholmodSolver() = default;

const CholmodSolver::Options& CholmodSolver::options() const { return factorization_->options; }

const CholmodSolver::FactorInfo& CholmodSolver::factor_info() const { return factorization_->info; }

void CholmodSolver::PrepareForRefactor() { factorization_->prepared_for_refactor = true; }

void CholmodSolver::set_refactor(RefactorChoice choice) {
  HARAP_CHECK(
      choice != RefactorChoice::kUpdate || factorization_->options.mode != Mode::kSupernodal,
      "refactor = \"update\" needs a simplicial factor (mode auto or simplicial)");
  factorization_->options.refactor = choice;
}

std::string_view CholmodSolver::ToString(Mode mode) { return NameOf(kModeNames, mode); }

std::string_view CholmodSolver::ToString(Ordering ordering) {
  return NameOf(kOrderingNames, ordering);
}

std::string_view CholmodSolver::ToString(RefactorChoice choice) {
  return NameOf(kRefactorNames, choice);
}

void CholmodSolver::FactorizeImpl(const SparseMatrix& a, const Context& context) {
  factorization_->Factorize(a, context);
}

CholmodSolver::Estimate CholmodSolver::Analyze(const SparseMatrix& a) {
  HARAP_CHECK(a.rows() == a.cols(), "matrix is {}×{}, not square", a.rows(), a.cols());
  return factorization_->Analyze(a);
}

LinearSolver::RefactorSummary CholmodSolver::RefactorImpl(const SparseMatrix& a,
                                                          const std::vector<Index>& changed_rows,
                                                          const Context& context) {
  const Stopwatch clock;
  CholmodFactorization& f = *factorization_;
  RefactorSummary summary;
  summary.changed_rows = static_cast<Index>(changed_rows.size());
  const auto finish = [&](RefactorRoute route) {
    summary.route = route;
    summary.seconds = clock.Seconds();
    return summary;
  };
  const auto full = [&] {
    Factorize(a, context);
    return finish(RefactorRoute::kFull);
  };
  // Without a factorization of the same pattern to start from, there is nothing to reuse.
  if (!cholmod_refactor::CanReuse(f, a)) return full();
  cholmod_refactor::CheckChangedRows(f, a, changed_rows);
  const Eigen::VectorXd diagonal = solver_checks::PositiveDiagonal(a, "cholmod");
  const cholmod_refactor::RefactorPlan plan = cholmod_refactor::PlanRefactor(f, a, changed_rows);

  // From here on the old factor is being replaced: a throw leaves the solver unfactored.
  f.factorized = false;
  f.use_tree_solve = false;
  switch (plan.route) {
    case RefactorChoice::kPartial:
      if (!cholmod_refactor::RefactorPartial(f, a, diagonal, context)) return full();
      return finish(RefactorRoute::kPartial);
    case RefactorChoice::kUpdate:
      cholmod_refactor::RefactorByUpdate(f, a, changed_rows, plan, diagonal, context);
      return finish(RefactorRoute::kUpdate);
    default:  // kNumeric: PlanRefactor() resolves kAuto, and CanReuse() is false for kFull.
      if (!cholmod_refactor::RefactorNumeric(f, a, diagonal, context)) return full();
      return finish(RefactorRoute::kNumeric);
  }
}

SolveSummary CholmodSolver::SolveImpl(const Eigen::Ref<const Eigen::MatrixXd>& b,
                                      Eigen::Ref<Eigen::MatrixXd> x, const Context& context) {
  return factorization_->Solve(b, x, context);
}

}  // namespace harap

#endif  // HARAP_HAVE_CHOLMOD
