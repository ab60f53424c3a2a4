// SPDX-License-Identifier: MIT
#include "hierarchies/builders/octree_hierarchy.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "framework/error.h"

// Cost: a small part of a hierarchical run (docs/benchmarks.md, "Hierarchy construction", has
// the times and the command). The levels shrink geometrically, so level 0's analysis (unique
// edges for Ē, bounding box, Eq. 2) and level 1 take most of it. What keeps it low: one pass per
// task over the elements with the per-vertex data they touch prefetched; clusters by union–find (no
// adjacency lists; level 0 walks the unique edges it has bucketed for Ē anyway); counting sorts
// instead of comparison sorts or hashing; scratch buffers sized once on level 0 and never
// zero-filled when they are overwritten anyway.

namespace harap {
namespace {

/// Bits per axis of the integer coordinates: three of them fit a 64-bit cell key.
constexpr int kMaxBits = 21;

constexpr EnumNames<OctreeHierarchy::CoarsePositions, 2> kCoarsePositionNames = {{
    {OctreeHierarchy::CoarsePositions::kMean, "mean"},
    {OctreeHierarchy::CoarsePositions::kQuantized, "quantized"},
}};
// Read with these ranges and checked against them by Validate().

/// Elements per TBB task in the parallel loops (they are cheap per element).
constexpr std::size_t kGrain = 4096;

template <class F>
void ParallelFor(std::size_t n, F&& f) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kGrain),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i) f(i);
                    });
}

/// Per-vertex data is read in element order, i.e. scattered: prefetch it for the element
/// kPrefetchDistance ahead of entry t (of `end` entries of K-simplices).
constexpr std::size_t kPrefetchDistance = 16;

template <int K, class T>
inline void PrefetchAhead(const T* data, const Index* e, std::size_t t, std::size_t end) {
  const std::size_t ahead = t + kPrefetchDistance * K;
  if (ahead < end) {
    for (int a = 0; a < K; ++a) __builtin_prefetch(data + e[ahead + a]);
  }
}

/// Runs f(part, begin, end) on `parts` contiguous ranges of [0, n) in parallel (one task each).
template <class F>
void ForEachPart(std::size_t n, int parts, F&& f) {
  tbb::parallel_for(0, parts, [&](int p) { f(p, n * p / parts, n * (p + 1) / parts); });
}

/// Concurrent union–find (the hooking of ECL-CC, Jaiganesh & Burtscher 2018) whose root is
/// always the smallest member: parent[i] ≤ i holds throughout, so the partition does not depend
/// on the order of the unions and one increasing sweep flattens the forest. Path halving only
/// ever stores an ancestor, so racing halvings are harmless; roots are hooked by CAS.
inline Index Find(Index* parent, Index i) {
  for (;;) {
    std::atomic_ref<Index> link(parent[i]);
    const Index p = link.load(std::memory_order_relaxed);
    if (p == i) return i;
    const Index grandparent = std::atomic_ref<Index>(parent[p]).load(std::memory_order_relaxed);
    if (grandparent != p) link.store(grandparent, std::memory_order_relaxed);
    i = grandparent;
  }
}

inline void Union(Index* parent, Index a, Index b) {
  for (;;) {
    a = Find(parent, a);
    b = Find(parent, b);
    if (a == b) return;
    if (b < a) std::swap(a, b);
    Index expected = b;  // hook the larger root under the smaller one
    if (std::atomic_ref<Index>(parent[b]).compare_exchange_weak(expected, a,
                                                                std::memory_order_relaxed)) {
      return;
    }
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
    for (const KeyedIndex& item : items) {
      scratch[count[(item.key >> shift) & (kBuckets - 1)]++] = item;
    }
    items.swap(scratch);
  }
}

template <int K>
inline bool Equal(const std::array<Index, K>& a, const std::array<Index, K>& b) {
  bool equal = true;
  for (int i = 0; i < K; ++i) equal = equal && a[i] == b[i];
  return equal;
}

template <int K>
inline bool Less(const std::array<Index, K>& a, const std::array<Index, K>& b) {
  for (int i = 0; i < K; ++i) {
    if (a[i] != b[i]) return a[i] < b[i];
  }
  return false;
}

template <int K>
inline std::array<Index, K> SortedSimplex(const Index* c) {
  std::array<Index, K> s;
  for (int a = 0; a < K; ++a) s[a] = c[a];
  auto order = [&](int a, int b) {
    if (s[b] < s[a]) std::swap(s[a], s[b]);
  };
  if constexpr (K == 3) {
    order(0, 1);
    order(1, 2);
    order(0, 1);
  } else {
    order(0, 1);
    order(2, 3);
    order(0, 2);
    order(1, 3);
    order(1, 2);
  }
  return s;
}

