// SPDX-License-Identifier: MIT
#include "hierarchies/builders/level_limits.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "framework/error.h"

namespace harap {
namespace {

constexpr Range kMinVerticesRange = Range::AtLeast(0);
constexpr Range kMaxLevelsRange = Range::AtLeast(0);
constexpr EnumNames<LevelLimits::Coarsest, 2> kCoarsestNames = {
    {{LevelLimits::Coarsest::kAtMost, "at_most"}, {LevelLimits::Coarsest::kAtLeast, "at_least"}}};

}  // namespace

void LevelLimits::ReadLimits(OptionReader node) {
  min_vertices =
      node.Get("min_vertices", min_vertices,
               "bound on the coarsest level's vertices, as `coarsest` says", kMinVerticesRange);
  coarsest = node.GetEnum("coarsest", coarsest, kCoarsestNames,
                          "at_most: coarsen until a level has at most min_vertices vertices; "
                          "at_least: add no level with fewer (the paper's Sec. 7)");
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

void DropCoarsestLevel(MeshHierarchy& hierarchy) {
  HARAP_CHECK(hierarchy.num_levels() > 1, "the input level cannot be dropped");
  hierarchy.levels.pop_back();
  hierarchy.levels.back().coarse_vertex = {};  // and their memory
  hierarchy.levels.back().in_cluster = {};
}

MeshHierarchy InputLevelOnly(const Mesh& mesh) {
  MeshHierarchy hierarchy;
  hierarchy.levels.push_back(HierarchyLevel{mesh, {}, {}});
  return hierarchy;
}

}  // namespace harap
