// SPDX-License-Identifier: MIT
#include "hierarchies/octree_hierarchy.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "framework/error.h"

namespace harap {
namespace {

/// Bits per axis of the integer coordinates: three of them fit a 64-bit cell key.
constexpr int kMaxBits = 21;

constexpr std::array<std::pair<std::string_view, OctreeHierarchy::CoarsePositions>, 2>
    kCoarsePositionNames = {{{"mean", OctreeHierarchy::CoarsePositions::kMean},
                             {"quantized", OctreeHierarchy::CoarsePositions::kQuantized}}};

/// Elements per TBB task in the parallel loops (they are cheap per element).
constexpr std::size_t kGrain = 4096;

template <class F>
void ParallelFor(std::size_t n, F&& f) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kGrain),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i) f(i);
                    });
}

/// Union–find whose root is always the smallest member: parent[i] ≤ i holds throughout, so one
/// increasing sweep flattens it.
inline Index Find(Index* parent, Index i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];  // path halving keeps parent[i] ≤ i
    i = parent[i];
  }
  return i;
}

inline void Union(Index* parent, Index a, Index b) {
  a = Find(parent, a);
  b = Find(parent, b);
  if (a < b) {
    parent[b] = a;
  } else if (b < a) {
    parent[a] = b;
  }
}

struct KeyedIndex {
  std::uint64_t key;
  Index index;
};

/// Stable LSD radix sort of `items` by the low `bits` bits of their keys (11-bit digits).
void RadixSort(std::vector<KeyedIndex>& items, std::vector<KeyedIndex>& scratch, int bits) {
  constexpr int kDigitBits = 11;
  constexpr std::size_t kBuckets = std::size_t{1} << kDigitBits;
  std::array<std::size_t, kBuckets> count;
  scratch.resize(items.size());
  for (int shift = 0; shift < bits; shift += kDigitBits) {
    count.fill(0);
    for (const KeyedIndex& item : items) ++count[(item.key >> shift) & (kBuckets - 1)];
    std::size_t sum = 0;
    for (std::size_t& c : count) sum += std::exchange(c, sum);
    for (const KeyedIndex& item : items) scratch[count[(item.key >> shift) & (kBuckets - 1)]++] = item;
    items.swap(scratch);
  }
}

/// The integer grid of Eq. (2).
struct Quantization {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< b_min
  Eigen::Vector3d step = Eigen::Vector3d::Zero();    ///< cell length (b_max − b_min)/(2^q − 1)
  std::array<int, 3> bits = {0, 0, 0};               ///< q_d
  int max_bits = 0;

  /// Bits per axis of a cell coordinate at `shift`.
  std::array<int, 3> BitsAt(int shift) const {
    return {std::max(bits[0] - shift, 0), std::max(bits[1] - shift, 0),
            std::max(bits[2] - shift, 0)};
  }

  /// World position of the centre of cell `cell` (coordinates w >> shift), clipped to the
  /// bounding box.
  Eigen::Vector3d CellCentre(const std::uint32_t* cell, int shift) const {
    Eigen::Vector3d p;
    for (int d = 0; d < 3; ++d) {
      const std::int64_t top = (std::int64_t{1} << bits[d]) - 1;
      const std::int64_t lo = std::int64_t{cell[d]} << shift;
      const std::int64_t hi = std::min(((std::int64_t{cell[d]} + 1) << shift) - 1, top);
      p[d] = origin[d] + 0.5 * double(lo + hi) * step[d];
    }
    return p;
  }
};

