// SPDX-License-Identifier: MIT
#pragma once

namespace harap {

/// Settings of the `harap` process that its libraries read from the environment once, at
/// start-up, so that only a restart applies them. Called first thing in main(): where a setting
/// is missing it sets the environment and re-executes the program once (same PID, same
/// arguments; it carries on as it is if the re-execution fails). Values the user set are kept.
///
/// - Huge pages for malloc (api/huge_pages.h, RequestHugePagesForMalloc()):
///   `glibc.malloc.hugetlb=1` is added to GLIBC_TUNABLES where the kernel gives transparent huge
///   pages only on request.
/// - Under an address-space limit (`ulimit -v`): OPENBLAS_NUM_THREADS=1 and OMP_THREAD_LIMIT=1.
///   OpenBLAS and libgomp (both used inside CHOLMOD) handle failed allocations badly: OpenBLAS's
///   worker threads retry forever when their 128 MiB work buffer cannot be allocated (the process
///   then hangs at exit), and libgomp ends the process ("libgomp: Thread creation failed") when it
///   cannot create a thread. Allocations really fail only under such a limit; there both run
///   single-threaded, so that running out of memory ends in harap's own error message (CHOLMOD
///   asks for 4 OpenMP threads with num_threads(), which only the thread limit caps). TBB's
///   threads, which do harap's own parallel work, are unaffected. Measured in docs/robustness.md.
void RestartWithProcessSettings(char** argv);

}  // namespace harap
