// SPDX-License-Identifier: MIT
// CHOLMOD-specific behaviour (options, every mode × ordering, out of memory). Skipped when the
// build has no CHOLMOD (the registry then has no "cholmod").

#include "solvers/linear/cholmod_solver.h"

#include <dlfcn.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "framework/context.h"
#include "framework/error.h"
#include "tests/solvers/solver_test_matrices.h"

#if defined(__linux__)
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <sstream>
#endif

#if defined(__SANITIZE_ADDRESS__)
#define HARAP_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define HARAP_TEST_ASAN 1
#endif
#endif

namespace harap::testing {
namespace {

const std::vector<std::string> kModes = {"auto", "simplicial", "supernodal"};
const std::vector<std::string> kOrderings = {"metis", "amd", "best"};

// Threads of this process (Linux: entries of /proc/self/task; elsewhere 0).
long ThreadCount() {
#if defined(__linux__)
  long count = 0;
  for ([[maybe_unused]] const auto& entry :
       std::filesystem::directory_iterator("/proc/self/task")) {
    ++count;
  }
  return count;
#else
  return 0;
#endif
}

#define HARAP_REQUIRE_CHOLMOD(registry)                              \
  if (!(registry).Contains("cholmod")) {                             \
    WARN("skipped: this build has no CHOLMOD (HARAP_WITH_CHOLMOD)"); \
    return;                                                          \
  }

std::string Options(const std::string& mode, const std::string& ordering) {
  return "mode = \"" + mode + "\"\nordering = \"" + ordering + "\"\n";
}

}  // namespace

TEST_CASE("cholmod: invalid option values list the valid choices", "[solvers][cholmod]") {
  const auto registry = LinearSolverRegistry();
  HARAP_REQUIRE_CHOLMOD(registry);
  CHECK_THROWS_AS(MakeSolver(registry, "cholmod", "mode = \"fast\""), ConfigError);
  CHECK_THROWS_WITH(MakeSolver(registry, "cholmod", "mode = \"fast\""),
                    Catch::Contains("fast") && Catch::Contains("auto, simplicial, supernodal"));
  CHECK_THROWS_WITH(MakeSolver(registry, "cholmod", "ordering = \"nesdis\""),
                    Catch::Contains("metis, amd, best"));
  CHECK_THROWS_AS(MakeSolver(registry, "cholmod", "mode = 2"), ConfigError);
  CHECK_THROWS_WITH(MakeSolver(registry, "cholmod", "pivot_tolerance = 1.5"),
                    Catch::Contains("pivot_tolerance") && Catch::Contains("[0, 1)"));
  CHECK_THROWS_AS(MakeSolver(registry, "cholmod", "pivot_tolerance = -1e-3"), ConfigError);
  CHECK_THROWS_AS(MakeSolver(registry, "cholmod", "check_residual = \"yes\""), ConfigError);
  CHECK_THROWS_WITH(MakeSolver(registry, "cholmod", "mdoe = \"simplicial\""),
                    Catch::Contains("mode") && Catch::Contains("ordering") &&
                        Catch::Contains("check_residual") && Catch::Contains("pivot_tolerance"));
}

TEST_CASE("cholmod: native_threads caps CHOLMOD's OpenMP and BLAS threads, results agree",
          "[solvers][cholmod]") {
  const auto registry = LinearSolverRegistry();
  HARAP_REQUIRE_CHOLMOD(registry);
  CHECK_THROWS_WITH(MakeSolver(registry, "cholmod", "native_threads = -1"),
                    Catch::Contains("native_threads") && Catch::Contains(">= 0"));
  CHECK_THROWS_WITH(MakeSolver(registry, "cholmod", "native_thread = 1"),
                    Catch::Contains("native_threads"));

  // The controls the solver sets, read back where this process has them (Debian's CHOLMOD is
  // built with OpenMP; libblas.so.3 may or may not be OpenBLAS).
  using GetInt = int (*)();
  const auto omp_get_max_threads =
      reinterpret_cast<GetInt>(dlsym(RTLD_DEFAULT, "omp_get_max_threads"));
  const auto omp_get_dynamic = reinterpret_cast<GetInt>(dlsym(RTLD_DEFAULT, "omp_get_dynamic"));
  const auto openblas_get_num_threads =
      reinterpret_cast<GetInt>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));

  const Context context;
  const SparseMatrix a = PinnedGridLaplacian(120, 120, 21);
  const Eigen::MatrixXd b = RandomRhs(a.rows(), 3, 23);
  // Factors and solves on a new thread, which starts with OpenMP's defaults and, on its first
  // parallel region, gets a pool of OpenMP threads of its own that lives as long as it does: the
  // threads the process gained during the factorization are those CHOLMOD's OpenMP started.
  const auto solve = [&](int native_threads, long& new_threads) {
    Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 3);
    std::thread worker([&] {
      const int dynamic_before = omp_get_dynamic ? omp_get_dynamic() : 0;
      const int threads_before = omp_get_max_threads ? omp_get_max_threads() : 0;
      auto solver =
          MakeSolver(registry, "cholmod",
                     "mode = \"supernodal\"\nnative_threads = " + std::to_string(native_threads));
      const long before = ThreadCount();
      solver->Factorize(a, context);
      new_threads = ThreadCount() - before;
      // Only the factorization is capped: this thread's OpenMP settings are as they were.
      if (omp_get_dynamic) CHECK(omp_get_dynamic() == dynamic_before);
      if (omp_get_max_threads) CHECK(omp_get_max_threads() == threads_before);
      CHECK(solver->Solve(b, x, context).success());
    });
    worker.join();
    return x;
  };
  long capped_threads = 0, two_threads = 0, native_threads = 0;
  // What native_threads = 0 restores: the environment's count, whatever earlier tests set.
  solve(0, native_threads);
  const int default_blas_threads = openblas_get_num_threads ? openblas_get_num_threads() : 0;
  const Eigen::MatrixXd one = solve(1, capped_threads);
  if (openblas_get_num_threads) CHECK(openblas_get_num_threads() == 1);
  const Eigen::MatrixXd two = solve(2, two_threads);
  if (openblas_get_num_threads) CHECK(openblas_get_num_threads() == 2);
  const Eigen::MatrixXd environment = solve(0, native_threads);
  if (openblas_get_num_threads) CHECK(openblas_get_num_threads() == default_blas_threads);
  if (native_threads > 0) {
    // CHOLMOD's own OpenMP started threads; with the cap it started none.
    CHECK(capped_threads == 0);
  } else {
    WARN("CHOLMOD started no OpenMP threads here: the cap is not observable");
  }
  CHECK(RelativeResidual(a, b, one) < 1e-10);
  CHECK(RelativeDifference(two, one) < 1e-12);
  CHECK(RelativeDifference(environment, one) < 1e-12);
}