/// Row i of a row-major #V×3 array.
inline Eigen::Map<const Eigen::Vector3d> Row(const double* xyz, Index i) {
  return Eigen::Map<const Eigen::Vector3d>(xyz + 3 * std::size_t(i));
}

/// Integer cell coordinates packed in one word: x in bits 42–62, y in 21–41, z in 0–20.
constexpr std::uint64_t kFieldMask = (std::uint64_t{1} << kMaxBits) - 1;

inline std::uint64_t PackCell(std::uint64_t x, std::uint64_t y, std::uint64_t z) {
  return (x << (2 * kMaxBits)) | (y << kMaxBits) | z;
}

inline std::uint64_t CellField(std::uint64_t cell, int d) {
  return (cell >> ((2 - d) * kMaxBits)) & kFieldMask;
}

/// The cell `delta` levels coarser (every coordinate shifted right by delta).
inline std::uint64_t ShiftCell(std::uint64_t cell, int delta) {
  const std::uint64_t field = kFieldMask >> delta;
  return (cell >> delta) & (field | (field << kMaxBits) | (field << (2 * kMaxBits)));
}

/// The integer grid of Eq. (2).
struct Quantization {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< b_min
  Eigen::Vector3d step = Eigen::Vector3d::Zero();    ///< cell length (b_max − b_min)/(2^q − 1)
  std::array<int, 3> bits = {0, 0, 0};               ///< q_d
  int max_bits = 0;

  /// The cell coordinates at `shift` packed densely (for sorting): bits per axis max(q_d − s, 0).
  std::uint64_t DenseKey(std::uint64_t cell, int shift) const {
    const int by = std::max(bits[1] - shift, 0), bz = std::max(bits[2] - shift, 0);
    return (CellField(cell, 0) << (by + bz)) | (CellField(cell, 1) << bz) | CellField(cell, 2);
  }
  int DenseKeyBits(int shift) const {
    return std::max(bits[0] - shift, 0) + std::max(bits[1] - shift, 0) +
           std::max(bits[2] - shift, 0);
  }

  /// World position of the centre of `cell` (coordinates w >> shift), clipped to the bounding
  /// box.
  Eigen::Vector3d CellCentre(std::uint64_t cell, int shift) const {
    Eigen::Vector3d p;
    for (int d = 0; d < 3; ++d) {
      const auto c = static_cast<std::int64_t>(CellField(cell, d));
      const std::int64_t top = (std::int64_t{1} << bits[d]) - 1;
      const std::int64_t lo = c << shift;
      const std::int64_t hi = std::min(((c + 1) << shift) - 1, top);
      p[d] = origin[d] + 0.5 * double(lo + hi) * step[d];
    }
    return p;
  }
};

/// A scratch array that only grows. new T[] leaves trivial types uninitialized, so pages that
/// are never written are never faulted in (the kernel zero-fills each fresh page on first touch,
/// which costs as much as the work on it).
template <class T>
class Scratch {
 public:
  T* Resize(std::size_t size) {
    if (size > capacity_) {
      data_.reset(new T[size]);
      capacity_ = size;
    }
    size_ = size;
    return data_.get();
  }
  T* data() { return data_.get(); }
  const T* data() const { return data_.get(); }
  T& operator[](std::size_t i) { return data_[i]; }
  const T& operator[](std::size_t i) const { return data_[i]; }
  std::size_t size() const { return size_; }
  void swap(Scratch& other) noexcept {
    data_.swap(other.data_);
    std::swap(capacity_, other.capacity_);
    std::swap(size_, other.size_);
  }

 private:
  std::unique_ptr<T[]> data_;
  std::size_t capacity_ = 0;
  std::size_t size_ = 0;
};

/// Splits [0, n) into fixed blocks (independent of the thread count, so sums over blocks taken
/// in block order are deterministic) and runs f(block, begin, end) on them in parallel.
template <class F>
void ForEachBlock(std::size_t n, std::size_t block_size, F&& f) {
  const std::size_t blocks = (n + block_size - 1) / block_size;
  tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t block) {
    f(block, block * block_size, std::min(n, (block + 1) * block_size));
  });
}

constexpr std::size_t kBlock = 16384;

/// Builds the coarse levels of a hierarchy of K-simplices (K = 3 triangles, 4 tetrahedra). The
/// scratch buffers are sized on level 0 and reused by the coarser levels.
template <int K>
class Builder {
 public:
  Builder(const OctreeHierarchy::Options& options, MeshHierarchy& hierarchy)
      : options_(options), hierarchy_(hierarchy) {}