/// Mean length of the unique element edges, edges bucketed by their smaller end.
double MeanUniqueEdgeLength(const Mesh& mesh, std::vector<Index>& offsets,
                            std::vector<Index>& others, std::vector<Index>& stamp) {
  const Index n = mesh.num_vertices();
  const int k = mesh.simplex_size();
  const Index* e = mesh.elements.data();
  const std::size_t entries = std::size_t(mesh.num_elements()) * k;
  offsets.assign(n + 1, 0);
  auto for_each_pair = [&](auto&& f) {
    for (std::size_t t = 0; t < entries; t += k) {
      for (int a = 0; a < k; ++a) {
        for (int b = a + 1; b < k; ++b) f(e[t + a], e[t + b]);
      }
    }
  };
  for_each_pair([&](Index a, Index b) { ++offsets[std::min(a, b) + 1]; });
  for (Index i = 0; i < n; ++i) offsets[i + 1] += offsets[i];
  others.resize(offsets[n]);
  stamp.assign(offsets.begin(), offsets.end() - 1);  // fill cursors
  for_each_pair([&](Index a, Index b) {
    const auto [lo, hi] = std::minmax(a, b);
    others[stamp[lo]++] = hi;
  });
  std::fill(stamp.begin(), stamp.end(), kNoVertex);
  double sum = 0.0;
  std::size_t count = 0;
  const Positions& v = mesh.vertices;
  for (Index a = 0; a < n; ++a) {
    for (Index j = offsets[a]; j < offsets[a + 1]; ++j) {
      const Index b = others[j];
      if (stamp[b] == a) continue;
      stamp[b] = a;
      sum += (v.row(a) - v.row(b)).norm();
      ++count;
    }
  }
  return count ? sum / double(count) : 0.0;
}

/// Sorted copy of element `t`'s first k entries (k ≤ 4).
inline std::array<Index, 4> SortedTuple(const Index* t, int k) {
  std::array<Index, 4> s = {t[0], t[1], t[2], k == 4 ? t[3] : std::numeric_limits<Index>::max()};
  std::sort(s.begin(), s.end());
  return s;
}

/// Builds the coarse levels. All buffers are sized for level 0 once and reused.
class Builder {
 public:
  Builder(const OctreeHierarchy::Options& options, MeshHierarchy& hierarchy)
      : options_(options), hierarchy_(hierarchy) {}

  void Run() {
    // At most one level per shift 1..kMaxBits − 1 besides level 0: references stay valid.
    hierarchy_.levels.reserve(kMaxBits + 1);
    const Mesh& input = hierarchy_.levels[0].mesh;
    k_ = input.simplex_size();
    SetUpFinestLevel(input);
    int shift = 0;
    for (;;) {
      const Index n = hierarchy_.levels.back().mesh.num_vertices();
      if (options_.max_levels > 0 && hierarchy_.num_levels() >= options_.max_levels) break;
      if (n <= options_.min_vertices) break;
      int next_shift = shift + 1;
      for (; next_shift < grid_.max_bits; ++next_shift) {
        if (Cluster(hierarchy_.levels.back().mesh, next_shift - shift, next_shift) < n) break;
      }
      if (next_shift >= grid_.max_bits) break;
      if (!AddCoarseLevel(next_shift - shift, next_shift)) break;
      shift = next_shift;
    }
  }