TEST_CASE("cholmod: StopIdleNativeThreads joins OpenBLAS's idle workers, more threads restart them",
          "[solvers][cholmod]") {
  const auto registry = LinearSolverRegistry();
  HARAP_REQUIRE_CHOLMOD(registry);
  using GetInt = int (*)();
  const auto openblas_get_num_threads =
      reinterpret_cast<GetInt>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
  const auto openblas_get_parallel =
      reinterpret_cast<GetInt>(dlsym(RTLD_DEFAULT, "openblas_get_parallel"));
  // 1: OpenBLAS's own pthreads server, whose workers the stop joins (with OpenMP there are none).
  if (!openblas_get_num_threads || !openblas_get_parallel || openblas_get_parallel() != 1 ||
      !dlsym(RTLD_DEFAULT, "blas_thread_shutdown_")) {
    WARN("the BLAS here is not OpenBLAS with its pthreads server: nothing to stop");
    return;
  }
  const Context context;
  const SparseMatrix a = PinnedGridLaplacian(120, 120, 21);
  const Eigen::MatrixXd b = RandomRhs(a.rows(), 3, 29);
  // On a thread of its own, whose OpenMP threads end with it: what stays is OpenBLAS's.
  const auto solve = [&](int native_threads) {
    Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 3);
    std::thread worker([&] {
      auto solver =
          MakeSolver(registry, "cholmod",
                     "mode = \"supernodal\"\nnative_threads = " + std::to_string(native_threads));
      solver->Factorize(a, context);
      CHECK(solver->Solve(b, x, context).success());
    });
    worker.join();
    return x;
  };
  const Eigen::MatrixXd one = solve(1);  // TBB's workers, which stay, exist from here on
  const Eigen::MatrixXd two = solve(2);  // OpenBLAS now has at least one worker
  REQUIRE(openblas_get_num_threads() == 2);
  const long with_workers = ThreadCount();
  CholmodSolver::StopIdleNativeThreads();
  CHECK(openblas_get_num_threads() == 1);
  const long stopped = ThreadCount();
  CHECK(stopped < with_workers);
  // One-thread factorizations leave OpenBLAS alone (no worker started again) ...
  const Eigen::MatrixXd one_again = solve(1);
  CHECK(ThreadCount() == stopped);
  // ... and one with more threads starts them again and computes the same.
  const Eigen::MatrixXd two_again = solve(2);
  CHECK(openblas_get_num_threads() == 2);
  CHECK(ThreadCount() > stopped);
  CHECK(RelativeResidual(a, b, one) < 1e-10);
  CHECK(RelativeDifference(two, one) < 1e-12);
  CHECK(RelativeDifference(two_again, two) == 0);
  CHECK(RelativeDifference(one_again, one) == 0);
  solve(0);  // OpenBLAS back at the environment's count, as the other tests expect
}

