// SPDX-License-Identifier: MIT
// Compiled into harap_solvers only when CHOLMOD was found (see cholmod_solver.cpp).
#ifdef HARAP_HAVE_CHOLMOD

#include "solvers/linear/blas_work_buffer.h"

#include <cholmod.h>

#include <cstdlib>

namespace harap {

bool EnsureBlasWorkBuffer() {
  thread_local bool ready = false;
  if (ready) return true;
  void* probe = std::malloc(kBlasBufferProbeBytes);
  if (probe == nullptr) return false;
  std::free(probe);
  cholmod_common common;
  cholmod_start(&common);
  common.print = 0;
  common.error_handler = nullptr;
  common.supernodal = CHOLMOD_SUPERNODAL;
  cholmod_sparse* one = cholmod_speye(1, 1, CHOLMOD_REAL, &common);
  if (one != nullptr) {
    one->stype = -1;
    cholmod_factor* factor = cholmod_analyze(one, &common);
    if (factor != nullptr) ready = cholmod_factorize(one, factor, &common) != 0;
    cholmod_free_factor(&factor, &common);
    cholmod_free_sparse(&one, &common);
  }
  cholmod_finish(&common);
  return ready;
}

}  // namespace harap

#endif  // HARAP_HAVE_CHOLMOD
