// SPDX-License-Identifier: MIT
#include "solvers/optimizers/vertex_ordering.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <utility>

#include "framework/error.h"

namespace harap {

namespace {

// Spreads the low 21 bits of x so that two zero bits follow each (3D Morton interleave).
uint64_t Spread(uint64_t x) {
  x &= 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffULL;
  x = (x | x << 16) & 0x1f0000ff0000ffULL;
  x = (x | x << 8) & 0x100f00f00f00f00fULL;
  x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
  x = (x | x << 2) & 0x1249249249249249ULL;
  return x;
}

// The indices 0..n-1 sorted by `key` (63 bits used), ties in index order: what sorting the
// pairs (key, index) gives, by a stable least-significant-digit radix sort (six passes of 11
// bits; a pass whose digit is the same for every key is skipped). Faster than a comparison sort
// of the pairs on one thread (dragon-lift's 437K vertices: 0.10 s for the whole ordering before,
// docs/results.md), and a level's setup often runs on one thread beside the other levels.
std::vector<Index> StableOrderByKey(const std::vector<uint64_t>& key) {
  constexpr int kBits = 11;
  constexpr size_t kBuckets = size_t{1} << kBits;
  const size_t n = key.size();
  std::vector<Index> order(n), scratch(n);
  std::iota(order.begin(), order.end(), Index{0});
  std::vector<size_t> start(kBuckets);
  for (int shift = 0; shift < 64; shift += kBits) {
    std::fill(start.begin(), start.end(), 0);
    for (size_t k = 0; k < n; ++k) ++start[(key[k] >> shift) & (kBuckets - 1)];
    if (n == 0 || start[(key[0] >> shift) & (kBuckets - 1)] == n) continue;
    size_t sum = 0;
    for (size_t& s : start) sum += std::exchange(s, sum);
    for (size_t k = 0; k < n; ++k) {
      const Index i = order[k];
      scratch[start[(key[i] >> shift) & (kBuckets - 1)]++] = i;
    }
    order.swap(scratch);
  }
  return order;
}

// body(k) for k in [0, count), in parallel (independent iterations).
template <typename Body>
void ForEach(Index count, Body&& body) {
  tbb::parallel_for(tbb::blocked_range<Index>(0, count, 8192),
                    [&](const tbb::blocked_range<Index>& range) {
                      for (Index k = range.begin(); k != range.end(); ++k) body(k);
                    });
}

}  // namespace

MeshOrdering LocalityOrdering(const Mesh& mesh) {
  const Index n = mesh.num_vertices();
  MeshOrdering ordering;
  const Eigen::RowVector3d lo = mesh.vertices.colwise().minCoeff();
  const Eigen::RowVector3d extent = mesh.vertices.colwise().maxCoeff() - lo;
  const double scale = extent.maxCoeff() > 0.0 ? ((1 << 21) - 1) / extent.maxCoeff() : 0.0;
  // The loops below are independent per vertex / element (the sorts are parallel already): in
  // parallel, the same permutation.
  std::vector<uint64_t> keys(n);
  ForEach(n, [&](Index v) {
    const Eigen::RowVector3d q = (mesh.vertices.row(v) - lo) * scale;
    keys[v] = Spread(static_cast<uint64_t>(q(0))) | Spread(static_cast<uint64_t>(q(1))) << 1 |
              Spread(static_cast<uint64_t>(q(2))) << 2;
  });
  ordering.old_vertex = StableOrderByKey(keys);  // ties broken by input index: deterministic
  ordering.new_vertex.resize(n);
  ForEach(n, [&](Index k) { ordering.new_vertex[ordering.old_vertex[k]] = k; });
  ordering.mesh.planar = mesh.planar;
  ordering.mesh.vertices.resize(n, 3);
  ForEach(n, [&](Index k) {
    ordering.mesh.vertices.row(k) = mesh.vertices.row(ordering.old_vertex[k]);
  });

  const Index m = mesh.num_elements();
  const int size = mesh.simplex_size();
  // Elements by their smallest new vertex index, ties in input order: a counting sort (the keys
  // are < n).
  std::vector<Index> smallest(m);
  ForEach(m, [&](Index e) {
    Index s = n;
    for (int a = 0; a < size; ++a) s = std::min(s, ordering.new_vertex[mesh.elements(e, a)]);
    smallest[e] = s;
  });
  std::vector<Index> start(n + 1, 0);
  for (Index e = 0; e < m; ++e) ++start[smallest[e] + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  ordering.old_element.resize(m);
  for (Index e = 0; e < m; ++e) ordering.old_element[start[smallest[e]]++] = e;
  ordering.new_element.resize(m);
  ordering.mesh.elements.resize(m, size);
  ForEach(m, [&](Index k) {
    const Index e = ordering.old_element[k];
    ordering.new_element[e] = k;
    for (int a = 0; a < size; ++a)
      ordering.mesh.elements(k, a) = ordering.new_vertex[mesh.elements(e, a)];
  });
  return ordering;
}

Positions MeshOrdering::ToNew(const Positions& input) const {
  Positions result(input.rows(), input.cols());
  ForEach(static_cast<Index>(old_vertex.size()),
          [&](Index k) { result.row(k) = input.row(old_vertex[k]); });
  return result;
}

void MeshOrdering::ToOld(const Positions& renumbered, Positions& out) const {
  out.resize(renumbered.rows(), renumbered.cols());
  ForEach(static_cast<Index>(old_vertex.size()),
          [&](Index k) { out.row(old_vertex[k]) = renumbered.row(k); });
}

std::vector<std::vector<Index>> RenumberForLocality(const MeshOrdering& finest,
                                                    MeshHierarchy& hierarchy) {
  const int levels = hierarchy.num_levels();
  HARAP_CHECK(levels > 0 && hierarchy.levels[0].mesh.num_vertices() ==
                                static_cast<Index>(finest.old_vertex.size()),
              "a hierarchy of {} levels for a renumbering of {} vertices", levels,
              finest.old_vertex.size());
  // The coarse levels' orderings (their meshes moved into the levels below).
  std::vector<MeshOrdering> coarse(levels);
  for (int l = 1; l < levels; ++l) coarse[l] = LocalityOrdering(hierarchy.levels[l].mesh);
  const auto ordering = [&](int l) -> const MeshOrdering& { return l == 0 ? finest : coarse[l]; };
  std::vector<std::vector<Index>> built(levels);
  for (int l = 0; l < levels; ++l) {
    HierarchyLevel& level = hierarchy.levels[l];
    const std::vector<Index>& old_vertex = ordering(l).old_vertex;
    if (l + 1 < levels) {
      const std::vector<Index>& new_coarse = ordering(l + 1).new_vertex;
      std::vector<Index> coarse_vertex(old_vertex.size());
      for (size_t k = 0; k < old_vertex.size(); ++k) {
        const Index c = level.coarse_vertex[old_vertex[k]];
        coarse_vertex[k] = c == kNoVertex ? kNoVertex : new_coarse[c];
      }
      level.coarse_vertex = std::move(coarse_vertex);
      if (!level.in_cluster.empty()) {
        std::vector<unsigned char> in_cluster(old_vertex.size());
        for (size_t k = 0; k < old_vertex.size(); ++k)
          in_cluster[k] = level.in_cluster[old_vertex[k]];
        level.in_cluster = std::move(in_cluster);
      }
    }
    level.mesh = l == 0 ? finest.mesh : std::move(coarse[l].mesh);
    if (l > 0) built[l] = std::move(coarse[l].new_vertex);
  }
  return built;
}

}  // namespace harap