TEST_CASE("cholmod: every mode × ordering gives the same solution", "[solvers][cholmod]") {
  const auto registry = LinearSolverRegistry();
  HARAP_REQUIRE_CHOLMOD(registry);
  const Context context;
  // Large enough for METIS to partition and for supernodes to form.
  const SparseMatrix a = PinnedGridLaplacian(62, 62, 21);
  const Eigen::MatrixXd b = RandomRhs(a.rows(), 3, 22);
  // Catch2 reruns the test body once per section; the dense reference is computed once.
  static const Eigen::MatrixXd reference = Eigen::MatrixXd(a).llt().solve(b);
  for (const auto& mode : kModes) {
    for (const auto& ordering : kOrderings) {
      DYNAMIC_SECTION("mode = " << mode << ", ordering = " << ordering) {
        auto solver = MakeSolver(registry, "cholmod", Options(mode, ordering));
        solver->Factorize(a, context);
        Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 3);
        REQUIRE(solver->Solve(b, x, context).success());
        CHECK(RelativeResidual(a, b, x) < 1e-10);
        CHECK(RelativeDifference(x, reference) < 1e-10);

        // Tiny systems (METIS and supernodes degenerate there).
        Eigen::MatrixXd tiny(2, 2);
        tiny << 4.0, 1.0, 1.0, 3.0;
        for (const Eigen::Index n : {1, 2}) {
          const Eigen::MatrixXd dense = tiny.topLeftCorner(n, n);
          solver->Factorize(FromDense(dense), context);
          const Eigen::MatrixXd tiny_b = RandomRhs(n, 3, 26);
          Eigen::MatrixXd tiny_x = Eigen::MatrixXd::Zero(n, 3);
          REQUIRE(solver->Solve(tiny_b, tiny_x, context).success());
          CHECK(RelativeDifference(tiny_x, dense.llt().solve(tiny_b)) < 1e-14);
        }
      }
    }
  }
}