  void Run() {
    // At most one level per shift 1..kMaxBits − 1 besides level 0: references stay valid.
    hierarchy_.levels.reserve(kMaxBits + 1);
    SetUpFinestLevel(hierarchy_.levels[0].mesh);
    int shift = 0;
    for (;;) {
      const Mesh& mesh = hierarchy_.levels.back().mesh;
      const Index n = mesh.num_vertices();
      if (options_.max_levels > 0 && hierarchy_.num_levels() >= options_.max_levels) break;
      if (n <= options_.min_vertices) break;
      int next_shift = shift + 1;
      while (next_shift < grid_.max_bits && Cluster(mesh, next_shift - shift) == n) {
        ++next_shift;  // nothing merges at this shift
      }
      if (next_shift >= grid_.max_bits) break;
      if (!AddCoarseLevel(next_shift)) break;
      if (!options_.KeepsLevel(hierarchy_.levels.back().mesh.num_vertices())) {
        DropCoarsestLevel(hierarchy_);
        break;
      }
      shift = next_shift;
    }
  }

 private:
  /// Level 0: referenced vertices, bounding box, mean unique edge length Ē, Eq. (2)–(3).
  void SetUpFinestLevel(const Mesh& mesh) {
    const Index n = mesh.num_vertices();
    parts_ = std::max(1, tbb::this_task_arena::max_concurrency());

    // Row-major positions: the finest members' sums on level 0 (one member each).
    double* xyz = sums_.Resize(3 * std::size_t(n));
    ParallelFor(n, [&](std::size_t i) {
      for (int d = 0; d < 3; ++d) xyz[3 * i + d] = mesh.vertices(i, d);
    });
    BucketEdges(mesh);
    const EdgeStatistics stats = MeasureUniqueEdges(n, xyz);
    SetUpGrid(n, xyz, stats);
    level0_ = true;
  }

  /// Marks the referenced vertices, and buckets the element edges by their smaller end (counting
  /// sort; after the fill, bucket i is [end[i − 1], end[i]) with end[−1] = 0).
  void BucketEdges(const Mesh& mesh) {
    const Index n = mesh.num_vertices();
    const std::size_t m = std::size_t(mesh.num_elements());
    const Index* e = mesh.elements.data();
    referenced_.assign(n, 0);
    Index* end = edge_end_.Resize(std::size_t(n) + 1);
    std::fill_n(end, std::size_t(n) + 1, 0);
    for (std::size_t t = 0; t < m * K; t += K) {
      for (int a = 0; a < K; ++a) {
        referenced_[e[t + a]] = 1;
        for (int b = a + 1; b < K; ++b) ++end[std::min(e[t + a], e[t + b]) + 1];
      }
    }
    for (Index i = 0; i < n; ++i) end[i + 1] += end[i];
    Index* edges = edges_.Resize(end[n]);
    for (std::size_t t = 0; t < m * K; t += K) {
      PrefetchAhead<K>(end, e, t, m * K);
      for (int a = 0; a < K; ++a) {
        for (int b = a + 1; b < K; ++b) {
          const auto [lo, hi] = std::minmax(e[t + a], e[t + b]);
          edges[end[lo]++] = hi;
        }
      }
    }
  }

  struct EdgeStatistics {
    double mean_edge = 0.0;  ///< Ē
    Eigen::Vector3d lo, hi;  ///< the bounding box of the referenced vertices
  };

