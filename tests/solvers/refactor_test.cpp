// SPDX-License-Identifier: MIT
// LinearSolver::Refactor after handle edits: masked grid Laplacians (handles' rows and columns
// become the identity's, the pattern stays), every CHOLMOD route (full, numeric, update, partial,
// auto)
// and the default of the other solvers. Each refactored solver must solve the NEW matrix.

#include <algorithm>
#include <catch2/catch.hpp>
#include <set>
#include <string>
#include <vector>

#include "framework/context.h"
#include "framework/error.h"
#include "tests/solvers/solver_test_matrices.h"

#ifdef HARAP_HAVE_CHOLMOD
#include "solvers/linear/cholmod_solver.h"
#endif

namespace harap::testing {
namespace {

using Route = LinearSolver::RefactorRoute;

constexpr int kSide = 40;  // 1600 vertices: small, but deep enough an elimination tree.

// The grid Laplacian with `handles` masked: their rows and columns zero, 1 on the diagonal,
// every entry kept (explicit zeros), as an interactive session hands it to the solver.
SparseMatrix Masked(const SparseMatrix& laplacian, const std::set<Index>& handles) {
  SparseMatrix a = laplacian;
  a.makeCompressed();
  for (Index j = 0; j < a.outerSize(); ++j) {
    for (SparseMatrix::InnerIterator it(a, j); it; ++it) {
      const bool masked = handles.count(it.row()) > 0 || handles.count(it.col()) > 0;
      if (masked) it.valueRef() = it.row() == it.col() ? 1.0 : 0.0;
    }
  }
  return a;
}

// Grid vertices within `radius` of (row, col).
std::set<Index> Ball(int row, int col, double radius) {
  std::set<Index> ball;
  for (int r = 0; r < kSide; ++r) {
    for (int c = 0; c < kSide; ++c) {
      if ((r - row) * (r - row) + (c - col) * (c - col) <= radius * radius) {
        ball.insert(r * kSide + c);
      }
    }
  }
  return ball;
}

std::vector<Index> SymmetricDifference(const std::set<Index>& x, const std::set<Index>& y) {
  std::vector<Index> rows;
  std::set_symmetric_difference(x.begin(), x.end(), y.begin(), y.end(), std::back_inserter(rows));
  return rows;
}

// The first handle set: the grid's first row (one handle per component keeps it SPD).
std::set<Index> FirstRow() {
  std::set<Index> handles;
  for (int c = 0; c < kSide; ++c) handles.insert(c);
  return handles;
}

// Checks that `solver` solves `a` x = b to a relative residual ≤ 1e-12.
void RequireSolves(LinearSolver& solver, const SparseMatrix& a, const Context& context) {
  const Eigen::MatrixXd b = RandomRhs(a.rows(), 3, 5);
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 3);
  REQUIRE(solver.Solve(b, x, context).success());
  REQUIRE(RelativeResidual(a, b, x) <= 1e-12);
}

Route Expected(const std::string& refactor, const std::string& mode, Route automatic) {
  if (refactor == "full") return Route::kFull;
  if (refactor == "numeric") return Route::kNumeric;
  if (refactor == "update") return Route::kUpdate;
  // The partial refactorization keeps mode auto's supernodal factor; other modes: numeric.
  if (refactor == "partial") return mode == "auto" ? Route::kPartial : Route::kNumeric;
  return automatic;
}

#ifdef HARAP_HAVE_CHOLMOD
// The route auto must take by the estimates the solver reports (the lowest; see Refactor()).
Route AutoRoute(const CholmodSolver::FactorInfo& info, bool can_partial, bool can_update) {
  Route route = Route::kNumeric;
  double best = info.estimated_numeric_seconds;
  if (can_partial && info.estimated_partial_seconds < best) {
    route = Route::kPartial;
    best = info.estimated_partial_seconds;
  }
  if (can_update && info.estimated_update_seconds < best) route = Route::kUpdate;
  return route;
}
#endif

#define HARAP_REQUIRE_CHOLMOD(registry)                              \
  if (!(registry).Contains("cholmod")) {                             \
    WARN("skipped: this build has no CHOLMOD (HARAP_WITH_CHOLMOD)"); \
    return;                                                          \
  }

}  // namespace