TEST_CASE("cholmod: the elimination-tree parallel solve matches CHOLMOD's own solve",
          "[solvers][cholmod]") {
  const auto registry = LinearSolverRegistry();
  HARAP_REQUIRE_CHOLMOD(registry);
  // A grid (balanced tree with METIS, AMD's tree otherwise), two disconnected grids (a forest),
  // and a path (the elimination tree is one chain: nothing runs in parallel).
  const SparseMatrix grid = PinnedGridLaplacian(90, 70, 31);
  const SparseMatrix forest = [&] {
    const Eigen::MatrixXd dense_a = Eigen::MatrixXd(PinnedGridLaplacian(30, 40, 32));
    const Eigen::MatrixXd dense_b = Eigen::MatrixXd(PinnedGridLaplacian(25, 20, 33));
    Eigen::MatrixXd both =
        Eigen::MatrixXd::Zero(dense_a.rows() + dense_b.rows(), dense_a.rows() + dense_b.rows());
    both.topLeftCorner(dense_a.rows(), dense_a.rows()) = dense_a;
    both.bottomRightCorner(dense_b.rows(), dense_b.rows()) = dense_b;
    return FromDense(both);
  }();
  const SparseMatrix path = PinnedGridLaplacian(3, 2000, 34);
  const std::vector<std::pair<std::string, const SparseMatrix*>> matrices = {
      {"grid", &grid}, {"forest", &forest}, {"path", &path}};
  for (const auto& [name, a] : matrices) {
    for (const std::string ordering : {"metis", "amd"}) {
      for (const int columns : {1, 3, 5}) {
        DYNAMIC_SECTION(name << ", " << ordering << ", " << columns << " columns") {
          const Eigen::MatrixXd b = RandomRhs(a->rows(), columns, 35);
          auto sequential = MakeSolver(registry, "cholmod",
                                       Options("auto", ordering) + "parallel_solve = false\n");
          const Context one_thread = Context::WithThreads(1);
          sequential->Factorize(*a, one_thread);
          Eigen::MatrixXd reference = Eigen::MatrixXd::Zero(a->rows(), columns);
          REQUIRE(sequential->Solve(b, reference, one_thread).success());
          REQUIRE(RelativeResidual(*a, b, reference) < 1e-10);

          Eigen::MatrixXd first;
          for (const int threads : {1, 2, 3, 8}) {
            const Context context = Context::WithThreads(threads);
            auto parallel = MakeSolver(registry, "cholmod", Options("auto", ordering));
            parallel->Factorize(*a, context);
#ifdef HARAP_HAVE_CHOLMOD
            const auto& info = dynamic_cast<const CholmodSolver&>(*parallel).factor_info();
            if (name != "path") {
              // The grid and the forest must really be split (else this test proves nothing).
              CHECK(info.solve_blocks >= 8);
              CHECK(info.solve_critical_path < 0.5);
            }
#endif
            Eigen::MatrixXd x = Eigen::MatrixXd::Constant(a->rows(), columns, 7.0);
            REQUIRE(parallel->Solve(b, x, context).success());
            CHECK(RelativeDifference(x, reference) < 1e-12);
            // Each entry is summed by one thread in a fixed order: bit-identical for any thread
            // count and schedule.
            if (first.size() == 0) {
              first = x;
            } else {
              CHECK((x.array() == first.array()).all());
            }
            Eigen::MatrixXd again = Eigen::MatrixXd::Zero(a->rows(), columns);
            REQUIRE(parallel->Solve(b, again, context).success());
            CHECK((again.array() == x.array()).all());
          }
        }
      }
    }
  }
}

