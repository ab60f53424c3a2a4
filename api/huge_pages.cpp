// SPDX-License-Identifier: MIT
#include "api/huge_pages.h"

#include <cstdio>
#include <cstdlib>
#include <fstream>
#ifdef __GLIBC__
#include <gnu/libc-version.h>
#endif

namespace harap {

namespace {

constexpr std::string_view kHugePageTunable = "glibc.malloc.hugetlb";
constexpr const char* kRequestedMarker = "HARAP_REQUESTED_HUGE_PAGES";

/// GLIBC_TUNABLES as this process was started with it (what glibc read), from
/// /proc/self/environ: setenv() after start-up changes the process's environment block, not it.
std::optional<std::string> StartupTunables() {
  std::ifstream file("/proc/self/environ", std::ios::binary);
  constexpr std::string_view kPrefix = "GLIBC_TUNABLES=";
  std::string entry;
  while (std::getline(file, entry, '\0')) {
    if (entry.starts_with(kPrefix)) return entry.substr(kPrefix.size());
  }
  return std::nullopt;
}

}  // namespace

std::string TransparentHugePageMode() {
  std::ifstream file("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string word;
  while (file >> word) {
    if (word.size() > 2 && word.front() == '[' && word.back() == ']') {
      return word.substr(1, word.size() - 2);
    }
  }
  return "";
}

bool MallocHasHugePageTunable() {
#ifdef __GLIBC__
  int major = 0, minor = 0;
  if (std::sscanf(gnu_get_libc_version(), "%d.%d", &major, &minor) != 2) return false;
  return major > 2 || (major == 2 && minor >= 35);
#else
  return false;
#endif
}

std::optional<std::string> TunableValue(std::string_view tunables, std::string_view name) {
  while (!tunables.empty()) {
    const size_t end = tunables.find(':');
    const std::string_view item = tunables.substr(0, end);
    const size_t equals = item.find('=');
    if (equals != std::string_view::npos && item.substr(0, equals) == name) {
      return std::string(item.substr(equals + 1));
    }
    if (end == std::string_view::npos) break;
    tunables.remove_prefix(end + 1);
  }
  return std::nullopt;
}

std::optional<std::string> TunablesWithHugePages(std::string_view tunables,
                                                 std::string_view thp_mode, bool has_tunable) {
  if (thp_mode != "madvise" || !has_tunable || TunableValue(tunables, kHugePageTunable)) {
    return std::nullopt;
  }
  std::string result(tunables);
  if (!result.empty()) result += ':';
  return result + std::string(kHugePageTunable) + "=1";
}

bool RequestHugePagesForMalloc() {
  // Once per chain of restarts, whatever happens to GLIBC_TUNABLES on the way (glibc erases it
  // for privileged programs, wrappers may scrub it): never a restart loop.
  if (std::getenv(kRequestedMarker) != nullptr) return false;
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  const auto changed = TunablesWithHugePages(tunables != nullptr ? tunables : "",
                                             TransparentHugePageMode(), MallocHasHugePageTunable());
  if (!changed) return false;
  setenv("GLIBC_TUNABLES", changed->c_str(), 1);
  setenv(kRequestedMarker, "1", 1);
  return true;
}

std::string HugePageBacking() {
  const std::string mode = TransparentHugePageMode();
  if (mode == "always") return "always";
  const std::optional<std::string> tunables = StartupTunables();
  if (mode == "madvise" && MallocHasHugePageTunable() && tunables &&
      TunableValue(*tunables, kHugePageTunable) == "1") {
    return "malloc";
  }
  return "off";
}

}  // namespace harap
