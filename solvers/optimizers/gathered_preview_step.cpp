// SPDX-License-Identifier: MIT
#include "solvers/optimizers/gathered_preview_step.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <random>

#include "framework/error.h"
#include "framework/level_solver.h"

namespace harap {

SolveSummary GatheredPreviewStep::Run(const Level& level, const std::vector<Index>& source,
                                      const Rotations& coarse, const std::vector<Index>& handles,
                                      const Positions& targets, Positions& positions,
                                      const Context& context) {
  HARAP_CHECK(level.energy.rotation_site() == RotationSite::kVertex &&
                  static_cast<Index>(source.size()) == level.energy.num_rotations(),
              "{} rotation sources for {} sites", source.size(), level.energy.num_rotations());
  const Index n = level.system.num_vertices();
  HARAP_CHECK(positions.rows() == n && targets.rows() == static_cast<Index>(handles.size()),
              "{} positions for {} vertices, {} targets for {} handles", positions.rows(), n,
              targets.rows(), handles.size());
  Positions& u = positions;
  Rotations& rotations = rotations_;
  for (size_t k = 0; k < handles.size(); ++k)
    u.row(handles[k]) = targets.row(static_cast<Index>(k));
  RhsMap& map = rhs_map_;
  if (map.num_coarse != static_cast<Index>(coarse.size()) || map.source != source) {
    BuildRhsMap(level, source, static_cast<Index>(coarse.size()), context);
  }
  if (!map.linear) {
    GatherRotations(source, coarse, rotations, context);
  }
  level.system.SetFixedPositions(u);
  SolveSummary summary;
  if (level.system.num_free() > 0) {
    rhs_.resize(n, 3);
    if (map.linear) {
      map.coarse.assign(coarse.begin(), coarse.end());
      map.coarse.push_back(Rotation::Identity());
      context.Run([&] {
        tbb::parallel_for(tbb::blocked_range<Index>(0, n, 4096),
                          [&](const tbb::blocked_range<Index>& range) {
                            for (Index j = range.begin(); j != range.end(); ++j) {
                              Eigen::Vector3d b = Eigen::Vector3d::Zero();
                              for (Index e = map.offset[j]; e < map.offset[j + 1]; ++e) {
                                b.noalias() += map.coarse[map.cluster[e]] * map.weight[e];
                              }
                              rhs_.row(j) = b.transpose();
                            }
                          });
      });
    } else {
      level.energy.AssembleRhs(rotations, rhs_, context);
    }
    level.system.ReducedRhs(rhs_, reduced_rhs_);
    if (!level.solver.is_direct()) level.system.GatherFree(u, reduced_x_);
    if (reduced_x_.rows() != reduced_rhs_.rows() || reduced_x_.cols() != reduced_rhs_.cols()) {
      reduced_x_.setZero(reduced_rhs_.rows(), reduced_rhs_.cols());
    }
    summary = level.solver.Solve(reduced_rhs_, reduced_x_, context);
    if (!summary.success()) {
      throw NumericalError(
          fmt::format("linear solve failed on level {}: {}", level.level, summary.message));
    }
    level.system.ScatterFree(reduced_x_, u);
  }
  return summary;
}

void GatheredPreviewStep::BuildRhsMap(const Level& level, const std::vector<Index>& source,
                                      Index num_coarse, const Context& context) {
  RhsMap& map = rhs_map_;
  map = RhsMap();
  map.source = source;
  map.num_coarse = num_coarse;
  const Index n = level.system.num_vertices();
  const Index clusters = num_coarse + 1;  // + the identity
  const auto cluster_of = [&](Index site) {
    return source[site] == kNoVertex ? num_coarse : source[site];
  };
  // The clusters each vertex's right-hand side may see: those of the sites of its closed
  // neighbourhood in A (an ARAP energy couples a vertex to the rotations of its elements'
  // vertices); the verification below catches an energy that reaches further.
  const SparseMatrix& a = level.energy.system_matrix();
  std::vector<Index> offset(n + 1, 0);
  std::vector<Index> near;
  std::vector<Index> mark(clusters, -1);
  for (Index j = 0; j < n; ++j) {
    const auto visit = [&](Index site) {
      const Index c = cluster_of(site);
      if (mark[c] != j) {
        mark[c] = j;
        near.push_back(c);
      }
    };
    visit(j);
    for (SparseMatrix::InnerIterator it(a, j); it; ++it) visit(static_cast<Index>(it.row()));
    offset[j + 1] = static_cast<Index>(near.size());
  }
  // Greedy coloring: clusters seen by one vertex get different colors.
  std::vector<std::vector<Index>> conflicts(clusters);
  for (Index j = 0; j < n; ++j) {
    for (Index e = offset[j]; e < offset[j + 1]; ++e) {
      for (Index f = offset[j]; f < offset[j + 1]; ++f) {
        if (e != f) conflicts[near[e]].push_back(near[f]);
      }
    }
  }
  std::vector<int> color(clusters, -1);
  int colors = 0;
  std::vector<char> used;
  for (Index c = 0; c < clusters; ++c) {
    used.assign(colors + 1, 0);
    for (Index d : conflicts[c]) {
      if (color[d] >= 0) used[color[d]] = 1;
    }
    int k = 0;
    while (used[k]) ++k;
    color[c] = k;
    colors = std::max(colors, k + 1);
  }
  // One probe per color: the identity on that color's sites, zero elsewhere; a vertex's row is
  // w_jc of the one cluster c of that color it sees, and zero if it sees none.
  std::vector<Eigen::Vector3d> weight(near.size(), Eigen::Vector3d::Zero());
  Rotations probe(source.size());
  Positions probe_rhs(n, 3);
  for (int k = 0; k < colors; ++k) {
    for (size_t s = 0; s < source.size(); ++s) {
      probe[s] = color[cluster_of(static_cast<Index>(s))] == k ? Rotation(Rotation::Identity())
                                                               : Rotation(Rotation::Zero());
    }
    level.energy.AssembleRhs(probe, probe_rhs, context);
    for (Index j = 0; j < n; ++j) {
      bool seen = false;
      for (Index e = offset[j]; e < offset[j + 1]; ++e) {
        if (color[near[e]] != k) continue;
        weight[e] = probe_rhs.row(j).transpose();
        seen = true;
      }
      if (!seen && probe_rhs.row(j).squaredNorm() != 0.0) return;  // reaches further: not used
    }
  }
  map.offset = std::move(offset);
  map.cluster = std::move(near);
  map.weight = std::move(weight);
  // Verify on arbitrary matrices (B is linear in them): the probed map must reproduce
  // AssembleRhs() to rounding, or it is not used.
  Rotations random_coarse(clusters);
  std::mt19937 generator(12345);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (Rotation& r : random_coarse) {
    for (int k = 0; k < 9; ++k) r(k) = uniform(generator);
  }
  for (size_t s = 0; s < source.size(); ++s) {
    probe[s] = random_coarse[cluster_of(static_cast<Index>(s))];
  }
  level.energy.AssembleRhs(probe, probe_rhs, context);
  double largest = 0.0, error = 0.0;
  for (Index j = 0; j < n; ++j) {
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    for (Index e = map.offset[j]; e < map.offset[j + 1]; ++e) {
      b += random_coarse[map.cluster[e]] * map.weight[e];
    }
    largest = std::max(largest, probe_rhs.row(j).cwiseAbs().maxCoeff());
    error = std::max(error, (probe_rhs.row(j).transpose() - b).cwiseAbs().maxCoeff());
  }
  map.linear = error <= 1e-12 * largest;
}

}  // namespace harap