TEST_CASE("cholmod: a one-shot factor frees CHOLMOD's row indices, a refactorable one keeps them",
          "[solvers][cholmod]") {
  const auto registry = LinearSolverRegistry();
  HARAP_REQUIRE_CHOLMOD(registry);
  const SparseMatrix a = PinnedGridLaplacian(60, 50, 41);
  SparseMatrix changed = a;  // row and column 7 changed (a larger diagonal entry)
  changed.coeffRef(7, 7) += 2.5;
  const SparseMatrix other = PinnedGridLaplacian(40, 30, 42);  // another pattern and size
  const Context context = Context::WithThreads(2);
  const Eigen::MatrixXd b = RandomRhs(a.rows(), 3, 43);
  const Eigen::MatrixXd b_other = RandomRhs(other.rows(), 3, 44);
  const auto solve = [&](LinearSolver& solver, const SparseMatrix& m, const Eigen::MatrixXd& rhs) {
    Eigen::MatrixXd x = Eigen::MatrixXd::Zero(m.rows(), rhs.cols());
    REQUIRE(solver.Solve(rhs, x, context).success());
    return RelativeResidual(m, rhs, x);
  };
#ifdef HARAP_HAVE_CHOLMOD
  const auto released = [](const LinearSolver& solver) {
    return dynamic_cast<const CholmodSolver&>(solver).factor_info().released_bytes;
  };
  const auto nnz_l = [](const LinearSolver& solver) {
    return dynamic_cast<const CholmodSolver&>(solver).factor_info().nnz_l;
  };
#endif
  for (const std::string mode : {"auto", "simplicial"}) {
    DYNAMIC_SECTION("one-shot, mode " << mode) {
      auto solver = MakeSolver(registry, "cholmod", Options(mode, "amd"));
      solver->Factorize(a, context);
#ifdef HARAP_HAVE_CHOLMOD
      CHECK(released(*solver) >= 4.0 * nnz_l(*solver));
#endif
      // Solves, repeatedly, from the tree's copy alone.
      CHECK(solve(*solver, a, b) < 1e-10);
      CHECK(solve(*solver, a, b) < 1e-10);
      // A new factorization, of another matrix, and a refactorization (a full one: nothing was
      // kept for a cheaper route) start from scratch.
      solver->Factorize(other, context);
      CHECK(solve(*solver, other, b_other) < 1e-10);
      solver->Factorize(a, context);
      const auto summary = solver->Refactor(changed, {7}, context);
      CHECK(summary.route == LinearSolver::RefactorRoute::kFull);
      CHECK(solve(*solver, changed, b) < 1e-10);
    }
  }
  SECTION("CHOLMOD's own solve needs its rows: kept") {
    auto solver =
        MakeSolver(registry, "cholmod", Options("auto", "amd") + "parallel_solve = false\n");
    solver->Factorize(a, context);
#ifdef HARAP_HAVE_CHOLMOD
    CHECK(released(*solver) == 0.0);
#endif
    CHECK(solve(*solver, a, b) < 1e-10);
  }
  SECTION("prepared for refactorization: kept, and the cheaper routes still work") {
    for (const std::string route : {"numeric", "update", "partial"}) {
      auto solver = MakeSolver(registry, "cholmod",
                               Options("auto", "amd") + "refactor = \"" + route + "\"\n");
      solver->PrepareForRefactor();
      solver->Factorize(a, context);
#ifdef HARAP_HAVE_CHOLMOD
      CHECK(released(*solver) == 0.0);
#endif
      const auto summary = solver->Refactor(changed, {7}, context);
      CHECK(summary.route != LinearSolver::RefactorRoute::kFull);
      CHECK(solve(*solver, changed, b) < 1e-10);
    }
  }
}

