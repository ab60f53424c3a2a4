// SPDX-License-Identifier: MIT
#pragma once
// Part of the CHOLMOD solver (cholmod_solver.h): used only by sources compiled with CHOLMOD
// (HARAP_HAVE_CHOLMOD).

namespace harap {

/// Caps CHOLMOD's own parallelism (CholmodSolver::Options::native_threads) at `threads` while it
/// lives; 0 leaves it as the environment set it. That parallelism is the OpenMP loops of
/// CHOLMOD's supernodal factorization and the BLAS it calls. Their controls are looked up at run
/// time (dlsym): they exist only when CHOLMOD was built with OpenMP and the BLAS behind
/// libblas.so.3 is OpenBLAS, and harap itself is not compiled with -fopenmp (that would also
/// switch on Eigen's OpenMP code paths); without them this does nothing.
///
/// OpenMP's controls are per thread: this thread's are set, and restored at the end, so only the
/// factorization is capped. CHOLMOD's loops say num_threads(4), which omp_set_num_threads alone
/// does not override; with dynamic adjustment on, libgomp bounds the team by this thread's
/// nthreads-var (OpenMP 5.2, §2.6.1: with dyn-var true the implementation may deliver fewer
/// threads than requested). The solves are left alone: libgomp allocates a new team for every
/// one-thread region (it caches only larger teams), and Solve() must not allocate.
///
/// OpenBLAS's thread count is process-wide and not restored: it is set only when it changes, so
/// concurrent factorizations with the same setting never touch it while another is inside BLAS.
/// Why the default caps at 1: docs/solvers.md ("Why native_threads = 1").
class ScopedNativeThreads {
 public:
  explicit ScopedNativeThreads(int threads);
  ~ScopedNativeThreads();
  ScopedNativeThreads(const ScopedNativeThreads&) = delete;
  ScopedNativeThreads& operator=(const ScopedNativeThreads&) = delete;

 private:
  int saved_dynamic_ = 0;
  int saved_threads_ = 0;  // 0: nothing to restore
};

}  // namespace harap
