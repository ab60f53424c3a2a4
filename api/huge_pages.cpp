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
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  const auto changed = TunablesWithHugePages(tunables != nullptr ? tunables : "",
                                             TransparentHugePageMode(), MallocHasHugePageTunable());
  if (!changed) return false;
  setenv("GLIBC_TUNABLES", changed->c_str(), 1);
  return true;
}

std::string HugePageBacking() {
  const std::string mode = TransparentHugePageMode();
  if (mode == "always") return "always";
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  if (mode == "madvise" && MallocHasHugePageTunable() && tunables != nullptr &&
      TunableValue(tunables, kHugePageTunable) == "1") {
    return "malloc";
  }
  return "off";
}

}  // namespace harap