TEST_CASE("cholmod: the parallel supernodal factorization equals cholmod_factorize bit for bit",
          "[solvers][cholmod]") {
  const auto registry = LinearSolverRegistry();
  HARAP_REQUIRE_CHOLMOD(registry);
  // A grid (one tree, heavy separators at the top), a forest (two grids), a mesh in many pieces
  // (one grid and 300 tiny ones: more roots than the split ever makes pieces, as dragon-lift's
  // 151 components), a cube (3D, denser supernodes): numeric = "parallel" must give CHOLMOD's
  // own factor (same solutions to the last bit, which only the same factor values give) for
  // every thread count.
  const SparseMatrix grid = PinnedGridLaplacian(120, 90, 41);
  const SparseMatrix forest =
      BlockDiagonal({PinnedGridLaplacian(30, 40, 42), PinnedGridLaplacian(25, 20, 43)});
  std::vector<SparseMatrix> pieces = {PinnedGridLaplacian(100, 80, 46)};
  for (unsigned k = 0; k < 300; ++k) pieces.push_back(PinnedGridLaplacian(3, 3, 100 + k));
  const SparseMatrix many_pieces = BlockDiagonal(pieces);
  const SparseMatrix cube = PinnedCubeLaplacian(16);
  const std::vector<std::pair<std::string, const SparseMatrix*>> matrices = {
      {"grid", &grid}, {"forest", &forest}, {"many pieces", &many_pieces}, {"cube", &cube}};
  for (const auto& [name, a] : matrices) {
    for (const std::string mode : {"auto", "supernodal"}) {
      DYNAMIC_SECTION(name << ", mode " << mode) {
        const Eigen::MatrixXd b = RandomRhs(a->rows(), 3, 44);
        const Context one_thread = Context::WithThreads(1);
        auto reference_solver =
            MakeSolver(registry, "cholmod", Options(mode, "amd") + "numeric = \"cholmod\"\n");
        reference_solver->Factorize(*a, one_thread);
        Eigen::MatrixXd reference = Eigen::MatrixXd::Zero(a->rows(), 3);
        REQUIRE(reference_solver->Solve(b, reference, one_thread).success());
        REQUIRE(RelativeResidual(*a, b, reference) < 1e-10);
        for (const int threads : {1, 2, 3, 8}) {
          INFO(threads << " threads");
          const Context context = Context::WithThreads(threads);
          auto solver = MakeSolver(registry, "cholmod", Options(mode, "amd"));
          solver->Factorize(*a, context);
#ifdef HARAP_HAVE_CHOLMOD
          // Really split into subtrees (else this test proves nothing).
          const auto& info = dynamic_cast<const CholmodSolver&>(*solver).factor_info();
          CHECK((threads == 1) == (info.numeric_subtrees == 0));
          if (threads > 1) {
            CHECK(info.numeric_subtree_work > 0.1);
            // The large tree was split too, not only the forest into its trees.
            CHECK(info.numeric_largest_subtree < 0.5);
          }
#endif
          // Solved on one thread as the reference was (the parallel solve sums differently).
          Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a->rows(), 3);
          REQUIRE(solver->Solve(b, x, one_thread).success());
          CHECK((x.array() == reference.array()).all());
        }
      }
    }
  }
}

TEST_CASE("cholmod: the parallel factorization reports the first failing pivot in order",
          "[solvers][cholmod]") {
  const auto registry = LinearSolverRegistry();
  HARAP_REQUIRE_CHOLMOD(registry);
  // Four components (independent subtrees, so pieces of their own), three of them with an
  // indefinite 2×2 block (positive diagonal, a coupling larger than it): several pieces fail at
  // once, and the error must name the column the sequential order meets first, whatever the
  // thread count, the same as cholmod_factorize's.
  std::vector<SparseMatrix> components;
  for (unsigned k = 0; k < 4; ++k) {
    SparseMatrix grid = PinnedGridLaplacian(60, 50, 45 + k);
    if (k > 0) {
      const int row = 500 * static_cast<int>(k);
      const double coupling = 3.0 * std::max(grid.coeff(row, row), grid.coeff(row + 1, row + 1));
      grid.coeffRef(row, row + 1) = grid.coeffRef(row + 1, row) = coupling;
    }
    components.push_back(grid);
  }
  const SparseMatrix a = BlockDiagonal(components);
  const auto factorize = [&](const std::string& options, int threads, int* subtrees) {
    auto solver = MakeSolver(registry, "cholmod", Options("supernodal", "amd") + options);
    std::string outcome = "no error";
    try {
      solver->Factorize(a, Context::WithThreads(threads));
    } catch (const NumericalError& error) {
      outcome = error.what();
    }
#ifdef HARAP_HAVE_CHOLMOD
    *subtrees = dynamic_cast<const CholmodSolver&>(*solver).factor_info().numeric_subtrees;
#endif
    return outcome;
  };
  int subtrees = 0;
  const std::string expected = factorize("numeric = \"cholmod\"\n", 1, &subtrees);
  CHECK_THAT(expected, Catch::Contains("not positive definite") && Catch::Contains("column"));
  for (const int threads : {1, 2, 4}) {
    INFO(threads << " threads");
    CHECK(factorize("", threads, &subtrees) == expected);
#ifdef HARAP_HAVE_CHOLMOD
    CHECK((subtrees >= 4) == (threads > 1));  // the components were factored apart
#endif
  }
}

