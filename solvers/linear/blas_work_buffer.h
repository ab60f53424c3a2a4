// SPDX-License-Identifier: MIT
#pragma once
// Part of the CHOLMOD solver (cholmod_solver.h): used only by sources compiled with CHOLMOD
// (HARAP_HAVE_CHOLMOD).

#include <cstddef>

namespace harap {

/// What EnsureBlasWorkBuffer() checks can still be allocated: twice OpenBLAS's work buffer.
inline constexpr size_t kBlasBufferProbeBytes = size_t{256} << 20;

/// Makes sure the calling thread's BLAS work buffer exists before a supernodal factorization;
/// false if it could not be made (out of memory: the caller reports it).
///
/// Why: OpenBLAS (Debian's BLAS for CHOLMOD) allocates a work buffer of 128 MiB of address space
/// on a thread's first BLAS call and, if that allocation fails, retries forever. CHOLMOD's
/// supernodal factorization makes its first BLAS call (dpotrf) only after allocating the factor,
/// i.e. when memory may be nearly exhausted: under an address-space limit (`ulimit -v`) running
/// out of memory then hung instead of failing (docs/robustness.md, "Resource limits"). So before
/// the first supernodal factorization on a thread this probes whether kBlasBufferProbeBytes can
/// still be allocated and, if so, factors a 1×1 matrix supernodally: OpenBLAS allocates its buffer
/// then, and keeps it for later calls. Once per thread; later calls return true at once.
bool EnsureBlasWorkBuffer();

}  // namespace harap