  /// Ē over the unique edges, whose ends are compacted to the front of each bucket (ending at
  /// unique_end[a]). Also the bounding box. Fixed blocks, summed in order.
  EdgeStatistics MeasureUniqueEdges(Index n, const double* xyz) {
    const Index* end = edge_end_.data();
    Index* edges = edges_.data();
    struct BlockResult {
      double length = 0.0;
      std::size_t edges = 0;
      Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
      Eigen::Vector3d hi = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());
    };
    std::vector<BlockResult> block_results((std::size_t(n) + kBlock - 1) / kBlock);
    Index* unique_end = unique_end_.Resize(n);
    ForEachBlock(n, kBlock, [&](std::size_t block, std::size_t first, std::size_t last) {
      BlockResult r;
      for (std::size_t a = first; a < last; ++a) {
        unique_end[a] = a == 0 ? 0 : end[a - 1];
        if (!referenced_[a]) continue;
        const Eigen::Vector3d pa = Row(xyz, Index(a));
        r.lo = r.lo.cwiseMin(pa);
        r.hi = r.hi.cwiseMax(pa);
        // The neighbours' positions are scattered: fetch the next bucket's meanwhile.
        if (a + 1 < last) {
          for (Index j = end[a]; j < end[a + 1]; ++j) {
            __builtin_prefetch(xyz + 3 * std::size_t(edges[j]));
          }
        }
        // Keep the first of equal entries, compacted to the front of the bucket.
        Index* begin = edges + (a == 0 ? 0 : end[a - 1]);
        Index* stop = edges + end[a];
        Index* out = begin;
        if (stop - begin > 64) {
          std::sort(begin, stop);
          out = std::unique(begin, stop);
        } else {
          for (Index* j = begin; j < stop; ++j) {
            bool seen = false;
            for (Index* i = begin; i < out; ++i) seen |= *i == *j;
            if (!seen) *out++ = *j;
          }
        }
        unique_end[a] = Index(out - edges);
        for (Index* j = begin; j < out; ++j) r.length += (pa - Row(xyz, *j)).norm();
        r.edges += std::size_t(out - begin);
      }
      block_results[block] = r;
    });
    BlockResult total;
    for (const BlockResult& r : block_results) {
      total.length += r.length;
      total.edges += r.edges;
      total.lo = total.lo.cwiseMin(r.lo);
      total.hi = total.hi.cwiseMax(r.hi);
    }
    return {total.edges ? total.length / double(total.edges) : 0.0, total.lo, total.hi};
  }

  /// The grid of cells of edge length ≤ Ē over the bounding box, and each vertex's cell, Eq. (2).
  void SetUpGrid(Index n, const double* xyz, const EdgeStatistics& stats) {
    const double mean_edge = stats.mean_edge;
    const Eigen::Vector3d& lo = stats.lo;
    const Eigen::Vector3d& hi = stats.hi;
    grid_.origin = lo;
    std::array<double, 3> extent = {0.0, 0.0, 0.0};
    std::array<double, 3> top = {0.0, 0.0, 0.0};  // 2^q − 1
    for (int d = 0; d < 3; ++d) {
      extent[d] = hi[d] - lo[d];
      int q = 0;
      if (mean_edge > 0.0 && extent[d] > mean_edge) {
        q = static_cast<int>(std::ceil(std::log2(extent[d] / mean_edge + 1.0)));
        // Guard against rounding in log2: the cell must not exceed Ē.
        while (q < kMaxBits && extent[d] / double((std::int64_t{1} << q) - 1) > mean_edge) ++q;
        q = std::clamp(q, 1, kMaxBits);
      }
      top[d] = double((std::int64_t{1} << q) - 1);
      grid_.bits[d] = q;
      grid_.step[d] = q > 0 ? extent[d] / top[d] : 0.0;
      grid_.max_bits = std::max(grid_.max_bits, q);
    }

    // Eq. (2): w = ⌊(2^q − 1)(v̄ − b_min)/(b_max − b_min) + ½⌋ (unreferenced vertices: 0).
    std::uint64_t* cells = cells_.Resize(n);
    ParallelFor(n, [&](std::size_t i) {
      std::array<std::uint64_t, 3> w = {0, 0, 0};
      if (referenced_[i]) {
        for (int d = 0; d < 3; ++d) {
          if (top[d] == 0.0) continue;
          // The argument is ≥ ½, so truncation is the floor.
          const double t = (xyz[3 * i + d] - lo[d]) / extent[d];
          w[d] = static_cast<std::uint64_t>(std::min(top[d] * t + 0.5, top[d]));
        }
      }
      cells[i] = PackCell(w[0], w[1], w[2]);
    });
  }

  bool Referenced(Index i) const { return !level0_ || referenced_[i]; }

  /// Clusters the current level's vertices in the cells `delta` levels coarser (into
  /// next_cells_); label_ numbers the clusters by their smallest member. Returns the number of
  /// clusters; unreferenced vertices are singletons.
  Index Cluster(const Mesh& mesh, int delta) {
    const Index n = mesh.num_vertices();
    const std::uint64_t* cells = cells_.data();
    std::uint64_t* cell = next_cells_.Resize(n);
    Index* parent = parent_.Resize(n);
    ParallelFor(n, [&](std::size_t i) {
      cell[i] = ShiftCell(cells[i], delta);
      parent[i] = Index(i);
    });
    if (options_.topology_aware && level0_) {
      // Connected components of the edges inside a cell (Algorithm 1), over the unique edges
      // of SetUpFinestLevel.
      const Index* end = edge_end_.data();
      const Index* unique_end = unique_end_.data();
      const Index* edges = edges_.data();
      ForEachPart(n, parts_, [&](int, std::size_t first, std::size_t last) {
        for (std::size_t a = first; a < last; ++a) {
          if (a + 1 < last) {
            for (Index j = end[a]; j < unique_end[a + 1]; ++j) __builtin_prefetch(cell + edges[j]);
          }
          const std::uint64_t key = cell[a];
          for (Index j = a == 0 ? 0 : end[a - 1]; j < unique_end[a]; ++j) {
            if (cell[edges[j]] == key) Union(parent, Index(a), edges[j]);
          }
        }
      });
    } else if (options_.topology_aware) {
      // The same over the element edges: per element, each vertex joins the first earlier
      // vertex of its cell (a spanning forest of the element's edges inside cells).
      const Index* e = mesh.elements.data();
      ForEachPart(mesh.num_elements(), parts_, [&](int, std::size_t first, std::size_t last) {
        for (std::size_t t = first * K; t < last * K; t += K) {
          PrefetchAhead<K>(cell, e, t, last * K);
          std::array<std::uint64_t, K> key;
          for (int a = 0; a < K; ++a) key[a] = cell[e[t + a]];
          for (int a = 1; a < K; ++a) {
            for (int b = 0; b < a; ++b) {
              if (key[b] == key[a]) {
                Union(parent, e[t + b], e[t + a]);
                break;
              }
            }
          }
        }
      });
    } else {
      // Every referenced vertex of a cell joins the cell's smallest vertex.
      const int shift = current_shift_ + delta;
      sorted_.clear();
      for (Index i = 0; i < n; ++i) {
        if (Referenced(i)) sorted_.push_back({grid_.DenseKey(cell[i], shift), i});
      }
      RadixSort(sorted_, sort_scratch_, grid_.DenseKeyBits(shift));
      for (std::size_t j = 1; j < sorted_.size(); ++j) {
        if (sorted_[j].key == sorted_[j - 1].key) {
          parent[sorted_[j].index] = parent[sorted_[j - 1].index];
        }
      }
    }
    // Flatten (parent[i] ≤ i) and label clusters in the order of their smallest member.
    Index* label = label_.Resize(n);
    num_clusters_ = 0;
    for (Index i = 0; i < n; ++i) {
      const Index p = parent[parent[i]];
      parent[i] = p;
      label[i] = p == i ? num_clusters_++ : label[p];
    }
    return num_clusters_;
  }

  /// Builds level l+1 (cells at `shift`) from the clusters in label_; false if no element
  /// survives.
  bool AddCoarseLevel(int shift) {
    HierarchyLevel& fine_level = hierarchy_.levels.back();
    const Mesh& fine = fine_level.mesh;
    const Index n = fine.num_vertices();
    const Index* label = label_.data();
    const Index num_survivors = CollectSurvivors(fine);
    if (num_survivors == 0) return false;
    const Index* survivors = survivors_.data();

    // Duplicates out; the used clusters (marked 0) compacted into coarse indices.
    Index* coarse_of = coarse_of_.Resize(num_clusters_);
    std::fill_n(coarse_of, num_clusters_, kNoVertex);
    const Index num_elements = RemoveDuplicates(num_survivors, coarse_of);
    Index num_coarse = 0;
    for (Index c = 0; c < num_clusters_; ++c) {
      if (coarse_of[c] == 0) coarse_of[c] = num_coarse++;
    }
    HierarchyLevel coarse_level;
    Mesh& coarse = coarse_level.mesh;
    coarse.planar = fine.planar;
    coarse.elements.resize(num_elements, K);
    Index* out = coarse.elements.data();
    for (Index s = 0; s < num_survivors; ++s) {
      if (!keep_[s]) continue;
      for (int a = 0; a < K; ++a) *out++ = coarse_of[survivors[std::size_t(s) * K + a]];
    }

    // Fine → coarse map.
    fine_level.coarse_vertex.resize(n);
    fine_level.in_cluster.resize(n);
    std::atomic<Index> unresolved = 0;
    ForEachBlock(n, kBlock, [&](std::size_t, std::size_t first, std::size_t last) {
      Index count = 0;
      for (std::size_t i = first; i < last; ++i) {
        const Index c = coarse_of[label[i]];
        fine_level.coarse_vertex[i] = c;
        fine_level.in_cluster[i] = c != kNoVertex ? 1 : 0;
        if (c == kNoVertex && Referenced(Index(i))) ++count;
      }
      unresolved += count;
    });
    if (unresolved > 0) MapToClosestSurvivor(fine, fine_level, unresolved);

    SetCoarseState(fine_level, num_coarse);
    current_shift_ = shift;
    coarse.vertices.resize(num_coarse, 3);
    ParallelFor(num_coarse, [&](std::size_t c) {
      for (int d = 0; d < 3; ++d) coarse.vertices(c, d) = sums_[3 * c + d] / double(counts_[c]);
    });
    if (options_.coarse_positions == OctreeHierarchy::CoarsePositions::kQuantized) {
      SetQuantizedPositions(coarse);
    }
    if (coarse.planar) coarse.vertices.col(2).setZero();
    hierarchy_.levels.push_back(std::move(coarse_level));
    return true;
  }

  /// Eq. (5)/(10): an element survives iff its vertices lie in K different clusters. Writes the
  /// survivors' clusters, in element order, to survivors_ and returns their number: each block
  /// writes its survivors where its elements start, then the blocks are moved together.
  Index CollectSurvivors(const Mesh& fine) {
    const std::size_t m = std::size_t(fine.num_elements());
    const Index* e = fine.elements.data();
    const Index* label = label_.data();
    if (level0_) survivors_.swap(edges_);  // the level-0 edge buckets are no longer needed
    Index* survivors = survivors_.Resize(m * K);
    const std::size_t blocks = (m + kBlock - 1) / kBlock;
    std::vector<Index> block_count(blocks, 0);
    ForEachBlock(m, kBlock, [&](std::size_t block, std::size_t first, std::size_t last) {
      Index* out = survivors + first * K;
      for (std::size_t t = first * K; t < last * K; t += K) {
        PrefetchAhead<K>(label, e, t, last * K);
        std::array<Index, K> c;
        for (int a = 0; a < K; ++a) c[a] = label[e[t + a]];
        bool distinct = true;
        for (int a = 0; a < K; ++a) {
          for (int b = a + 1; b < K; ++b) distinct = distinct && c[a] != c[b];
        }
        for (int a = 0; a < K; ++a) out[a] = c[a];
        out += distinct ? K : 0;
      }
      block_count[block] = Index((out - survivors - first * K) / K);
    });
    Index num_survivors = 0;
    for (std::size_t block = 0; block < blocks; ++block) {
      // Moving down, in block order, never overwrites a block not yet moved.
      std::memmove(survivors + std::size_t(num_survivors) * K, survivors + block * kBlock * K,
                   std::size_t(block_count[block]) * K * sizeof(Index));
      num_survivors += block_count[block];
    }
    return num_survivors;
  }

  /// The per-vertex state of the coarse level (`num_coarse` vertices, mapped from `fine_level`):
  /// cell, sum and count of the finest members.
  void SetCoarseState(const HierarchyLevel& fine_level, Index num_coarse) {
    const Index n = fine_level.mesh.num_vertices();
    std::uint64_t* coarse_cells = coarse_cells_.Resize(num_coarse);
    double* coarse_sums = coarse_sums_.Resize(3 * std::size_t(num_coarse));
    Index* coarse_counts = coarse_counts_.Resize(num_coarse);
    std::fill_n(coarse_sums, 3 * std::size_t(num_coarse), 0.0);
    std::fill_n(coarse_counts, num_coarse, 0);
    for (Index i = 0; i < n; ++i) {
      if (!fine_level.in_cluster[i]) continue;
      const Index c = fine_level.coarse_vertex[i];
      coarse_cells[c] = next_cells_[i];
      for (int d = 0; d < 3; ++d)
        coarse_sums[3 * std::size_t(c) + d] += sums_[3 * std::size_t(i) + d];
      coarse_counts[c] += level0_ ? 1 : counts_[i];
    }
    cells_.swap(coarse_cells_);
    sums_.swap(coarse_sums_);
    counts_.swap(coarse_counts_);
    level0_ = false;
  }

  /// Sets keep_[s] = 0 for each survivor whose cluster set equals that of an earlier survivor
  /// (1 otherwise) and marks the clusters the survivors use with 0 in `used`. Returns the number
  /// of survivors kept.
  Index RemoveDuplicates(Index num_survivors, Index* used) {
    // Bucket the survivors by their smallest cluster (counting sort, stable); an entry holds
    // the survivor and its other clusters, sorted, so a bucket is compared in place.
    const Index* survivors = survivors_.data();
    Index* offsets = offsets_.Resize(std::size_t(num_clusters_) + 1);
    std::fill_n(offsets, std::size_t(num_clusters_) + 1, 0);
    for (Index s = 0; s < num_survivors; ++s) {
      const Index* c = survivors + std::size_t(s) * K;
      Index lowest = c[0];
      for (int a = 0; a < K; ++a) {
        used[c[a]] = 0;
        lowest = std::min(lowest, c[a]);
      }
      ++offsets[lowest + 1];
    }
    for (Index c = 0; c < num_clusters_; ++c) offsets[c + 1] += offsets[c];
    BucketEntry* bucket = bucket_.Resize(num_survivors);
    Index* cursor = parent_.Resize(num_clusters_);  // parent_ is free after clustering
    std::copy_n(offsets, num_clusters_, cursor);
    for (Index s = 0; s < num_survivors; ++s) {
      const std::array<Index, K> sorted = SortedSimplex<K>(survivors + std::size_t(s) * K);
      BucketEntry& entry = bucket[cursor[sorted[0]]++];
      entry.survivor = s;
      for (int a = 1; a < K; ++a) entry.rest[a - 1] = sorted[a];
    }
    unsigned char* keep = keep_.Resize(num_survivors);
    std::fill_n(keep, num_survivors, 1);
    std::atomic<Index> duplicates = 0;
    ForEachBlock(num_clusters_, kBlock, [&](std::size_t, std::size_t first, std::size_t last) {
      Index count = 0;
      for (std::size_t c = first; c < last; ++c) {
        BucketEntry* begin = bucket + offsets[c];
        BucketEntry* end = bucket + offsets[c + 1];
        if (end - begin < 2) continue;
        if (end - begin > 16) {
          std::sort(begin, end, [](const BucketEntry& x, const BucketEntry& y) {
            return Less<K - 1>(x.rest, y.rest) ||
                   (Equal<K - 1>(x.rest, y.rest) && x.survivor < y.survivor);
          });
          for (BucketEntry* j = begin + 1; j < end; ++j) {
            if (Equal<K - 1>(j->rest, (j - 1)->rest)) {
              keep[j->survivor] = 0;
              ++count;
            }
          }
          continue;
        }
        for (BucketEntry* j = begin + 1; j < end; ++j) {
          for (BucketEntry* i = begin; i < j; ++i) {
            if (Equal<K - 1>(i->rest, j->rest)) {
              // The first of equal entries stays (entries are in survivor order).
              keep[j->survivor] = 0;
              ++count;
              break;
            }
          }
        }
      }
      duplicates += count;
    });
    return num_survivors - duplicates;
  }

  /// Multi-source BFS in the fine vertex–edge graph from the vertices whose cluster survived to
  /// the `unresolved` referenced vertices whose cluster did not: each takes the coarse vertex of
  /// its closest survivor (hop distance; ties → lowest coarse index).
  void MapToClosestSurvivor(const Mesh& fine, HierarchyLevel& level, Index unresolved) {
    const Index n = fine.num_vertices();
    const Index m = fine.num_elements();
    const Index* e = fine.elements.data();
    std::vector<Index>& coarse = level.coarse_vertex;
    const std::vector<unsigned char>& in_cluster = level.in_cluster;

    // The unresolved vertices (ascending; local ids are positions in this list), flagged, and
    // their incident elements (CSR). They are few: flag lookups keep the element scan cheap.
    unsigned char* flag = flag_.Resize(n);
    std::vector<Index> vertices;
    vertices.reserve(unresolved);
    for (Index i = 0; i < n; ++i) {
      flag[i] = !in_cluster[i] && Referenced(i) ? 1 : 0;
      if (flag[i]) vertices.push_back(i);
    }
    auto local = [&](Index v) {
      return flag[v]
                 ? Index(std::lower_bound(vertices.begin(), vertices.end(), v) - vertices.begin())
                 : kNoVertex;
    };
    std::vector<std::pair<Index, Index>> touching;  // (local id, element)
    for (std::size_t j = 0; j < std::size_t(m) * K; ++j) {
      if (flag[e[j]]) touching.emplace_back(local(e[j]), Index(j / K));
    }
    std::vector<Index> offsets(vertices.size() + 1, 0);
    for (const auto& [u, t] : touching) ++offsets[u + 1];
    for (std::size_t u = 0; u < vertices.size(); ++u) offsets[u + 1] += offsets[u];
    std::vector<Index> incident(touching.size());
    std::vector<Index> cursor(offsets.begin(), offsets.end() - 1);
    for (const auto& [u, t] : touching) incident[cursor[u]++] = t;
    auto element = [&](Index j) { return e + std::size_t(incident[j]) * K; };

    constexpr Index kUnset = -1, kPending = -2;
    std::vector<Index> distance(vertices.size(), kUnset);
    std::vector<Index> frontier, next;
    // Layer 1: unresolved vertices with a neighbour whose cluster survived.
    for (std::size_t u = 0; u < vertices.size(); ++u) {
      Index best = kNoVertex;
      for (Index j = offsets[u]; j < offsets[u + 1]; ++j) {
        for (int a = 0; a < K; ++a) {
          const Index w = element(j)[a];
          if (in_cluster[w] && (best == kNoVertex || coarse[w] < best)) best = coarse[w];
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
          for (int a = 0; a < K; ++a) {
            const Index w = local(element(j)[a]);
            if (w != kNoVertex && distance[w] == kUnset) {
              distance[w] = kPending;
              next.push_back(w);
            }
          }
        }
      }
      for (Index u : next) {
        Index best = kNoVertex;
        for (Index j = offsets[u]; j < offsets[u + 1]; ++j) {
          for (int a = 0; a < K; ++a) {
            const Index w = element(j)[a];
            const Index local_w = local(w);
            if (local_w != kNoVertex && distance[local_w] == layer &&
                (best == kNoVertex || coarse[w] < best)) {
              best = coarse[w];
            }
          }
        }
        coarse[vertices[u]] = best;
        distance[u] = layer + 1;
      }
      frontier.swap(next);
    }
  }

  /// Cell centres at the current shift; clusters sharing a cell (a cell split by the topology
  /// check) keep the mean position already in coarse.vertices.
  void SetQuantizedPositions(Mesh& coarse) {
    const Index n = coarse.num_vertices();
    std::vector<unsigned char> split(n, 0);
    if (options_.topology_aware) {
      sorted_.resize(n);
      for (Index c = 0; c < n; ++c) sorted_[c] = {grid_.DenseKey(cells_[c], current_shift_), c};
      RadixSort(sorted_, sort_scratch_, grid_.DenseKeyBits(current_shift_));
      for (Index j = 1; j < n; ++j) {
        if (sorted_[j].key == sorted_[j - 1].key) {
          split[sorted_[j].index] = split[sorted_[j - 1].index] = 1;
        }
      }
    }
    ParallelFor(n, [&](std::size_t c) {
      if (!split[c]) coarse.vertices.row(c) = grid_.CellCentre(cells_[c], current_shift_);
    });
  }

  const OctreeHierarchy::Options& options_;
  MeshHierarchy& hierarchy_;
  Quantization grid_;
  bool level0_ = true;
  int current_shift_ = 0;
  int parts_ = 1;  ///< ranges processed in parallel (the arena's concurrency)
  std::vector<unsigned char> referenced_;  ///< level 0 only

  // Per vertex of the current level: packed cell (w >> shift), and the sum (row-major) and
  // count of the finest members' positions (on level 0 the positions; counts unused).
  // next_cells_: the cells at the shift being tried; coarse_*: the level being built.
  Scratch<std::uint64_t> cells_, next_cells_, coarse_cells_;
  Scratch<double> sums_, coarse_sums_;
  Scratch<Index> counts_, coarse_counts_;

  // Scratch reused by every level.
  Scratch<Index> parent_, label_, survivors_, offsets_, coarse_of_;
  // Level 0: the element edges bucketed by their smaller end; bucket a is
  // [edge_end_[a − 1], edge_end_[a]), its unique entries end at unique_end_[a].
  Scratch<Index> edge_end_, unique_end_, edges_;
  Index num_clusters_ = 0;
  std::vector<KeyedIndex> sorted_, sort_scratch_;
  struct BucketEntry {
    Index survivor;
    std::array<Index, K - 1> rest;
  };
  Scratch<BucketEntry> bucket_;
  Scratch<unsigned char> keep_, flag_;
};

}  // namespace

