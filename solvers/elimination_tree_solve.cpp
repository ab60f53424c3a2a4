// SPDX-License-Identifier: MIT
#include "solvers/elimination_tree_solve.h"

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

// Subtrees are split until none holds more than 1/max(kMinTasks, kTasksPerThread · threads) of
// the work, so that dynamic scheduling balances the threads; splitting stops early once the
// sequential top would exceed kMaxSequentialFraction of the work (a chain-like tree has little to
// gain). The split, and so the summation order, is the same for every thread count up to
// kMinTasks / kTasksPerThread: results are bit-identical for 1 to 8 threads.
constexpr double kMinTasks = 32.0;
constexpr double kTasksPerThread = 4.0;
constexpr double kMaxSequentialFraction = 0.25;
// Below this many operations a subtree is not worth a task of its own.
constexpr double kMinTaskWork = 2000.0;
// Largest block of right-hand-side columns solved in one sweep over the factor.
constexpr int kMaxBlockColumns = 4;

}  // namespace

void EliminationTreeSolve::Setup(const LdltFactorView& factor, int num_threads) {
  const Index n = factor.n;
  n_ = n;
  HARAP_CHECK(n >= 0 && factor.column_start && factor.column_count && factor.row && factor.value,
              "incomplete factor view");

  // Strictly lower L by column, pivots apart.
  column_start_.assign(n + 1, 0);
  inverse_pivot_.resize(n);
  for (Index j = 0; j < n; ++j) {
    HARAP_CHECK(factor.column_count[j] >= 1, "column {} of the factor is empty", j);
    column_start_[j + 1] = column_start_[j] + factor.column_count[j] - 1;
  }
  column_row_.resize(column_start_[n]);
  column_value_.resize(column_start_[n]);
  std::vector<Index> parent(n, -1);
  for (Index j = 0; j < n; ++j) {
    const int source = factor.column_start[j];
    const double pivot = factor.value[source];
    HARAP_CHECK(factor.row[source] == j && pivot > 0.0 && std::isfinite(pivot),
                "column {} of the factor does not start with a positive pivot", j);
    inverse_pivot_[j] = 1.0 / pivot;
    Index first_row = n;
    for (int e = 1; e < factor.column_count[j]; ++e) {
      const int i = factor.row[source + e];
      HARAP_CHECK(i > j && i < n, "entry ({}, {}) of the factor is not below the diagonal", i, j);
      column_row_[column_start_[j] + e - 1] = i;
      column_value_[column_start_[j] + e - 1] = factor.value[source + e];
      first_row = std::min(first_row, i);
    }
    parent[j] = first_row < n ? first_row : -1;  // the elimination tree
  }
  permutation_.assign(n, 0);
  for (Index k = 0; k < n; ++k) permutation_[k] = factor.permutation ? factor.permutation[k] : k;

  // Rows of L: the forward pass's work per column j is its row, the backward pass's its column.
  std::vector<int> row_count(n, 0);
  for (int i : column_row_) ++row_count[i];
  std::vector<double> subtree_work(n);
  std::vector<Index> first_descendant(n);
  std::vector<Index> subtree_size(n, 1);
  for (Index j = 0; j < n; ++j) {
    subtree_work[j] = 1.0 + row_count[j] + (column_start_[j + 1] - column_start_[j]);
    first_descendant[j] = j;
  }
  const double total_work = [&] {
    double sum = 0.0;
    for (double w : subtree_work) sum += w;
    return sum;
  }();
  // Children have smaller indices than their parents, so one ascending sweep accumulates.
  for (Index j = 0; j < n; ++j) {
    if (parent[j] < 0) continue;
    subtree_work[parent[j]] += subtree_work[j];
    subtree_size[parent[j]] += subtree_size[j];
    first_descendant[parent[j]] = std::min(first_descendant[parent[j]], first_descendant[j]);
  }
  // A post-ordered tree numbers every subtree contiguously; without that, solve sequentially.
  bool postordered = true;
  for (Index j = 0; j < n && postordered; ++j) {
    postordered = j - first_descendant[j] + 1 == subtree_size[j];
  }

  // Split from the roots down, always the heaviest subtree, moving its root to the top.
  std::vector<Index> child_head(n, -1), next_sibling(n, -1);
  std::vector<Index> roots;
  for (Index j = n - 1; j >= 0; --j) {
    if (parent[j] < 0) {
      roots.push_back(j);
    } else {
      next_sibling[j] = child_head[parent[j]];
      child_head[parent[j]] = j;
    }
  }
  std::vector<unsigned char> in_top(n, postordered ? 0 : 1);
  subtrees_.clear();
  double top_work = 0.0;
  if (postordered) {
    using Entry = std::pair<double, Index>;  // (subtree work, root)
    std::priority_queue<Entry> heaviest;
    for (Index root : roots) heaviest.emplace(subtree_work[root], root);
    const double task_limit = std::max(
        kMinTaskWork, total_work / std::max(kMinTasks, kTasksPerThread * std::max(1, num_threads)));
    while (!heaviest.empty() && heaviest.top().first > task_limit &&
           top_work < kMaxSequentialFraction * total_work) {
      const Index root = heaviest.top().second;
      heaviest.pop();
      in_top[root] = 1;
      top_work += 1.0 + row_count[root] + (column_start_[root + 1] - column_start_[root]);
      for (Index child = child_head[root]; child >= 0; child = next_sibling[child]) {
        heaviest.emplace(subtree_work[child], child);
      }
    }
    for (; !heaviest.empty(); heaviest.pop()) {
      const Index root = heaviest.top().second;
      subtrees_.push_back({first_descendant[root], root + 1});
    }
  }
  top_.clear();
  for (Index j = 0; j < n; ++j) {
    if (in_top[j]) top_.push_back(j);
  }

  // Rows of L, entries in ascending column order; for top rows, subtree columns first.
  row_start_.assign(n + 1, 0);
  for (Index i = 0; i < n; ++i) row_start_[i + 1] = row_start_[i] + row_count[i];
  row_column_.resize(column_row_.size());
  row_value_.resize(column_row_.size());
  std::vector<int> fill(row_start_.begin(), row_start_.end() - 1);
  for (Index j = 0; j < n; ++j) {
    for (int e = column_start_[j]; e < column_start_[j + 1]; ++e) {
      const int slot = fill[column_row_[e]]++;
      row_column_[slot] = j;
      row_value_[slot] = column_value_[e];
    }
  }
  row_top_begin_.resize(top_.size());
  double sequential_entries = 0.0;
  for (size_t t = 0; t < top_.size(); ++t) {
    const Index i = top_[t];
    std::vector<std::pair<int, double>> entries;
    entries.reserve(row_count[i]);
    for (int e = row_start_[i]; e < row_start_[i + 1]; ++e) {
      entries.emplace_back(row_column_[e], row_value_[e]);
    }
    const auto boundary = std::stable_partition(
        entries.begin(), entries.end(), [&](const auto& entry) { return !in_top[entry.first]; });
    row_top_begin_[t] = row_start_[i] + static_cast<int>(boundary - entries.begin());
    for (size_t k = 0; k < entries.size(); ++k) {
      row_column_[row_start_[i] + k] = entries[k].first;
      row_value_[row_start_[i] + k] = entries[k].second;
    }
    sequential_entries += (row_start_[i + 1] - row_top_begin_[t]) +
                          (column_start_[i + 1] - column_start_[i]);
  }
  sequential_fraction_ =
      column_row_.empty() ? 0.0 : sequential_entries / (2.0 * static_cast<double>(column_row_.size()));
  work_.clear();
}

