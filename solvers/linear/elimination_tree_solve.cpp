// SPDX-License-Identifier: MIT
#include "solvers/linear/elimination_tree_solve.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>

#include <algorithm>
#include <cmath>
#include <queue>
#include <utility>

#include "framework/error.h"

namespace harap {
namespace {

// Leaf subtrees are cut until none holds more than 1/max(kMinTasks, kTasksPerThread · threads)
// of the work, so that dynamic scheduling balances the threads. The cut, and so the summation
// order, is the same for every thread count up to kMinTasks / kTasksPerThread.
constexpr double kMinTasks = 32.0;
constexpr double kTasksPerThread = 4.0;
// Below this many factor entries a subtree is not worth a task of its own.
constexpr double kMinTaskWork = 2000.0;
// Largest block of right-hand-side columns solved in one sweep over the factor.
constexpr int kMaxBlockColumns = 4;

// FNV-1a over the factor's pattern (offsets, counts, row indices of the used entries).
std::uint64_t PatternHash(const LdltFactorView& factor) {
  std::uint64_t hash = 14695981039346656037ull;
  const auto mix = [&hash](std::uint64_t value) {
    hash ^= value;
    hash *= 1099511628211ull;
  };
  mix(static_cast<std::uint64_t>(factor.n));
  for (Index j = 0; j < factor.n; ++j) {
    mix(static_cast<std::uint32_t>(factor.column_start[j]));
    mix(static_cast<std::uint32_t>(factor.column_count[j]));
    const int* row = factor.row + factor.column_start[j];
    for (int e = 0; e < factor.column_count[j]; ++e) mix(static_cast<std::uint32_t>(row[e]));
  }
  return hash;
}

}  // namespace

bool EliminationTreeSolve::Rebind(const LdltFactorView& factor) {
  if (factor.n != n_ || !factor.column_start || !factor.column_count || !factor.row ||
      !factor.value || PatternHash(factor) != pattern_hash_) {
    return false;
  }
  for (Index k = 0; k < n_; ++k) {
    if (permutation_[k] != (factor.permutation ? factor.permutation[k] : k)) return false;
  }
  factor_ = factor;
  RefreshPivots();
  return true;
}

// The elimination tree of a factor (parent = first row below the diagonal) with what the cut
// needs of each subtree.
struct EliminationTreeSolve::Tree {
  std::vector<Index> parent;            ///< -1 for a root
  std::vector<double> subtree_work;     ///< factor entries of the subtree (one pass each way)
  std::vector<Index> first_descendant;  ///< the lowest column of the subtree
  std::vector<Index> num_children;
  double total_work = 0.0;
  /// Every subtree numbered contiguously (CHOLMOD's post-ordered analysis); without that, the
  /// solve is one sequential block.
  bool postordered = true;
};

void EliminationTreeSolve::Setup(const LdltFactorView& factor, int num_threads) {
  const Index n = factor.n;
  HARAP_CHECK(n >= 0 && factor.column_start && factor.column_count && factor.row && factor.value,
              "incomplete factor view");
  n_ = n;
  factor_ = factor;
  pattern_hash_ = PatternHash(factor);
  permutation_.assign(n, 0);
  for (Index k = 0; k < n; ++k) permutation_[k] = factor.permutation ? factor.permutation[k] : k;
  const Tree tree = ReadTree();
  std::vector<int> block_of(n, -1);
  MakeBlocks(tree, num_threads, block_of);
  LinkBlocks(tree, block_of);
  AssignSlots(block_of);
  work_.clear();
}

EliminationTreeSolve::Tree EliminationTreeSolve::ReadTree() {
  const Index n = n_;
  const int* start = factor_.column_start;
  const int* count = factor_.column_count;
  Tree tree;
  // Pivots and the elimination tree.
  inverse_pivot_.resize(n);
  tree.parent.assign(n, -1);
  tree.subtree_work.resize(n);
  for (Index j = 0; j < n; ++j) {
    HARAP_CHECK(count[j] >= 1, "column {} of the factor is empty", j);
    const double pivot = factor_.value[start[j]];
    HARAP_CHECK(factor_.row[start[j]] == j && pivot > 0.0 && std::isfinite(pivot),
                "column {} of the factor does not start with a positive pivot", j);
    inverse_pivot_[j] = 1.0 / pivot;
    Index first_row = n;
    for (int e = start[j] + 1; e < start[j] + count[j]; ++e) {
      const int i = factor_.row[e];
      HARAP_CHECK(i > j && i < n, "entry ({}, {}) of the factor is not below the diagonal", i, j);
      first_row = std::min(first_row, i);
    }
    tree.parent[j] = first_row < n ? first_row : -1;
    tree.subtree_work[j] = count[j];  // one pass each way over the column
    tree.total_work += count[j];
  }
  tree.first_descendant.resize(n);
  tree.num_children.assign(n, 0);
  std::vector<Index> subtree_size(n, 1);
  for (Index j = 0; j < n; ++j) tree.first_descendant[j] = j;
  // Children have smaller indices than their parents, so one ascending sweep accumulates.
  for (Index j = 0; j < n; ++j) {
    const Index p = tree.parent[j];
    if (p < 0) continue;
    tree.subtree_work[p] += tree.subtree_work[j];
    subtree_size[p] += subtree_size[j];
    ++tree.num_children[p];
    tree.first_descendant[p] = std::min(tree.first_descendant[p], tree.first_descendant[j]);
  }
  for (Index j = 0; j < n && tree.postordered; ++j) {
    tree.postordered = j - tree.first_descendant[j] + 1 == subtree_size[j];
  }
  return tree;
}

void EliminationTreeSolve::MakeBlocks(const Tree& tree, int num_threads,
                                      std::vector<int>& block_of) {
  const Index n = n_;
  // Cut from the roots down, always the heaviest subtree, moving its root above the cut.
  std::vector<Index> child_head(n, -1), next_sibling(n, -1), roots;
  for (Index j = n - 1; j >= 0; --j) {
    if (tree.parent[j] < 0) {
      roots.push_back(j);
    } else {
      next_sibling[j] = child_head[tree.parent[j]];
      child_head[tree.parent[j]] = j;
    }
  }
  std::vector<unsigned char> above_cut(n, 0);
  std::vector<Index> leaf_roots;
  if (tree.postordered) {
    using Entry = std::pair<double, Index>;  // (subtree work, root)
    std::priority_queue<Entry> heaviest;
    for (Index root : roots) heaviest.emplace(tree.subtree_work[root], root);
    const double task_limit =
        std::max(kMinTaskWork,
                 tree.total_work / std::max(kMinTasks, kTasksPerThread * std::max(1, num_threads)));
    while (!heaviest.empty() && heaviest.top().first > task_limit) {
      const Index root = heaviest.top().second;
      heaviest.pop();
      above_cut[root] = 1;
      for (Index child = child_head[root]; child >= 0; child = next_sibling[child]) {
        heaviest.emplace(tree.subtree_work[child], child);
      }
    }
    for (; !heaviest.empty(); heaviest.pop()) leaf_roots.push_back(heaviest.top().second);
  }

  // Blocks: leaf subtrees, and the chains above the cut; all contiguous column ranges.
  blocks_.clear();
  const auto add_block = [&](Index begin, Index end) {
    for (Index j = begin; j < end; ++j) block_of[j] = static_cast<int>(blocks_.size());
    blocks_.push_back({begin, end});
  };
  if (!tree.postordered) {
    if (n > 0) add_block(0, n);
    return;
  }
  std::sort(leaf_roots.begin(), leaf_roots.end());
  for (Index root : leaf_roots) add_block(tree.first_descendant[root], root + 1);
  for (Index j = 0; j < n; ++j) {
    if (!above_cut[j]) continue;
    // j continues the chain of its only child j − 1 (post-order puts it right after).
    if (j > 0 && above_cut[j - 1] && tree.parent[j - 1] == j && tree.num_children[j] == 1) {
      blocks_[block_of[j - 1]].end = j + 1;
      block_of[j] = block_of[j - 1];
    } else {
      add_block(j, j + 1);
    }
  }
}

void EliminationTreeSolve::LinkBlocks(const Tree& tree, const std::vector<int>& block_of) {
  const int num_blocks = static_cast<int>(blocks_.size());
  std::vector<std::vector<int>> children(num_blocks);
  root_blocks_.clear();
  for (int b = 0; b < num_blocks; ++b) {
    const Index p = tree.parent[blocks_[b].end - 1];
    if (p < 0) {
      root_blocks_.push_back(b);
    } else {
      children[block_of[p]].push_back(b);
    }
  }
  block_children_.clear();
  for (int b = 0; b < num_blocks; ++b) {
    blocks_[b].children_begin = static_cast<int>(block_children_.size());
    block_children_.insert(block_children_.end(), children[b].begin(), children[b].end());
    blocks_[b].children_end = static_cast<int>(block_children_.size());
  }
  // Critical path, accumulated children first: a child block ends before its parent does.
  std::vector<int> by_end(num_blocks);
  for (int b = 0; b < num_blocks; ++b) by_end[b] = b;
  std::sort(by_end.begin(), by_end.end(),
            [&](int x, int y) { return blocks_[x].end < blocks_[y].end; });
  std::vector<double> path(num_blocks, 0.0);
  double critical = 0.0;
  for (int b : by_end) {
    for (Index j = blocks_[b].begin; j < blocks_[b].end; ++j) path[b] += factor_.column_count[j];
    double heaviest_child = 0.0;
    for (int c : children[b]) heaviest_child = std::max(heaviest_child, path[c]);
    path[b] += heaviest_child;
    critical = std::max(critical, path[b]);
  }
  critical_path_fraction_ = tree.total_work > 0.0 ? critical / tree.total_work : 0.0;
}

void EliminationTreeSolve::AssignSlots(const std::vector<int>& block_of) {
  const Index n = n_;
  const int* start = factor_.column_start;
  const int* count = factor_.column_count;
  const int num_blocks = static_cast<int>(blocks_.size());
  // Slots: a block's entries in rows above it get slots of the block's own.
  row_.assign(factor_.row, factor_.row + (n > 0 ? start[n] : 0));
  slot_row_.clear();
  std::vector<int> slot_of_row(n, -1);
  std::vector<Index> touched;
  for (int b = 0; b < num_blocks; ++b) {
    Block& block = blocks_[b];
    block.slots_begin = static_cast<int>(slot_row_.size());
    for (Index j = block.begin; j < block.end; ++j) {
      for (int e = start[j] + 1; e < start[j] + count[j]; ++e) {
        const int i = row_[e];
        if (i < block.end) continue;  // inside the block
        if (slot_of_row[i] < 0) {
          slot_of_row[i] = static_cast<int>(slot_row_.size());
          slot_row_.push_back(i);
          touched.push_back(i);
        }
        row_[e] = n + slot_of_row[i];
      }
    }
    block.slots_end = static_cast<int>(slot_row_.size());
    for (Index i : touched) slot_of_row[i] = -1;
    touched.clear();
  }
  // Each block gathers the slots aimed at its rows, sorted by (row, slot): a fixed order.
  std::vector<std::vector<int>> gathered(num_blocks);
  for (int slot = 0; slot < static_cast<int>(slot_row_.size()); ++slot) {
    gathered[block_of[slot_row_[slot]]].push_back(slot);
  }
  gather_slot_.clear();
  for (int b = 0; b < num_blocks; ++b) {
    auto& list = gathered[b];
    std::sort(list.begin(), list.end(), [&](int x, int y) {
      return slot_row_[x] != slot_row_[y] ? slot_row_[x] < slot_row_[y] : x < y;
    });
    blocks_[b].gather_begin = static_cast<int>(gather_slot_.size());
    gather_slot_.insert(gather_slot_.end(), list.begin(), list.end());
    blocks_[b].gather_end = static_cast<int>(gather_slot_.size());
  }
}

void EliminationTreeSolve::RefreshPivots() {
  for (Index j = 0; j < n_; ++j) {
    const double pivot = factor_.value[factor_.column_start[j]];
    HARAP_CHECK(pivot > 0.0 && std::isfinite(pivot),
                "column {} of the factor does not start with a positive pivot", j);
    inverse_pivot_[j] = 1.0 / pivot;
  }
}

template <int kColumns>
void EliminationTreeSolve::SolveInPlace(int columns, const Context& context) {
  // kColumns > 0 fixes the block width at compile time; 0 reads it from `columns`.
  const int width = kColumns > 0 ? kColumns : columns;
  double* y = work_.data();
  double* slots = y + static_cast<size_t>(n_) * width;
  const int* start = factor_.column_start;
  const int* count = factor_.column_count;
  const double* value = factor_.value;
  const int* row = row_.data();

  const auto forward_block = [&](const Block& block) {
    for (int k = block.gather_begin; k < block.gather_end; ++k) {
      const int slot = gather_slot_[k];
      double* yi = y + static_cast<size_t>(slot_row_[slot]) * width;
      const double* from = slots + static_cast<size_t>(slot) * width;
      for (int c = 0; c < width; ++c) yi[c] += from[c];
    }
    for (Index j = block.begin; j < block.end; ++j) {
      double yj[kMaxBlockColumns];
      for (int c = 0; c < width; ++c) yj[c] = y[j * width + c];
      for (int e = start[j] + 1; e < start[j] + count[j]; ++e) {
        const double l = value[e];
        double* yi = y + static_cast<size_t>(row[e]) * width;
        for (int c = 0; c < width; ++c) yi[c] -= l * yj[c];
      }
    }
  };
  const auto backward_block = [&](const Block& block) {
    for (int slot = block.slots_begin; slot < block.slots_end; ++slot) {
      const double* from = y + static_cast<size_t>(slot_row_[slot]) * width;
      double* to = slots + static_cast<size_t>(slot) * width;
      for (int c = 0; c < width; ++c) to[c] = from[c];
    }
    for (Index j = block.end; j-- > block.begin;) {
      double acc[kMaxBlockColumns];
      const double inverse_pivot = inverse_pivot_[j];
      for (int c = 0; c < width; ++c) acc[c] = y[j * width + c] * inverse_pivot;
      for (int e = start[j] + 1; e < start[j] + count[j]; ++e) {
        const double l = value[e];
        const double* yi = y + static_cast<size_t>(row[e]) * width;
        for (int c = 0; c < width; ++c) acc[c] -= l * yi[c];
      }
      for (int c = 0; c < width; ++c) y[j * width + c] = acc[c];
    }
  };
  // Runs `visit` on each of `list`'s blocks in parallel.
  const auto for_each_block = [&](const int* list, int size, auto&& visit) {
    if (size == 1) {
      visit(list[0]);
      return;
    }
    tbb::parallel_for(
        tbb::blocked_range<int>(0, size, 1),
        [&](const tbb::blocked_range<int>& range) {
          for (int k = range.begin(); k != range.end(); ++k) visit(list[k]);
        },
        tbb::simple_partitioner());
  };
  // L z = P b bottom-up: children first, then the block. (Recursive lambdas take themselves as
  // an argument: a std::function would allocate on every solve.)
  const auto forward = [&](const auto& self, int b) -> void {
    const Block& block = blocks_[b];
    for_each_block(block_children_.data() + block.children_begin,
                   block.children_end - block.children_begin, [&](int c) { self(self, c); });
    forward_block(block);
  };
  // Lᵀ w = D⁻¹ z top-down: the block, then its children.
  const auto backward = [&](const auto& self, int b) -> void {
    const Block& block = blocks_[b];
    backward_block(block);
    for_each_block(block_children_.data() + block.children_begin,
                   block.children_end - block.children_begin, [&](int c) { self(self, c); });
  };
  const int num_roots = static_cast<int>(root_blocks_.size());
  context.Run([&] {
    for_each_block(root_blocks_.data(), num_roots, [&](int b) { forward(forward, b); });
    for_each_block(root_blocks_.data(), num_roots, [&](int b) { backward(backward, b); });
  });
}

void EliminationTreeSolve::Solve(const Eigen::Ref<const Eigen::MatrixXd>& b,
                                 Eigen::Ref<Eigen::MatrixXd> x, const Context& context) {
  HARAP_CHECK(b.rows() == n_ && x.rows() == n_ && x.cols() == b.cols(),
              "b is {}×{} and x is {}×{}, the factor has {} rows", b.rows(), b.cols(), x.rows(),
              x.cols(), n_);
  constexpr Index kGrain = 4096;
  for (Eigen::Index first = 0; first < b.cols(); first += kMaxBlockColumns) {
    const int width = static_cast<int>(std::min<Eigen::Index>(kMaxBlockColumns, b.cols() - first));
    const size_t rows_with_slots = static_cast<size_t>(n_) + slot_row_.size();
    if (work_.size() < rows_with_slots * width) work_.resize(rows_with_slots * width);
    double* y = work_.data();
    // The forward pass accumulates into the slots.
    std::fill(work_.begin() + static_cast<std::ptrdiff_t>(n_) * width,
              work_.begin() + static_cast<std::ptrdiff_t>(rows_with_slots) * width, 0.0);
    context.Run([&] {
      tbb::parallel_for(tbb::blocked_range<Index>(0, n_, kGrain),
                        [&](const tbb::blocked_range<Index>& range) {
                          for (Index k = range.begin(); k != range.end(); ++k) {
                            for (int c = 0; c < width; ++c) {
                              y[static_cast<size_t>(k) * width + c] = b(permutation_[k], first + c);
                            }
                          }
                        });
    });
    switch (width) {
      case 3:
        SolveInPlace<3>(width, context);
        break;
      case 1:
        SolveInPlace<1>(width, context);
        break;
      default:
        SolveInPlace<0>(width, context);
        break;
    }
    context.Run([&] {
      tbb::parallel_for(tbb::blocked_range<Index>(0, n_, kGrain),
                        [&](const tbb::blocked_range<Index>& range) {
                          for (Index k = range.begin(); k != range.end(); ++k) {
                            for (int c = 0; c < width; ++c) {
                              x(permutation_[k], first + c) = y[static_cast<size_t>(k) * width + c];
                            }
                          }
                        });
    });
  }
}

}  // namespace harap
