// SPDX-License-Identifier: MIT
// Compiled into harap_solvers only when CHOLMOD was found (see cholmod_solver.cpp).
#ifdef HARAP_HAVE_CHOLMOD

#include "solvers/linear/cholmod_native_threads.h"

#include <dlfcn.h>

#include <mutex>

#include "solvers/linear/cholmod_solver.h"

namespace harap {
namespace {

// The OpenMP and OpenBLAS controls found in the process, looked up once.
struct NativeThreadControls {
  using GetInt = int (*)();
  using SetInt = void (*)(int);
  GetInt omp_get_dynamic = nullptr;
  GetInt omp_get_max_threads = nullptr;
  SetInt omp_set_dynamic = nullptr;
  SetInt omp_set_num_threads = nullptr;
  SetInt openblas_set_num_threads = nullptr;
  // OpenBLAS's own blas_thread_shutdown_ (what its fork handler calls): joins the idle workers.
  GetInt blas_thread_shutdown = nullptr;
  // As the environment set it, read before harap changed anything: native_threads = 0 restores
  // it.
  int default_blas_threads = 0;
  std::mutex blas_mutex;
  int applied_blas_threads = 0;

  static NativeThreadControls& Get() {
    static NativeThreadControls controls;
    return controls;
  }
  bool has_openmp() const { return omp_set_num_threads != nullptr; }

 private:
  NativeThreadControls() {
    const auto get = [](const char* name) {
      return reinterpret_cast<GetInt>(dlsym(RTLD_DEFAULT, name));
    };
    const auto set = [](const char* name) {
      return reinterpret_cast<SetInt>(dlsym(RTLD_DEFAULT, name));
    };
    omp_get_dynamic = get("omp_get_dynamic");
    omp_get_max_threads = get("omp_get_max_threads");
    omp_set_dynamic = set("omp_set_dynamic");
    omp_set_num_threads = set("omp_set_num_threads");
    if (!omp_get_dynamic || !omp_get_max_threads || !omp_set_dynamic || !omp_set_num_threads) {
      omp_set_num_threads = nullptr;
    }
    const GetInt openblas_get_num_threads = get("openblas_get_num_threads");
    openblas_set_num_threads = set("openblas_set_num_threads");
    if (!openblas_get_num_threads || !openblas_set_num_threads) {
      openblas_set_num_threads = nullptr;
    } else {
      default_blas_threads = applied_blas_threads = openblas_get_num_threads();
      blas_thread_shutdown = get("blas_thread_shutdown_");
    }
  }
};

}  // namespace

void CholmodSolver::StopIdleNativeThreads() {
  NativeThreadControls& controls = NativeThreadControls::Get();
  if (controls.openblas_set_num_threads == nullptr || controls.blas_thread_shutdown == nullptr) {
    return;
  }
  const std::lock_guard lock(controls.blas_mutex);
  // One thread first: openblas_set_num_threads starts the workers again when none run, so after
  // this a one-thread factorization (applied_blas_threads already 1) never calls it.
  if (controls.applied_blas_threads != 1) {
    controls.openblas_set_num_threads(1);
    controls.applied_blas_threads = 1;
  }
  controls.blas_thread_shutdown();
}

ScopedNativeThreads::ScopedNativeThreads(int threads) {
  NativeThreadControls& controls = NativeThreadControls::Get();
  if (threads > 0 && controls.has_openmp()) {
    saved_dynamic_ = controls.omp_get_dynamic();
    saved_threads_ = controls.omp_get_max_threads();
    controls.omp_set_dynamic(1);
    controls.omp_set_num_threads(threads);
  }
  if (controls.openblas_set_num_threads != nullptr) {
    const int blas_threads = threads > 0 ? threads : controls.default_blas_threads;
    const std::lock_guard lock(controls.blas_mutex);
    if (blas_threads != controls.applied_blas_threads) {
      controls.openblas_set_num_threads(blas_threads);
      controls.applied_blas_threads = blas_threads;
    }
  }
}

ScopedNativeThreads::~ScopedNativeThreads() {
  if (saved_threads_ > 0) {
    NativeThreadControls& controls = NativeThreadControls::Get();
    controls.omp_set_dynamic(saved_dynamic_);
    controls.omp_set_num_threads(saved_threads_);
  }
}

}  // namespace harap

#endif  // HARAP_HAVE_CHOLMOD