TEST_CASE("refactor: every cholmod route solves the new matrix after handle edits",
          "[solvers][cholmod][refactor]") {
  const auto registry = LinearSolverRegistry();
  HARAP_REQUIRE_CHOLMOD(registry);
  const Context context;
  const SparseMatrix laplacian = GridLaplacian(kSide, kSide, 7);
  // Add a ball, remove part of it, add another ball overlapping it, remove everything but the
  // first row, then a small edit (one vertex in, one out).
  const std::set<Index> first = FirstRow();
  std::vector<std::set<Index>> steps;
  std::set<Index> handles = first;
  for (Index v : Ball(20, 20, 5.0)) handles.insert(v);
  steps.push_back(handles);
  for (Index v : Ball(20, 23, 3.0)) handles.erase(v);
  steps.push_back(handles);
  for (Index v : Ball(25, 25, 4.0)) handles.insert(v);
  steps.push_back(handles);
  steps.push_back(first);
  handles = first;
  handles.erase(3);
  handles.insert(kSide * kSide - 1);
  steps.push_back(handles);

  for (const std::string mode : {"auto", "simplicial", "supernodal"}) {
    for (const std::string refactor : {"auto", "full", "numeric", "update", "partial"}) {
      if (mode == "supernodal" && refactor == "update") continue;  // rejected, tested below
      DYNAMIC_SECTION(mode << ", refactor = " << refactor) {
        auto solver = MakeSolver(registry, "cholmod",
                                 "mode = \"" + mode + "\"\nrefactor = \"" + refactor + "\"");
        solver->PrepareForRefactor();  // as a session's level does (auto keeps copies only then)
        std::set<Index> current = first;
        SparseMatrix a = Masked(laplacian, current);
        solver->Factorize(a, context);
        RequireSolves(*solver, a, context);
        for (const auto& next : steps) {
          const std::vector<Index> changed = SymmetricDifference(current, next);
          a = Masked(laplacian, next);
          const auto summary = solver->Refactor(a, changed, context);
          CHECK(summary.changed_rows == static_cast<Index>(changed.size()));
          CHECK(summary.seconds >= 0.0);
          // auto never factors from scratch; on a supernodal factor it refactors numerically,
          // partial refactorizations only in mode auto.
          if (refactor == "auto") {
            CHECK(summary.route != Route::kFull);
            if (mode == "supernodal") CHECK(summary.route == Route::kNumeric);
            if (mode != "auto") CHECK(summary.route != Route::kPartial);
          } else {
            CHECK(summary.route == Expected(refactor, mode, summary.route));
          }
          RequireSolves(*solver, a, context);
          current = next;
        }
      }
    }
  }
}