TEST_CASE("cholmod: a matrix whose pattern is not symmetric is rejected, not read out of bounds",
          "[solvers][cholmod]") {
  const auto registry = LinearSolverRegistry();
  HARAP_REQUIRE_CHOLMOD(registry);
  // Entries stored above the diagonal only: CHOLMOD's analysis sees the lower triangle, the
  // numeric factorization reads both; an entry outside the analysed pattern must not be
  // written into another supernode's rows.
  SparseMatrix a = PinnedGridLaplacian(40, 40, 48);
  for (int k = 0; k < 40; ++k) a.coeffRef(k, a.cols() - 1 - k) = -0.01;
  a.makeCompressed();
  auto solver = MakeSolver(registry, "cholmod", Options("supernodal", "amd"));
  CHECK_THROWS_WITH(solver->Factorize(a, Context::WithThreads(2)), Catch::Contains("symmetric"));
}

TEST_CASE("cholmod: every mode × ordering rejects indefinite and singular matrices",
          "[solvers][cholmod]") {
  const auto registry = LinearSolverRegistry();
  HARAP_REQUIRE_CHOLMOD(registry);
  const Context context;
  SparseMatrix indefinite = PinnedGridLaplacian(40, 40, 23);
  for (int i = 0; i < indefinite.rows(); ++i) indefinite.coeffRef(i, i) -= 0.5;
  const SparseMatrix singular = GridLaplacian(40, 40, 24);
  for (const auto& mode : kModes) {
    for (const auto& ordering : kOrderings) {
      DYNAMIC_SECTION("mode = " << mode << ", ordering = " << ordering) {
        auto solver = MakeSolver(registry, "cholmod", Options(mode, ordering));
        CHECK_THROWS_WITH(
            solver->Factorize(indefinite, context),
            Catch::Contains("not positive definite") && Catch::Contains("constrained vertex"));
        CHECK_THROWS_WITH(solver->Factorize(singular, context),
                          Catch::Contains("positive definite"));
        CHECK_THROWS_AS(solver->Factorize(singular, context), NumericalError);
        CHECK_THROWS_WITH(solver->Factorize(IndefiniteArrowMatrix(), context),
                          Catch::Contains("(row 0 of the 12×12 matrix"));
      }
    }
  }
}

TEST_CASE("cholmod: pivot_tolerance decides what counts as singular", "[solvers][cholmod]") {
  const auto registry = LinearSolverRegistry();
  HARAP_REQUIRE_CHOLMOD(registry);
  const Context context;
  // Nearly singular: one vertex hangs on by a weight of 1e-9 (pivot / diagonal ≈ 1e-9 / 2), a
  // small positive pivot that only the tolerance can flag.
  Eigen::MatrixXd dense(2, 2);
  dense << 2.0, -2.0, -2.0, 2.0 + 1e-9;
  const SparseMatrix a = FromDense(dense);
  const Eigen::MatrixXd b = RandomRhs(2, 3, 25);
  for (const std::string mode : {"simplicial", "supernodal"}) {
    DYNAMIC_SECTION("mode = " << mode) {
      const std::string options = "mode = \"" + mode + "\"\n";
      auto strict = MakeSolver(registry, "cholmod", options + "pivot_tolerance = 1e-6");
      CHECK_THROWS_WITH(strict->Factorize(a, context), Catch::Contains("numerically singular"));
      auto lenient = MakeSolver(registry, "cholmod", options + "pivot_tolerance = 1e-12");
      lenient->Factorize(a, context);
      Eigen::MatrixXd x = Eigen::MatrixXd::Zero(2, 3);
      CHECK(lenient->Solve(b, x, context).success());
      CHECK(RelativeDifference(x, dense.llt().solve(b)) < 1e-4);  // cond(A) ≈ 8e9.
    }
  }
}