std::string_view OctreeHierarchy::ToString(CoarsePositions positions) {
  return NameOf(kCoarsePositionNames, positions);
}

OctreeHierarchy::Options OctreeHierarchy::Options::FromConfig(OptionReader node) {
  Options options;
  options.topology_aware =
      node.Get("topology_aware", options.topology_aware,
               "merge the vertices of one cell only if element edges inside the cell connect "
               "them (the paper's topology check)");
  options.coarse_positions =
      node.GetEnum("coarse_positions", options.coarse_positions, kCoarsePositionNames,
                   "rest positions of coarse vertices: mean of the finest cluster members, or "
                   "the cell centre of the truncated integer coordinates (the paper)");
  options.ReadLimits(node);
  node.RejectUnknownKeys();
  return options;
}

void OctreeHierarchy::Options::Validate() const { ThrowIfInvalidOptions(kName, LimitProblems()); }

OctreeHierarchy::OctreeHierarchy(const Options& options) : options_(options) {
  options_.Validate();
}

MeshHierarchy OctreeHierarchy::Build(const Mesh& mesh, const Context& context) const {
  MeshHierarchy hierarchy = InputLevelOnly(mesh);
  if (mesh.num_elements() == 0) return hierarchy;
  const int k = mesh.simplex_size();
  HARAP_CHECK(k == 3 || k == 4,
              "elements have {} vertices; the octree hierarchy needs "
              "triangles (3) or tetrahedra (4)",
              k);
  HARAP_CHECK(mesh.elements.minCoeff() >= 0 && mesh.elements.maxCoeff() < mesh.num_vertices(),
              "element indices must lie in [0, {})", mesh.num_vertices());
  if (mesh.num_vertices() <= options_.min_vertices || options_.max_levels == 1) return hierarchy;
  static_assert(sizeof(std::array<Index, 3>) == 3 * sizeof(Index) &&
                sizeof(std::array<Index, 4>) == 4 * sizeof(Index));
  context.Run([&] {
    if (k == 3) {
      Builder<3>(options_, hierarchy).Run();
    } else {
      Builder<4>(options_, hierarchy).Run();
    }
  });
  return hierarchy;
}

}  // namespace harap