TEST_CASE("refactor: auto takes the route its estimate says, large edits estimate far more",
          "[solvers][cholmod][refactor]") {
#ifdef HARAP_HAVE_CHOLMOD
  const auto registry = LinearSolverRegistry();
  HARAP_REQUIRE_CHOLMOD(registry);
  const Context context;
  const SparseMatrix laplacian = GridLaplacian(kSide, kSide, 11);
  auto solver = MakeSolver(registry, "cholmod");
  solver->PrepareForRefactor();
  const auto& cholmod = dynamic_cast<const CholmodSolver&>(*solver);
  std::set<Index> handles = FirstRow();
  SparseMatrix a = Masked(laplacian, handles);
  solver->Factorize(a, context);
  CHECK(cholmod.factor_info().numeric_seconds > 0.0);
  CHECK(cholmod.factor_info().analysis_seconds > 0.0);

  // One vertex: a few paths of the elimination tree. Every row but the first: each deletion
  // walks a path to the root, together far more than the whole factorization's work.
  std::set<Index> one = handles;
  one.insert(kSide * kSide / 2 + kSide / 2);
  a = Masked(laplacian, one);
  const auto small = solver->Refactor(a, SymmetricDifference(handles, one), context);
  const double small_estimate = cholmod.factor_info().estimated_update_seconds;
  // The partial refactorization recomputes a part of the work only, estimated below numeric.
  CHECK(cholmod.factor_info().partial_work_fraction > 0.0);
  CHECK(cholmod.factor_info().partial_work_fraction < 1.0);
  CHECK(cholmod.factor_info().estimated_partial_seconds <
        cholmod.factor_info().estimated_numeric_seconds);
  CHECK(small.route == AutoRoute(cholmod.factor_info(), true, true));
  RequireSolves(*solver, a, context);

  std::set<Index> most = one;
  for (Index v = kSide; v < kSide * kSide; v += 1) {
    if (v % kSide != 0) most.insert(v);  // column 0 stays free
  }
  a = Masked(laplacian, most);
  const auto large = solver->Refactor(a, SymmetricDifference(one, most), context);
  const double large_estimate = cholmod.factor_info().estimated_update_seconds;
  CHECK(large_estimate > 100.0 * small_estimate);
  // After an update the kept supernodal factor is stale: no partial route.
  CHECK(large.route == AutoRoute(cholmod.factor_info(), small.route != Route::kUpdate, true));
  if (large.route == Route::kUpdate) {
    WARN("the numeric factorization was timed slower than " << large_estimate
                                                            << " s (a loaded machine?)");
  }
  RequireSolves(*solver, a, context);
  // And back to the first handles: as many rows, each now an addition.
  a = Masked(laplacian, handles);
  solver->Refactor(a, SymmetricDifference(most, handles), context);
  RequireSolves(*solver, a, context);
#endif
}

TEST_CASE("refactor: routes can follow each other on one factor", "[solvers][cholmod][refactor]") {
#ifdef HARAP_HAVE_CHOLMOD
  const auto registry = LinearSolverRegistry();
  HARAP_REQUIRE_CHOLMOD(registry);
  const Context context;
  const SparseMatrix laplacian = GridLaplacian(kSide, kSide, 13);
  using Choice = CholmodSolver::RefactorChoice;
  for (const std::string mode : {"auto", "simplicial"}) {
    auto solver = MakeSolver(registry, "cholmod", "mode = \"" + mode + "\"");
    solver->PrepareForRefactor();
    auto& cholmod = dynamic_cast<CholmodSolver&>(*solver);
    std::set<Index> current = FirstRow();
    SparseMatrix a = Masked(laplacian, current);
    solver->Factorize(a, context);
    // Deletions, then additions (they move columns of the factor), then numeric on that
    // factor, partial refactorizations of it (mode auto), then an update of the refactored
    // one, partial (after an update: numeric, which makes partial possible again), numeric
    // again, then full.
    const std::vector<std::pair<std::set<Index>, Choice>> steps = {
        {Ball(10, 10, 6.0), Choice::kUpdate},  {Ball(10, 14, 3.0), Choice::kUpdate},
        {Ball(30, 30, 5.0), Choice::kNumeric}, {Ball(30, 25, 5.0), Choice::kPartial},
        {Ball(5, 5, 3.0), Choice::kPartial},   {Ball(25, 20, 4.0), Choice::kUpdate},
        {Ball(24, 20, 4.0), Choice::kPartial}, {Ball(20, 20, 2.0), Choice::kPartial},
        {Ball(20, 20, 3.0), Choice::kNumeric}, {Ball(5, 35, 4.0), Choice::kFull}};
    Choice previous = Choice::kFull;
    int step = 0;
    for (const auto& [ball, choice] : steps) {
      std::set<Index> next = FirstRow();
      next.insert(ball.begin(), ball.end());
      cholmod.set_refactor(choice);
      a = Masked(laplacian, next);
      const auto summary = solver->Refactor(a, SymmetricDifference(current, next), context);
      INFO("mode " << mode << ", step " << step++);
      const Route partial =
          mode == "auto" && previous != Choice::kUpdate ? Route::kPartial : Route::kNumeric;
      CHECK(summary.route == (choice == Choice::kUpdate    ? Route::kUpdate
                              : choice == Choice::kNumeric ? Route::kNumeric
                              : choice == Choice::kPartial ? partial
                                                           : Route::kFull));
      RequireSolves(*solver, a, context);
      current = next;
      previous = choice;
    }
  }
  auto supernodal = MakeSolver(registry, "cholmod", "mode = \"supernodal\"");
  CHECK_THROWS_AS(dynamic_cast<CholmodSolver&>(*supernodal).set_refactor(Choice::kUpdate),
                  InternalError);
#endif
}