 private:
  void SetUpFinestLevel(const Mesh& mesh) {
    const Index n = mesh.num_vertices();
    const std::size_t entries = std::size_t(mesh.num_elements()) * k_;
    referenced_.assign(n, 0);
    const Index* e = mesh.elements.data();
    for (std::size_t j = 0; j < entries; ++j) referenced_[e[j]] = 1;

    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector3d hi = -lo;
    for (Index i = 0; i < n; ++i) {
      if (!referenced_[i]) continue;
      lo = lo.cwiseMin(mesh.vertices.row(i).transpose());
      hi = hi.cwiseMax(mesh.vertices.row(i).transpose());
    }
    const double mean_edge = MeanUniqueEdgeLength(mesh, offsets_, others_, index_scratch_);
    grid_.origin = lo;
    for (int d = 0; d < 3; ++d) {
      const double extent = hi[d] - lo[d];
      int q = 0;
      if (mean_edge > 0.0 && extent > mean_edge) {
        q = static_cast<int>(std::ceil(std::log2(extent / mean_edge + 1.0)));
        // Guard against rounding in log2: the cell must not exceed Ē.
        while (q < kMaxBits && extent / double((std::int64_t{1} << q) - 1) > mean_edge) ++q;
        q = std::min(q, kMaxBits);
      }
      grid_.bits[d] = q;
      grid_.step[d] = q > 0 ? extent / double((std::int64_t{1} << q) - 1) : 0.0;
      grid_.max_bits = std::max(grid_.max_bits, q);
    }

    cells_.assign(3 * std::size_t(n), 0);
    sums_.resize(3 * std::size_t(n));
    counts_.resize(n);
    ParallelFor(n, [&](std::size_t i) {
      for (int d = 0; d < 3; ++d) sums_[3 * i + d] = mesh.vertices(i, d);
      counts_[i] = referenced_[i] ? 1 : 0;
      if (!referenced_[i]) return;
      for (int d = 0; d < 3; ++d) {
        const int q = grid_.bits[d];
        if (q == 0) continue;
        const double top = double((std::int64_t{1} << q) - 1);
        const double t = (mesh.vertices(i, d) - lo[d]) / (hi[d] - lo[d]);
        const double w = std::floor(top * t + 0.5);
        cells_[3 * i + d] = static_cast<std::uint32_t>(std::clamp(w, 0.0, top));
      }
    });
    level0_ = true;

    // Buffers for all levels, sized for the largest (level 0).
    keys_.reserve(n);
    parent_.reserve(n);
    label_.reserve(n);
    sorted_.reserve(n);
    sort_scratch_.reserve(n);
    mapped_.reserve(entries);
    keep_.reserve(mesh.num_elements());
    next_cells_.reserve(3 * std::size_t(n));
    next_sums_.reserve(3 * std::size_t(n));
    next_counts_.reserve(n);
  }

  /// Cell key of every vertex of the current level at `shift` (its cell coordinates shifted by
  /// `delta`), packed with the bits the coordinates need.
  void ComputeKeys(Index n, int delta, int shift) {
    const std::array<int, 3> b = grid_.BitsAt(shift);
    keys_.resize(n);
    ParallelFor(n, [&](std::size_t i) {
      const std::uint32_t* c = &cells_[3 * i];
      keys_[i] = (std::uint64_t{c[0] >> delta} << (b[1] + b[2])) |
                 (std::uint64_t{c[1] >> delta} << b[2]) | std::uint64_t{c[2] >> delta};
    });
  }

  /// Clusters the current level's vertices at `shift` into parent_ (roots = smallest members);
  /// returns the number of clusters (unreferenced vertices are singletons).
  Index Cluster(const Mesh& mesh, int delta, int shift) {
    const Index n = mesh.num_vertices();
    ComputeKeys(n, delta, shift);
    parent_.resize(n);
    for (Index i = 0; i < n; ++i) parent_[i] = i;
    Index* parent = parent_.data();
    if (options_.topology_aware) {
      const Index* e = mesh.elements.data();
      const std::size_t entries = std::size_t(mesh.num_elements()) * k_;
      for (std::size_t t = 0; t < entries; t += k_) {
        for (int a = 0; a < k_; ++a) {
          const Index va = e[t + a];
          const std::uint64_t key = keys_[va];
          for (int b = a + 1; b < k_; ++b) {
            if (keys_[e[t + b]] == key) Union(parent, va, e[t + b]);
          }
        }
      }
    } else {
      // Every referenced vertex of a cell joins the cell's first (smallest) vertex.
      sorted_.clear();
      for (Index i = 0; i < n; ++i) {
        if (!level0_ || referenced_[i]) sorted_.push_back({keys_[i], i});
      }
      const std::array<int, 3> b = grid_.BitsAt(shift);
      RadixSort(sorted_, sort_scratch_, b[0] + b[1] + b[2]);
      for (std::size_t j = 1; j < sorted_.size(); ++j) {
        if (sorted_[j].key == sorted_[j - 1].key) parent[sorted_[j].index] = parent[sorted_[j - 1].index];
      }
    }
    // Flatten (parent[i] ≤ i) and label clusters in the order of their smallest member.
    label_.resize(n);
    num_clusters_ = 0;
    for (Index i = 0; i < n; ++i) {
      const Index p = parent[parent[i]];
      parent[i] = p;
      label_[i] = p == i ? num_clusters_++ : label_[p];
    }
    return num_clusters_;
  }