template <int kColumns>
void EliminationTreeSolve::SolveInPlace(int columns, const Context& context) {
  // kColumns > 0 fixes the block width at compile time; 0 reads it from `columns`.
  const int width = kColumns > 0 ? kColumns : columns;
  double* y = work_.data();
  const auto forward_row = [&](Index i, int begin, int end) {
    double acc[kMaxBlockColumns];
    for (int c = 0; c < width; ++c) acc[c] = y[i * width + c];
    for (int e = begin; e < end; ++e) {
      const double l = row_value_[e];
      const double* yj = y + static_cast<size_t>(row_column_[e]) * width;
      for (int c = 0; c < width; ++c) acc[c] -= l * yj[c];
    }
    for (int c = 0; c < width; ++c) y[i * width + c] = acc[c];
  };
  const auto backward_column = [&](Index j) {
    double acc[kMaxBlockColumns];
    const double inverse_pivot = inverse_pivot_[j];
    for (int c = 0; c < width; ++c) acc[c] = y[j * width + c] * inverse_pivot;
    for (int e = column_start_[j]; e < column_start_[j + 1]; ++e) {
      const double l = column_value_[e];
      const double* yi = y + static_cast<size_t>(column_row_[e]) * width;
      for (int c = 0; c < width; ++c) acc[c] -= l * yi[c];
    }
    for (int c = 0; c < width; ++c) y[j * width + c] = acc[c];
  };
  const tbb::blocked_range<size_t> subtree_range(0, subtrees_.size(), 1);

  context.Run([&] {
    // L z = P b, inside the subtrees (each row reads only its own descendants).
    tbb::parallel_for(
        subtree_range,
        [&](const tbb::blocked_range<size_t>& range) {
          for (size_t s = range.begin(); s != range.end(); ++s) {
            for (Index i = subtrees_[s].begin; i < subtrees_[s].end; ++i) {
              forward_row(i, row_start_[i], row_start_[i + 1]);
            }
          }
        },
        tbb::simple_partitioner());
    // Top rows: the parts of their sums over (finished) subtree columns are independent...
    tbb::parallel_for(tbb::blocked_range<size_t>(0, top_.size(), 64),
                      [&](const tbb::blocked_range<size_t>& range) {
                        for (size_t t = range.begin(); t != range.end(); ++t) {
                          const Index i = top_[t];
                          forward_row(i, row_start_[i], row_top_begin_[t]);
                        }
                      });
    // ...the top-to-top parts go in order.
    for (size_t t = 0; t < top_.size(); ++t) {
      const Index i = top_[t];
      forward_row(i, row_top_begin_[t], row_start_[i + 1]);
    }
    // Lᵀ w = D⁻¹ z: top columns first (their ancestors are top columns), then the subtrees.
    for (size_t t = top_.size(); t-- > 0;) backward_column(top_[t]);
    tbb::parallel_for(
        subtree_range,
        [&](const tbb::blocked_range<size_t>& range) {
          for (size_t s = range.begin(); s != range.end(); ++s) {
            for (Index j = subtrees_[s].end; j-- > subtrees_[s].begin;) backward_column(j);
          }
        },
        tbb::simple_partitioner());
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
    if (work_.size() < static_cast<size_t>(n_) * width) work_.resize(static_cast<size_t>(n_) * width);
    double* y = work_.data();
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