#if defined(__linux__) && !defined(HARAP_TEST_ASAN)
namespace {

// Virtual memory of this process in bytes (VmSize), or 0 if unknown.
size_t VirtualMemoryBytes() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmSize:", 0) == 0) {
      std::istringstream fields(line.substr(7));
      size_t kilobytes = 0;
      fields >> kilobytes;
      return kilobytes * 1024;
    }
  }
  return 0;
}

struct ChildResult {
  int exit_code = -1;  ///< 0: NumericalError, 1: no exception, 2: other exception, 3: skipped.
  std::string message;
};

// Factorizes `a` in a forked child whose address space is capped at its current size plus
// `headroom` bytes, so the failure cannot disturb this process. Only async-signal-safe calls and
// the solver run in the child; it leaves with _exit (no Catch2 state is touched).
ChildResult FactorizeWithMemoryCap(const Registry<LinearSolver>& registry,
                                   const std::string& options, const SparseMatrix& a,
                                   size_t headroom) {
  int fds[2];
  if (pipe(fds) != 0) return {3, "pipe() failed"};
  const pid_t pid = fork();
  if (pid < 0) return {3, "fork() failed"};
  if (pid == 0) {
    close(fds[0]);
    int code = 1;
    std::string message = "Factorize() succeeded";
    try {
      auto solver = MakeSolver(registry, "cholmod", options);
      const Context context;
      rlimit limit{};
      getrlimit(RLIMIT_AS, &limit);
      const size_t cap = VirtualMemoryBytes() + headroom;
      if (VirtualMemoryBytes() == 0 || (limit.rlim_max != RLIM_INFINITY && cap > limit.rlim_max)) {
        code = 3;
        message = "cannot read VmSize or the hard RLIMIT_AS is too low";
      } else {
        limit.rlim_cur = cap;
        setrlimit(RLIMIT_AS, &limit);
        solver->Factorize(a, context);
      }
    } catch (const NumericalError& error) {
      code = 0;
      message = error.what();
    } catch (const std::exception& error) {
      code = 2;
      message = error.what();
    }
    const char* data = message.data();
    size_t left = message.size();
    while (left > 0) {
      const ssize_t written = write(fds[1], data, left);
      if (written <= 0) break;
      data += written;
      left -= static_cast<size_t>(written);
    }
    close(fds[1]);
    _exit(code);
  }
  close(fds[1]);
  ChildResult result;
  char buffer[4096];
  ssize_t got = 0;
  while ((got = read(fds[0], buffer, sizeof buffer)) > 0) result.message.append(buffer, got);
  close(fds[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return result;
}

}  // namespace

TEST_CASE("cholmod: running out of memory is a NumericalError suggesting an iterative solver",
          "[solvers][cholmod]") {
  const auto registry = LinearSolverRegistry();
  HARAP_REQUIRE_CHOLMOD(registry);
  // 40³ unknowns: A has 0.4M entries (the analysis needs a few MB) while L with AMD has ~20M
  // (~200 MB), so 64 MB of headroom fails in the numeric factorization itself.
  const SparseMatrix a = PinnedCubeLaplacian(40);
  for (const std::string mode : {"simplicial", "supernodal"}) {
    DYNAMIC_SECTION("mode = " << mode) {
      const ChildResult result =
          FactorizeWithMemoryCap(registry, Options(mode, "amd"), a, size_t{64} << 20);
      if (result.exit_code == 3) {
        WARN("skipped: " << result.message);
        return;
      }
      INFO(result.message);
      CHECK(result.exit_code == 0);
      CHECK_THAT(result.message,
                 Catch::Contains("out of memory") && Catch::Contains("factorization") &&
                     Catch::Contains("--solver cg") && Catch::Contains("gauss_seidel") &&
                     Catch::Contains("ordering = \"metis\""));
    }
  }
}
#endif

}  // namespace harap::testing