  /// Builds level l+1 from the clusters in label_; false if no element survives.
  bool AddCoarseLevel(int delta, int shift) {
    HierarchyLevel& fine_level = hierarchy_.levels.back();
    const Mesh& fine = fine_level.mesh;
    const Index n = fine.num_vertices();
    const Index m = fine.num_elements();
    const int k = k_;

    // Eq. (5)/(10): an element survives iff its vertices lie in k different clusters.
    mapped_.resize(std::size_t(m) * k);
    keep_.resize(m);
    const Index* e = fine.elements.data();
    ParallelFor(m, [&](std::size_t t) {
      Index* c = &mapped_[t * k];
      for (int a = 0; a < k; ++a) c[a] = label_[e[t * k + a]];
      bool distinct = c[0] != c[1] && c[0] != c[2] && c[1] != c[2];
      if (k == 4) distinct = distinct && c[3] != c[0] && c[3] != c[1] && c[3] != c[2];
      keep_[t] = distinct ? 1 : 0;
    });
    RemoveDuplicates(m);

    // Compact the used clusters (in label order) into coarse indices.
    std::vector<Index>& coarse_of = index_scratch_;
    coarse_of.assign(num_clusters_, kNoVertex);
    Index coarse_elements = 0;
    for (Index t = 0; t < m; ++t) {
      if (!keep_[t]) continue;
      ++coarse_elements;
      for (int a = 0; a < k; ++a) coarse_of[mapped_[std::size_t(t) * k + a]] = 0;
    }
    if (coarse_elements == 0) return false;
    Index num_coarse = 0;
    for (Index c = 0; c < num_clusters_; ++c) {
      if (coarse_of[c] == 0) coarse_of[c] = num_coarse++;
    }

    HierarchyLevel coarse_level;
    Mesh& coarse = coarse_level.mesh;
    coarse.planar = fine.planar;
    coarse.elements.resize(coarse_elements, k);
    for (Index t = 0, out = 0; t < m; ++t) {
      if (!keep_[t]) continue;
      for (int a = 0; a < k; ++a) coarse.elements(out, a) = coarse_of[mapped_[std::size_t(t) * k + a]];
      ++out;
    }

    // Fine → coarse map.
    fine_level.coarse_vertex.resize(n);
    fine_level.in_cluster.resize(n);
    Index unresolved = 0;
    for (Index i = 0; i < n; ++i) {
      const Index c = coarse_of[label_[i]];
      fine_level.coarse_vertex[i] = c;
      fine_level.in_cluster[i] = c != kNoVertex ? 1 : 0;
      if (c == kNoVertex && (!level0_ || referenced_[i])) ++unresolved;
    }
    if (unresolved > 0) MapToClosestSurvivor(fine, fine_level, unresolved);

    // Per-vertex state of the coarse level: cell, sum and count of the finest members.
    next_cells_.resize(3 * std::size_t(num_coarse));
    next_sums_.assign(3 * std::size_t(num_coarse), 0.0);
    next_counts_.assign(num_coarse, 0);
    for (Index i = 0; i < n; ++i) {
      if (!fine_level.in_cluster[i]) continue;
      const Index c = fine_level.coarse_vertex[i];
      for (int d = 0; d < 3; ++d) {
        next_cells_[3 * std::size_t(c) + d] = cells_[3 * std::size_t(i) + d] >> delta;
        next_sums_[3 * std::size_t(c) + d] += sums_[3 * std::size_t(i) + d];
      }
      next_counts_[c] += counts_[i];
    }
    cells_.swap(next_cells_);
    sums_.swap(next_sums_);
    counts_.swap(next_counts_);
    level0_ = false;

    coarse.vertices.resize(num_coarse, 3);
    ParallelFor(num_coarse, [&](std::size_t c) {
      coarse.vertices.row(c) = Eigen::RowVector3d(sums_[3 * c], sums_[3 * c + 1], sums_[3 * c + 2]) /
                               double(counts_[c]);
    });
    if (options_.coarse_positions == OctreeHierarchy::CoarsePositions::kQuantized) {
      SetQuantizedPositions(coarse, shift);
    }
    if (coarse.planar) coarse.vertices.col(2).setZero();
    hierarchy_.levels.push_back(std::move(coarse_level));
    return true;
  }

