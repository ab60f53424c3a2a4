// SPDX-License-Identifier: MIT
#include "hierarchies/builders/level_limits.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "framework/error.h"

namespace harap {
namespace {

constexpr Range kMinVerticesRange = Range::AtLeast(0);
constexpr Range kMaxLevelsRange = Range::AtLeast(0);

}  // namespace

void LevelLimits::ReadLimits(OptionReader node) {
  min_vertices =
      node.Get("min_vertices", min_vertices,
               "stop once the coarsest level has at most this many vertices", kMinVerticesRange);
  max_levels =
      node.Get("max_levels", max_levels,
               "at most this many levels, the input included (0 = no limit)", kMaxLevelsRange);
}

std::vector<std::string> LevelLimits::LimitProblems() const {
  return RangeProblems({{"min_vertices", double(min_vertices), kMinVerticesRange},
                        {"max_levels", double(max_levels), kMaxLevelsRange}});
}

void ThrowIfInvalidOptions(std::string_view hierarchy, const std::vector<std::string>& problems) {
  if (!problems.empty()) {
    throw ConfigError(
        fmt::format("invalid {} hierarchy options: {}", hierarchy, fmt::join(problems, "; ")));
  }
}

MeshHierarchy InputLevelOnly(const Mesh& mesh) {
  MeshHierarchy hierarchy;
  hierarchy.levels.push_back(HierarchyLevel{mesh, {}, {}});
  return hierarchy;
}

}  // namespace harap
