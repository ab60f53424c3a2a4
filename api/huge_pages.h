// SPDX-License-Identifier: MIT
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace harap {

/// Transparent huge pages for malloc's memory.
///
/// A large run allocates and frees gigabytes, and glibc's malloc takes every block above its mmap
/// threshold (32 MiB at most) from the kernel and gives it back on free. The kernel hands such
/// memory out in 4 KiB pages, each zeroed and mapped by a page fault on its first write; on
/// virtual machines a fault costs microseconds, so a large run can spend more time in faults
/// than in arithmetic (docs/results.md, "Huge pages for malloc"). With 2 MiB transparent huge pages
/// one fault maps 512 times as much. Kernels in THP mode `madvise` (Debian's default on many
/// cloud images) give them only to memory that asks: glibc 2.35 and later ask for malloc's memory
/// when the tunable `glibc.malloc.hugetlb=1` is set in GLIBC_TUNABLES, read once at start-up. The
/// `harap` command and the benchmarks restart themselves with it where it matters
/// (cli/process_settings.h); programs that embed harap (Python) set it in their environment
/// (docs/python.md).

/// The kernel's THP mode, the bracketed word of /sys/kernel/mm/transparent_hugepage/enabled
/// ("always", "madvise", "never"); empty where the file is missing.
std::string TransparentHugePageMode();

/// Whether this glibc reads `glibc.malloc.hugetlb` (2.35 and later); false without glibc.
bool MallocHasHugePageTunable();

/// The value of `name` among the colon-separated `name=value` items of a GLIBC_TUNABLES string;
/// nullopt where the item is absent.
std::optional<std::string> TunableValue(std::string_view tunables, std::string_view name);

/// The GLIBC_TUNABLES string to restart with so that malloc's memory gets huge pages: `tunables`
/// with `glibc.malloc.hugetlb=1` appended, where the kernel gives huge pages only on request
/// (`thp_mode` "madvise"), glibc has the tunable and `tunables` does not set it already (a value
/// the user chose, 0 included, is kept). Otherwise nullopt: nothing to change.
std::optional<std::string> TunablesWithHugePages(std::string_view tunables,
                                                 std::string_view thp_mode, bool has_tunable);

/// Sets GLIBC_TUNABLES to TunablesWithHugePages() of its current value, this kernel and this
/// glibc; true if it changed it. The setting takes effect in a process started after it: the
/// `harap` command and the benchmarks then re-execute themselves. It also sets
/// HARAP_REQUESTED_HUGE_PAGES, and does nothing where that is set, so a chain of restarts asks
/// once. Processes started later inherit both (harap's own runs, the report scripts, a browser).
bool RequestHugePagesForMalloc();

/// How this process's malloc'd memory is backed: "always" (the kernel gives every anonymous
/// mapping huge pages), "malloc" (glibc asks for them: the process started with the tunable and
/// the kernel is in `madvise` mode) or "off" (4 KiB pages). Reported with the peak memory.
std::string HugePageBacking();

}  // namespace harap