  /// Clears keep_ for surviving elements whose cluster set equals that of an earlier survivor.
  void RemoveDuplicates(Index m) {
    const int k = k_;
    // Bucket survivors by their smallest cluster (counting sort, stable in element order).
    offsets_.assign(std::size_t(num_clusters_) + 1, 0);
    for (Index t = 0; t < m; ++t) {
      if (!keep_[t]) continue;
      const Index* c = &mapped_[std::size_t(t) * k];
      ++offsets_[*std::min_element(c, c + k) + 1];
    }
    for (Index c = 0; c < num_clusters_; ++c) offsets_[c + 1] += offsets_[c];
    others_.resize(offsets_[num_clusters_]);
    index_scratch_.assign(offsets_.begin(), offsets_.end() - 1);
    for (Index t = 0; t < m; ++t) {
      if (!keep_[t]) continue;
      const Index* c = &mapped_[std::size_t(t) * k];
      others_[index_scratch_[*std::min_element(c, c + k)]++] = t;
    }
    std::vector<std::pair<std::array<Index, 4>, Index>> bucket;
    for (Index c = 0; c < num_clusters_; ++c) {
      const Index begin = offsets_[c], end = offsets_[c + 1];
      if (end - begin < 2) continue;
      bucket.clear();
      for (Index j = begin; j < end; ++j) {
        bucket.emplace_back(SortedTuple(&mapped_[std::size_t(others_[j]) * k], k), others_[j]);
      }
      std::sort(bucket.begin(), bucket.end());  // equal tuples: first element first
      for (std::size_t j = 1; j < bucket.size(); ++j) {
        if (bucket[j].first == bucket[j - 1].first) keep_[bucket[j].second] = 0;
      }
    }
  }