TEST_CASE("refactor: a different pattern factors from scratch", "[solvers][cholmod][refactor]") {
  const auto registry = LinearSolverRegistry();
  HARAP_REQUIRE_CHOLMOD(registry);
  const Context context;
  for (const std::string refactor : {"auto", "numeric", "update", "partial"}) {
    auto solver = MakeSolver(registry, "cholmod", "refactor = \"" + refactor + "\"");
    solver->PrepareForRefactor();
    const std::set<Index> handles = FirstRow();
    solver->Factorize(Masked(GridLaplacian(kSide, kSide, 3), handles), context);
    // Another grid size, and the same size with one more edge.
    const SparseMatrix smaller = Masked(GridLaplacian(kSide - 1, kSide, 3), handles);
    CHECK(solver->Refactor(smaller, {}, context).route == Route::kFull);
    RequireSolves(*solver, smaller, context);
    SparseMatrix extra = GridLaplacian(kSide, kSide, 3);
    extra.coeffRef(kSide + 1, 3 * kSide + 7) -= 0.5;
    extra.coeffRef(3 * kSide + 7, kSide + 1) -= 0.5;
    extra.coeffRef(kSide + 1, kSide + 1) += 0.5;
    extra.coeffRef(3 * kSide + 7, 3 * kSide + 7) += 0.5;
    extra = Masked(extra, handles);
    CHECK(solver->Refactor(extra, {kSide + 1, 3 * kSide + 7}, context).route == Route::kFull);
    RequireSolves(*solver, extra, context);
    // Same pattern again: reused.
    const SparseMatrix back = Masked(GridLaplacian(kSide, kSide, 3), handles);
    solver->Factorize(back, context);
    CHECK(solver->Refactor(back, {}, context).route != Route::kFull);
    RequireSolves(*solver, back, context);
  }
}

TEST_CASE("refactor: misuse is an error that keeps the factor, a non-SPD result throws",
          "[solvers][cholmod][refactor]") {
  const auto registry = LinearSolverRegistry();
  HARAP_REQUIRE_CHOLMOD(registry);
  const Context context;
  const SparseMatrix laplacian = GridLaplacian(kSide, kSide, 5);
  const std::set<Index> handles = FirstRow();
  const SparseMatrix a = Masked(laplacian, handles);
  auto solver = MakeSolver(registry, "cholmod");
  solver->PrepareForRefactor();
  solver->Factorize(a, context);

  std::set<Index> more = handles;
  more.insert(100);
  more.insert(200);
  const SparseMatrix b = Masked(laplacian, more);
  // Unsorted or out of range rows, and a change outside the rows named.
  CHECK_THROWS_WITH(solver->Refactor(b, {200, 100}, context), Catch::Contains("sorted, unique"));
  CHECK_THROWS_WITH(solver->Refactor(b, {100, 200, 1600}, context),
                    Catch::Contains("sorted, unique"));
  CHECK_THROWS_WITH(solver->Refactor(b, {100}, context),
                    Catch::Contains("neither row") && Catch::Contains("200"));
  // The factor of `a` is intact.
  RequireSolves(*solver, a, context);

  // Row 100 coupled so strongly to its neighbours that the matrix is indefinite.
  SparseMatrix bad = a;
  for (SparseMatrix::InnerIterator it(bad, 100); it; ++it) {
    if (it.row() != 100) it.valueRef() *= 10.0;
  }
  for (Index j = 0; j < bad.outerSize(); ++j) {
    for (SparseMatrix::InnerIterator it(bad, j); it; ++it) {
      if (it.row() == 100 && it.col() != 100) it.valueRef() *= 10.0;
    }
  }
  for (const std::string refactor : {"update", "numeric", "partial"}) {
    auto forced = MakeSolver(registry, "cholmod", "refactor = \"" + refactor + "\"");
    forced->Factorize(a, context);
    CHECK_THROWS_AS(forced->Refactor(bad, {100}, context), NumericalError);
    Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 3);
    CHECK_THROWS_AS(forced->Solve(RandomRhs(a.rows(), 3, 1), x, context), InternalError);
    forced->Factorize(a, context);
    RequireSolves(*forced, a, context);
  }
}

