// SPDX-License-Identifier: MIT
// LinearSolver::Solve() must not allocate after its first call (the global step runs it every
// iteration). Counted by interposing malloc/calloc/realloc in this executable (glibc: forwards to
// __libc_*), which also sees CHOLMOD's and BLAS's allocations through the dynamic linker.

#include <dlfcn.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <catch2/catch.hpp>
#include <cstddef>
#include <cstdlib>
#include <new>
#include <string>
#include <string_view>
#include <vector>

#include "framework/context.h"
#include "tests/solvers/solver_test_matrices.h"

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define HARAP_TEST_SANITIZER 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || \
    __has_feature(memory_sanitizer)
#define HARAP_TEST_SANITIZER 1
#endif
#endif

// Sanitizers replace malloc themselves; then the test is skipped.
#if defined(__GLIBC__) && !defined(HARAP_TEST_SANITIZER)
#define HARAP_COUNT_ALLOCATIONS 1

namespace {
std::atomic<bool> counting{false};
std::atomic<long> allocations{0};
// Who called malloc/calloc/realloc, for the first allocations counted: classified afterwards
// (dladdr) without allocating while counting.
std::array<void*, 4096> callers;

void Count(void* caller) {
  if (counting.load(std::memory_order_relaxed)) {
    const long k = allocations.fetch_add(1, std::memory_order_relaxed);
    if (k < static_cast<long>(callers.size())) callers[k] = caller;
  }
}
}  // namespace

extern "C" {
void* __libc_malloc(size_t size);
void* __libc_calloc(size_t count, size_t size);
void* __libc_realloc(void* pointer, size_t size);

void* malloc(size_t size) {
  Count(__builtin_return_address(0));
  return __libc_malloc(size);
}
void* calloc(size_t count, size_t size) {
  Count(__builtin_return_address(0));
  return __libc_calloc(count, size);
}
void* realloc(void* pointer, size_t size) {
  Count(__builtin_return_address(0));
  return __libc_realloc(pointer, size);
}
}
#endif

namespace harap::testing {

#ifdef HARAP_COUNT_ALLOCATIONS
namespace {

// Allocations made while running `f`.
template <class F>
long AllocationsIn(F&& f) {
  allocations = 0;
  counting = true;
  f();
  counting = false;
  return allocations.load();
}

// Of the allocations the last AllocationsIn() counted, those that BLAS made itself. OpenBLAS
// 0.3.21 (Debian 12) makes some on AVX-512 machines: its small-matrix dgemm kernel for
// SkylakeX/CooperLake takes a 512-byte buffer from malloc on every call (seen on an AMD EPYC with
// avx512_bf16, where it picks the COOPERLAKE kernels), and CHOLMOD's supernodal solve makes such
// products. harap cannot avoid them; every other allocation is a failure.
long AllocationsByBlas() {
  const long counted = std::min<long>(allocations.load(), static_cast<long>(callers.size()));
  long by_blas = 0;
  for (long k = 0; k < counted; ++k) {
    Dl_info info{};
    if (dladdr(callers[k], &info) != 0 && info.dli_fname != nullptr &&
        std::string_view(info.dli_fname).find("blas") != std::string_view::npos) {
      ++by_blas;
    }
  }
  return by_blas;
}

}  // namespace

TEST_CASE("linear solvers: the allocation counter sees allocations", "[solvers]") {
  // Guards the test below against an interposition that silently stopped working.
  // Called through volatile pointers so the compiler cannot elide the allocation pairs.
  void* (*volatile allocate)(size_t) = &std::malloc;
  void (*volatile release)(void*) = &std::free;
  void* (*volatile allocate_new)(size_t) = static_cast<void* (*)(size_t)>(&::operator new);
  void (*volatile release_new)(void*) = static_cast<void (*)(void*)>(&::operator delete);
  CHECK(AllocationsIn([&] { release(allocate(64)); }) == 1);
  CHECK(AllocationsByBlas() == 0);  // made here, not in BLAS
  CHECK(AllocationsIn([&] { release_new(allocate_new(64)); }) == 1);
  CHECK(AllocationsIn([] {}) == 0);
}

TEST_CASE("linear solvers: Solve() does not allocate after its first call", "[solvers]") {
  const auto registry = LinearSolverRegistry();
  const SparseMatrix a = PinnedGridLaplacian(47, 47, 31);
  const Eigen::MatrixXd b = RandomRhs(a.rows(), 3, 32);
  std::vector<std::string> configurations;
  for (const auto& name : registry.Names()) configurations.push_back(name);
  // Supernodal CHOLMOD solves go through BLAS, simplicial ones do not: both are covered.
  if (registry.Contains("cholmod")) {
    configurations = {"cholmod simplicial", "cholmod supernodal"};
    for (const auto& name : registry.Names()) {
      if (name != "cholmod") configurations.push_back(name);
    }
  }
  for (const auto& configuration : configurations) {
    DYNAMIC_SECTION(configuration) {
      const auto space = configuration.find(' ');
      const std::string name = configuration.substr(0, space);
      const std::string options =
          space == std::string::npos ? "" : "mode = \"" + configuration.substr(space + 1) + "\"";
      auto solver = MakeSolver(registry, name, options);
      const Context context;
      solver->Factorize(a, context);
      Eigen::MatrixXd x = Eigen::MatrixXd::Zero(a.rows(), 3);
      REQUIRE(solver->Solve(b, x, context).success());
      SolveSummary summary;
      const long count = AllocationsIn([&] {
        for (int i = 0; i < 3; ++i) summary = solver->Solve(b, x, context);
      });
      CHECK(summary.success());
      const long by_blas = AllocationsByBlas();
      if (by_blas > 0) {
        WARN(configuration << ": " << by_blas << " allocations in 3 solves made inside BLAS "
                           << "(this machine's BLAS allocates in small matrix products)");
      }
      CHECK(count - by_blas == 0);
    }
  }
}
#else
TEST_CASE("linear solvers: Solve() does not allocate after its first call", "[solvers]") {
  WARN("skipped: allocation counting needs glibc and no sanitizer");
}
#endif

}  // namespace harap::testing