  /// Multi-source BFS in the fine vertex–edge graph from the vertices whose cluster survived to
  /// the `unresolved` referenced vertices whose cluster did not: each takes the coarse vertex of
  /// its closest survivor (hop distance; ties → lowest coarse index).
  void MapToClosestSurvivor(const Mesh& fine, HierarchyLevel& level, Index unresolved) {
    const Index n = fine.num_vertices();
    const Index m = fine.num_elements();
    const int k = k_;
    const Index* e = fine.elements.data();
    std::vector<Index>& coarse = level.coarse_vertex;
    const std::vector<unsigned char>& in_cluster = level.in_cluster;

    // Local ids of the unresolved vertices and their incident elements (CSR).
    std::vector<Index> local(n, kNoVertex);
    std::vector<Index> vertices;
    vertices.reserve(unresolved);
    for (Index i = 0; i < n; ++i) {
      if (!in_cluster[i] && (!level0_ || referenced_[i])) {
        local[i] = static_cast<Index>(vertices.size());
        vertices.push_back(i);
      }
    }
    std::vector<Index> offsets(vertices.size() + 1, 0);
    for (std::size_t j = 0; j < std::size_t(m) * k; ++j) {
      if (local[e[j]] != kNoVertex) ++offsets[local[e[j]] + 1];
    }
    for (std::size_t u = 0; u < vertices.size(); ++u) offsets[u + 1] += offsets[u];
    std::vector<Index> incident(offsets.back());
    std::vector<Index> cursor(offsets.begin(), offsets.end() - 1);
    for (std::size_t j = 0; j < std::size_t(m) * k; ++j) {
      if (local[e[j]] != kNoVertex) incident[cursor[local[e[j]]]++] = static_cast<Index>(j / k);
    }

    constexpr Index kUnset = -1, kPending = -2;
    std::vector<Index> distance(vertices.size(), kUnset);
    std::vector<Index> frontier, next;
    // Layer 1: unresolved vertices with a neighbour whose cluster survived.
    for (std::size_t u = 0; u < vertices.size(); ++u) {
      Index best = kNoVertex;
      for (Index j = offsets[u]; j < offsets[u + 1]; ++j) {
        const Index* t = &e[std::size_t(incident[j]) * k];
        for (int a = 0; a < k; ++a) {
          if (in_cluster[t[a]] && (best == kNoVertex || coarse[t[a]] < best)) best = coarse[t[a]];
        }
      }
      if (best != kNoVertex) {
        coarse[vertices[u]] = best;
        distance[u] = 1;
        frontier.push_back(static_cast<Index>(u));
      }
    }
    for (Index layer = 1; !frontier.empty(); ++layer) {
      next.clear();
      for (Index u : frontier) {
        for (Index j = offsets[u]; j < offsets[u + 1]; ++j) {
          const Index* t = &e[std::size_t(incident[j]) * k];
          for (int a = 0; a < k; ++a) {
            const Index w = local[t[a]];
            if (w != kNoVertex && distance[w] == kUnset) {
              distance[w] = kPending;
              next.push_back(w);
            }
          }
        }
      }
      for (Index w : next) {
        Index best = kNoVertex;
        for (Index j = offsets[w]; j < offsets[w + 1]; ++j) {
          const Index* t = &e[std::size_t(incident[j]) * k];
          for (int a = 0; a < k; ++a) {
            const Index x = local[t[a]];
            if (x != kNoVertex && distance[x] == layer &&
                (best == kNoVertex || coarse[t[a]] < best)) {
              best = coarse[t[a]];
            }
          }
        }
        coarse[vertices[w]] = best;
        distance[w] = layer + 1;
      }
      frontier.swap(next);
    }
  }

  /// Cell centres at `shift`; clusters sharing a cell (a cell split by the topology check) keep
  /// the mean position already in coarse.vertices.
  void SetQuantizedPositions(Mesh& coarse, int shift) {
    const Index n = coarse.num_vertices();
    const std::array<int, 3> b = grid_.BitsAt(shift);
    std::vector<unsigned char> split(n, 0);
    if (options_.topology_aware) {
      sorted_.resize(n);
      for (Index c = 0; c < n; ++c) {
        const std::uint32_t* cell = &cells_[3 * std::size_t(c)];
        sorted_[c] = {(std::uint64_t{cell[0]} << (b[1] + b[2])) | (std::uint64_t{cell[1]} << b[2]) |
                          std::uint64_t{cell[2]},
                      c};
      }
      RadixSort(sorted_, sort_scratch_, b[0] + b[1] + b[2]);
      for (Index j = 1; j < n; ++j) {
        if (sorted_[j].key == sorted_[j - 1].key) {
          split[sorted_[j].index] = split[sorted_[j - 1].index] = 1;
        }
      }
    }
    ParallelFor(n, [&](std::size_t c) {
      if (!split[c]) coarse.vertices.row(c) = grid_.CellCentre(&cells_[3 * c], shift).transpose();
    });
  }

  const OctreeHierarchy::Options& options_;
  MeshHierarchy& hierarchy_;
  int k_ = 3;
  Quantization grid_;
  bool level0_ = true;
  std::vector<unsigned char> referenced_;  ///< level 0 only