TEST_CASE("refactor: auto keeps copies only after PrepareForRefactor, explicit routes always",
          "[solvers][cholmod][refactor]") {
#ifdef HARAP_HAVE_CHOLMOD
  const auto registry = LinearSolverRegistry();
  HARAP_REQUIRE_CHOLMOD(registry);
  const Context context;
  const SparseMatrix laplacian = GridLaplacian(kSide, kSide, 17);
  const std::set<Index> handles = FirstRow();
  std::set<Index> more = handles;
  for (Index v : Ball(20, 20, 4.0)) more.insert(v);
  const SparseMatrix a = Masked(laplacian, handles);
  const SparseMatrix b = Masked(laplacian, more);
  for (const std::string refactor : {"auto", "full", "numeric", "update", "partial"}) {
    for (const bool prepare : {false, true}) {
      DYNAMIC_SECTION("refactor = " << refactor << (prepare ? ", prepared" : "")) {
        auto solver = MakeSolver(registry, "cholmod", "refactor = \"" + refactor + "\"");
        const auto& cholmod = dynamic_cast<const CholmodSolver&>(*solver);
        if (prepare) solver->PrepareForRefactor();
        solver->Factorize(a, context);
        // A one-shot run (auto, not prepared) and "full" keep nothing; the others keep the
        // analysis and the matrix.
        const bool keeps = refactor == "numeric" || refactor == "update" || refactor == "partial" ||
                           (refactor == "auto" && prepare);
        CHECK((cholmod.factor_info().refactor_bytes > 0.0) == keeps);
        const auto summary = solver->Refactor(b, SymmetricDifference(handles, more), context);
        CHECK((summary.route != Route::kFull) == keeps);
        RequireSolves(*solver, b, context);
      }
    }
  }
#endif
}

TEST_CASE("refactor: options are validated", "[solvers][cholmod][refactor]") {
  const auto registry = LinearSolverRegistry();
  HARAP_REQUIRE_CHOLMOD(registry);
  CHECK_THROWS_WITH(MakeSolver(registry, "cholmod", "refactor = \"sometimes\""),
                    Catch::Contains("auto, full, numeric, update, partial"));
  CHECK_THROWS_WITH(MakeSolver(registry, "cholmod", "mode = \"supernodal\"\nrefactor = \"update\""),
                    Catch::Contains("refactor") && Catch::Contains("supernodal"));
  CHECK_NOTHROW(MakeSolver(registry, "cholmod", "mode = \"supernodal\"\nrefactor = \"numeric\""));
}

TEST_CASE("refactor: the other solvers factor from scratch and solve the new matrix",
          "[solvers][refactor]") {
  const auto registry = LinearSolverRegistry();
  const Context context;
  const SparseMatrix laplacian = GridLaplacian(12, 12, 9);
  std::set<Index> handles;
  for (Index v = 0; v < 12; ++v) handles.insert(v);
  const SparseMatrix a = Masked(laplacian, handles);
  std::set<Index> more = handles;
  more.insert(60);
  const SparseMatrix b = Masked(laplacian, more);
  for (const std::string& name : registry.Names()) {
    if (name == "cholmod") continue;
    DYNAMIC_SECTION(name) {
      auto solver = MakeAccurateSolver(registry, name);
      solver->Factorize(a, context);
      const auto summary = solver->Refactor(b, {60}, context);
      CHECK(summary.route == Route::kFull);
      CHECK(summary.changed_rows == 1);
      const Eigen::MatrixXd rhs = RandomRhs(b.rows(), 3, 2);
      Eigen::MatrixXd x = Eigen::MatrixXd::Zero(b.rows(), 3);
      REQUIRE(solver->Solve(rhs, x, context).success());
      CHECK(RelativeResidual(b, rhs, x) <= (IsIterative(registry, name) ? 1e-10 : 1e-12));
    }
  }
}

}  // namespace harap::testing
