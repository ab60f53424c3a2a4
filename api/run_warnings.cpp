// SPDX-License-Identifier: MIT
#include "api/run_warnings.h"

#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <utility>

namespace harap {

namespace {

// Soup thresholds: a handful of loose triangles beside a body is a defect the checks already
// list; a soup is when stray pieces are the rule.
constexpr size_t kSoupMinComponents = 10;
constexpr Index kTinyComponentElements = 2;

}  // namespace

bool LooksLikeTriangleSoup(const MeshCheckReport& checks) {
  if (checks.components.size() < kSoupMinComponents) return false;
  const auto tiny = std::count_if(
      checks.components.begin(), checks.components.end(),
      [](const MeshComponentInfo& c) { return c.elements <= kTinyComponentElements; });
  return 2 * static_cast<size_t>(tiny) > checks.components.size();
}

std::vector<std::string> RunWarnings(const RunWarningInput& input) {
  std::vector<std::string> warnings;
  const Scenario& scenario = *input.scenario;
  const MeshCheckReport& solved = *input.solved_checks;
  const OptimizeResult& result = *input.result;
  const bool triangles = solved.kind == ElementKind::kTriangle;
  const char* element = triangles ? "triangle" : "tetrahedron";

  if (LooksLikeTriangleSoup(solved)) {
    const auto tiny = std::count_if(
        solved.components.begin(), solved.components.end(),
        [](const MeshComponentInfo& c) { return c.elements <= kTinyComponentElements; });
    std::string advice;
    const Index duplicates = input.input_checks->duplicate_vertices.count;
    if (duplicates > 0 && solved.duplicate_vertices.count > 0) {
      advice = fmt::format(
          "The input has {} vertices at the same position as another: weld them with --set "
          "mesh.weld_duplicates=true (or [mesh] weld_duplicates = true)",
          duplicates);
    } else {
      advice =
          "No corners share a position, so welding would not help: the mesh file itself "
          "needs repair (merge close vertices in a mesh editor)";
    }
    const Index largest = solved.components.front().elements;
    const char* elements = triangles ? "triangles" : "tetrahedra";
    warnings.push_back(fmt::format(
        "the mesh is a {} soup: {} separate pieces, {} of them one or two {} (the largest: {} "
        "{}); each piece deforms on its own and the energy adds up unrelated pieces, so the "
        "result and its energy mean little. {}",
        element, solved.components.size(), tiny, elements, largest,
        largest == 1 ? element : elements, advice));
  }

  // Handles that share vertices: MergedConstraints gives such a vertex the first handle's target.
  std::map<std::pair<size_t, size_t>, Index> shared;  // (earlier handle, later handle) → count
  std::vector<int> owner(static_cast<size_t>(scenario.mesh.num_vertices()), -1);
  for (size_t h = 0; h < scenario.handles.size(); ++h) {
    for (const Index v : scenario.handles[h].vertices) {
      if (v < 0 || v >= scenario.mesh.num_vertices()) continue;
      if (owner[v] < 0) {
        owner[v] = static_cast<int>(h);
      } else if (owner[v] != static_cast<int>(h)) {
        ++shared[{static_cast<size_t>(owner[v]), h}];
      }
    }
  }
  for (const auto& [pair, count] : shared) {
    const auto& [first, second] = pair;
    warnings.push_back(fmt::format(
        "handles '{}' and '{}' overlap: {} vertices are selected by both and follow '{}' (the "
        "earlier handle); narrow one selection if they should not",
        scenario.handles[first].name, scenario.handles[second].name, count,
        scenario.handles[first].name));
  }

  if (!result.levels.empty() && result.levels.front().unknowns == 0) {
    warnings.push_back(fmt::format(
        "the handles leave no vertex free ({} constrained of {}): every vertex sits at its "
        "target and nothing was optimized (the 0 iterations mean that, not convergence); "
        "select fewer vertices",
        result.constraints.constrained_vertices, scenario.mesh.num_vertices()));
  }

  // (An interrupted run may end with one coarse level solved: that is no one-level hierarchy.)
  if (input.hierarchical && result.levels.size() == 1 && result.levels.front().level == 0) {
    const Index vertices = result.levels.front().vertices;
    warnings.push_back(fmt::format(
        "the hierarchy has a single level: the mesh ({} vertices) is too small for a coarser "
        "level under hierarchy.min_vertices (750 by default; no level is made from a mesh at or "
        "below it, nor, with hierarchy.coarsest = \"at_least\", a level below it), so this ran "
        "as classic ARAP on one level. Lower it, e.g. --set hierarchy.min_vertices={}{}",
        vertices, std::max<Index>(4, vertices / 8),
        triangles ? ", or refine the mesh (scenario `refine = 1` or 2)" : ""));
  }
  // Negative weights: the energy is no longer a sum of squares (docs/energies.md, "Weight
  // schemes"), so its value and minimizer mean something else than the user expects.
  std::string negative_levels;
  for (const LevelResult& level : result.levels) {
    if (!level.weights.can_be_negative) continue;
    negative_levels +=
        fmt::format("{}level {} ({} of {} edges, weights {}, E = {:.6g})",
                    negative_levels.empty() ? "" : "; ", level.level, level.weights.negative_edges,
                    level.weights.edges, level.weights.scheme, level.energy);
  }
  if (!negative_levels.empty()) {
    const std::string final_energy =
        result.energy < 0.0 ? fmt::format(
                                  " The final energy E = {:.9e} is below zero: it is not the ARAP "
                                  "energy of a converged deformation, whatever `converged` says.",
                                  result.energy)
                            : std::string();
    warnings.push_back(fmt::format(
        "negative edge weights on {}: obtuse angles give those edges a negative cotangent "
        "weight, so the energy is not a sum of squares there, is not bounded below and can be "
        "negative, and the minimization exploits the negative terms (a coarse level that runs "
        "away spoils the finer ones).{} Use weights that are never negative: --set "
        "energy.weights=intrinsic_delaunay (and energy.coarse_weights=intrinsic_delaunay)",
        negative_levels, final_energy));
  }
  return warnings;
}

}  // namespace harap