  // Per vertex of the current level: cell coordinates (w >> shift), sum and count of the
  // finest members' positions; next_* for the level being built.
  std::vector<std::uint32_t> cells_, next_cells_;
  std::vector<double> sums_, next_sums_;
  std::vector<Index> counts_, next_counts_;

  // Scratch reused by every level.
  std::vector<std::uint64_t> keys_;
  std::vector<Index> parent_, label_;
  Index num_clusters_ = 0;
  std::vector<KeyedIndex> sorted_, sort_scratch_;
  std::vector<Index> mapped_;
  std::vector<unsigned char> keep_;
  std::vector<Index> offsets_, others_, index_scratch_;
};

}  // namespace

std::string_view OctreeHierarchy::ToString(CoarsePositions positions) {
  for (const auto& [name, value] : kCoarsePositionNames) {
    if (value == positions) return name;
  }
  return "?";
}

OctreeHierarchy::Options OctreeHierarchy::Options::FromConfig(const ConfigNode& node) {
  Options options;
  options.topology_aware =
      node.Get("topology_aware", options.topology_aware,
               "merge the vertices of one cell only if element edges inside the cell connect "
               "them (the paper's topology check)");
  std::vector<std::string> choices;
  for (const auto& [name, value] : kCoarsePositionNames) choices.emplace_back(name);
  const std::string positions =
      node.GetChoice("coarse_positions", ToString(options.coarse_positions), choices,
                     "rest positions of coarse vertices: mean of the finest cluster members, or "
                     "the cell centre of the truncated integer coordinates (the paper)");
  for (const auto& [name, value] : kCoarsePositionNames) {
    if (name == positions) options.coarse_positions = value;
  }
  options.min_vertices =
      node.Get("min_vertices", options.min_vertices,
               "stop once the coarsest level has at most this many vertices (>= 0)");
  options.max_levels = node.Get("max_levels", options.max_levels,
                                "at most this many levels, the input included (>= 0; 0 = no "
                                "limit)");
  node.RejectUnknownKeys();
  try {
    options.Validate();
  } catch (const ConfigError& error) {
    const std::string table = node.path().empty() ? std::string() : " [" + node.path() + "]";
    throw ConfigError(fmt::format("{}{}: {}", node.source(), table, error.what()));
  }
  return options;
}

void OctreeHierarchy::Options::Validate() const {
  std::vector<std::string> problems;
  if (min_vertices < 0) problems.push_back(fmt::format("min_vertices is {}, must be >= 0", min_vertices));
  if (max_levels < 0) problems.push_back(fmt::format("max_levels is {}, must be >= 0", max_levels));
  if (!problems.empty()) {
    throw ConfigError(fmt::format("invalid {} hierarchy options: {}", kName, fmt::join(problems, "; ")));
  }
}

OctreeHierarchy::OctreeHierarchy(const Options& options) : options_(options) {
  options_.Validate();
}

std::unique_ptr<Hierarchy> OctreeHierarchy::Create(const ConfigNode& node) {
  return std::make_unique<OctreeHierarchy>(Options::FromConfig(node));
}

MeshHierarchy OctreeHierarchy::Build(const Mesh& mesh, const Context& context) const {
  MeshHierarchy hierarchy;
  hierarchy.levels.push_back(HierarchyLevel{mesh, {}, {}});
  if (mesh.num_elements() == 0) return hierarchy;
  const int k = mesh.simplex_size();
  HARAP_CHECK(k == 3 || k == 4, "elements have {} vertices; the octree hierarchy needs "
              "triangles (3) or tetrahedra (4)", k);
  HARAP_CHECK(mesh.elements.minCoeff() >= 0 && mesh.elements.maxCoeff() < mesh.num_vertices(),
              "element indices must lie in [0, {})", mesh.num_vertices());
  if (mesh.num_vertices() <= options_.min_vertices || options_.max_levels == 1) return hierarchy;
  context.Run([&] { Builder(options_, hierarchy).Run(); });
  return hierarchy;
}

}  // namespace harap
