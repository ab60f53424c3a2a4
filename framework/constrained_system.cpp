// SPDX-License-Identifier: MIT
#include "framework/constrained_system.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <numeric>

#include "framework/disjoint_sets.h"
#include "framework/error.h"

namespace harap {
namespace {

// Writes the rows of x for the free vertices into u and returns max ‖Δu_v‖² over them; x holds
// one row per free vertex (eliminated system) or one per vertex (masked system).
double ScatterRows(const std::vector<Index>& free_vertices, const Eigen::MatrixXd& x,
                   bool row_per_vertex, Positions& u) {
  return tbb::parallel_deterministic_reduce(
      tbb::blocked_range<Index>(0, static_cast<Index>(free_vertices.size()), 4096), 0.0,
      [&](const tbb::blocked_range<Index>& range, double largest) {
        for (Index k = range.begin(); k != range.end(); ++k) {
          const Index v = free_vertices[k];
          const Index row = row_per_vertex ? v : k;
          largest = std::max(largest, (x.row(row) - u.row(v)).squaredNorm());
          u.row(v) = x.row(row);
        }
        return largest;
      },
      [](double a, double b) { return std::max(a, b); });
}

// The rows of the free vertices (renumbered by `free_index`, kNoVertex for fixed ones) of the
// given columns of `a`, column k of the result being column columns[k] of `a`: A_ff or A_fc.
// Written straight into compressed storage: `free_index` is increasing on the free vertices, so
// each column's rows stay sorted (the same matrix setFromTriplets made, without its sort).
SparseMatrix FreeRowsOfColumns(const SparseMatrix& a, const std::vector<Index>& free_index,
                               const std::vector<Index>& columns, Index num_free) {
  const Index m = static_cast<Index>(columns.size());
  const Index* inner = a.innerIndexPtr();
  const double* values = a.valuePtr();
  SparseMatrix result(num_free, m);
  Index* result_outer = result.outerIndexPtr();
  result_outer[0] = 0;
  tbb::parallel_for(tbb::blocked_range<Index>(0, m, 4096), [&](const tbb::blocked_range<Index>& r) {
    for (Index k = r.begin(); k != r.end(); ++k) {
      Index count = 0;
      const auto [begin, end] = ColumnRange(a, columns[k]);
      for (Index p = begin; p < end; ++p) {
        count += free_index[inner[p]] != kNoVertex;
      }
      result_outer[k + 1] = count;
    }
  });
  for (Index k = 0; k < m; ++k) result_outer[k + 1] += result_outer[k];
  result.resizeNonZeros(result_outer[m]);
  Index* result_inner = result.innerIndexPtr();
  double* result_values = result.valuePtr();
  tbb::parallel_for(tbb::blocked_range<Index>(0, m, 4096), [&](const tbb::blocked_range<Index>& r) {
    for (Index k = r.begin(); k != r.end(); ++k) {
      Index out = result_outer[k];
      const auto [begin, end] = ColumnRange(a, columns[k]);
      for (Index p = begin; p < end; ++p) {
        const Index row = free_index[inner[p]];
        if (row == kNoVertex) continue;
        result_inner[out] = row;
        result_values[out] = values[p];
        ++out;
      }
    }
  });
  return result;
}

}  // namespace

SystemComponents::SystemComponents(const SparseMatrix& a) {
  const Index n = static_cast<Index>(a.rows());
  HARAP_CHECK(a.rows() == a.cols(), "global matrix is {}x{}", a.rows(), a.cols());
  // Components over non-zero off-diagonal couplings; vertices with an empty row are isolated.
  DisjointSets<Index> sets(n);
  coupled.assign(n, 0);
  for (Index col = 0; col < n; ++col) {
    for (SparseMatrix::InnerIterator it(a, col); it; ++it) {
      if (it.value() == 0.0) continue;
      coupled[col] = 1;
      if (it.row() != col) sets.Unite(static_cast<Index>(it.row()), col);
    }
  }
  root.resize(n);
  for (Index v = 0; v < n; ++v) root[v] = sets.Find(v);
}

FixedVertices ChooseFixedVertices(const SystemComponents& components,
                                  const std::vector<Index>& constrained,
                                  const std::vector<Index>& anchored) {
  const Index n = components.num_vertices();
  FixedVertices result;
  std::vector<unsigned char>& fixed = result.fixed;
  fixed.assign(n, 0);
  for (Index v : constrained) {
    HARAP_CHECK(v >= 0 && v < n, "constrained vertex {} out of range (n = {})", v, n);
    HARAP_CHECK(!fixed[v], "vertex {} constrained twice", v);
    fixed[v] = 1;
  }
  ConstraintReport& report = result.report;
  report.constrained_vertices = static_cast<Index>(constrained.size());
  std::vector<unsigned char> component_constrained(n, 0);
  for (Index v : constrained) component_constrained[components.root[v]] = 1;
  for (Index v : anchored) {
    HARAP_CHECK(v >= 0 && v < n, "anchored vertex {} out of range (n = {})", v, n);
    if (components.coupled[v]) component_constrained[components.root[v]] = 1;
  }
  for (Index v = 0; v < n; ++v) {
    if (fixed[v]) continue;
    if (!components.coupled[v]) {
      fixed[v] = 1;
      result.pinned.push_back(v);
      ++report.isolated_vertices;
      continue;
    }
    const Index root = components.root[v];
    if (!component_constrained[root]) {
      // `root` is the component's lowest index, so this is the first vertex we meet of it.
      component_constrained[root] = 1;
      fixed[v] = 1;
      result.pinned.push_back(v);
      ++report.free_components;
    }
  }
  if (report.free_components > 0) {
    for (Index v = 0; v < n; ++v) {
      if (components.coupled[v]) {
        const Index root = components.root[v];
        bool root_pinned = std::binary_search(result.pinned.begin(), result.pinned.end(), root);
        if (root_pinned) ++report.vertices_in_free_components;
      }
    }
  }
  return result;
}

ConstrainedSystem::ConstrainedSystem(const SparseMatrix& a, const std::vector<Index>& constrained,
                                     const std::vector<Index>& anchored) {
  const Index n = static_cast<Index>(a.rows());
  FixedVertices choice = ChooseFixedVertices(SystemComponents(a), constrained, anchored);
  const std::vector<unsigned char>& fixed = choice.fixed;
  pinned_vertices_ = std::move(choice.pinned);
  report_ = choice.report;

  fixed_vertices_ = constrained;
  fixed_vertices_.insert(fixed_vertices_.end(), pinned_vertices_.begin(), pinned_vertices_.end());
  free_index_.assign(n, kNoVertex);
  for (Index v = 0; v < n; ++v) {
    if (!fixed[v]) {
      free_index_[v] = static_cast<Index>(free_vertices_.size());
      free_vertices_.push_back(v);
    }
  }

  // Split the columns of the free vertices into A_ff and A_fc (already sorted by row).
  const Index num_free = static_cast<Index>(free_vertices_.size());
  a_ff_ = FreeRowsOfColumns(a, free_index_, free_vertices_, num_free);
  a_fc_ = FreeRowsOfColumns(a, free_index_, fixed_vertices_, num_free);
  fixed_coupling_ = Eigen::MatrixXd::Zero(num_free, 3);
  fixed_positions_.resize(fixed_vertices_.size(), 3);
}

void ConstrainedSystem::SetFixedPositions(const Positions& u) {
  HARAP_CHECK(u.rows() == num_vertices(), "{} positions for {} vertices", u.rows(), num_vertices());
  // Called before every global step when coarse targets follow the rotations: reuse the buffer.
  for (size_t k = 0; k < fixed_vertices_.size(); ++k) {
    fixed_positions_.row(k) = u.row(fixed_vertices_[k]);
  }
  fixed_coupling_.noalias() = a_fc_ * fixed_positions_;
}

void ConstrainedSystem::ReducedRhs(const Positions& b, Eigen::MatrixXd& rhs_f) const {
  const Index num_free = this->num_free();
  rhs_f.resize(num_free, 3);  // no-op after the first call
  tbb::parallel_for(tbb::blocked_range<Index>(0, num_free, 4096),
                    [&](const tbb::blocked_range<Index>& range) {
                      for (Index k = range.begin(); k != range.end(); ++k) {
                        rhs_f.row(k) = b.row(free_vertices_[k]) - fixed_coupling_.row(k);
                      }
                    });
}

void ConstrainedSystem::GatherFree(const Positions& u, Eigen::MatrixXd& x_f) const {
  x_f.resize(num_free(), 3);
  for (Index k = 0; k < num_free(); ++k) x_f.row(k) = u.row(free_vertices_[k]);
}

double ConstrainedSystem::ScatterFree(const Eigen::MatrixXd& x_f, Positions& u) const {
  return ScatterRows(free_vertices_, x_f, /*row_per_vertex=*/false, u);
}

MaskedSystem::MaskedSystem(const SparseMatrix& a) : components_(a) {
  const Index n = components_.num_vertices();
  // M's pattern: every stored entry of A (explicit zeros too: a factor's pattern then covers
  // every constraint set's) plus the whole diagonal (identity rows of isolated vertices).
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(a.nonZeros() + n);
  for (Index col = 0; col < n; ++col) {
    for (SparseMatrix::InnerIterator it(a, col); it; ++it) {
      entries.emplace_back(static_cast<Index>(it.row()), col, it.value());
    }
    entries.emplace_back(col, col, 0.0);  // summed with A's diagonal: adds exactly nothing
  }
  unmasked_.resize(n, n);
  unmasked_.setFromTriplets(entries.begin(), entries.end());
  unmasked_.makeCompressed();
  masked_ = unmasked_;
  fixed_.assign(n, 0);
  free_vertices_.resize(n);
  std::iota(free_vertices_.begin(), free_vertices_.end(), Index{0});
  fixed_coupling_ = Positions::Zero(n, 3);
}

void MaskedSystem::MaskColumn(Index column) {
  const Index begin = unmasked_.outerIndexPtr()[column];
  const Index end = unmasked_.outerIndexPtr()[column + 1];
  const Index* rows = unmasked_.innerIndexPtr();
  const double* values = unmasked_.valuePtr();
  double* masked = masked_.valuePtr();
  for (Index k = begin; k < end; ++k) {
    const Index row = rows[k];
    if (fixed_[row] || fixed_[column]) {
      masked[k] = row == column ? 1.0 : 0.0;
    } else {
      masked[k] = values[k];
    }
  }
}

std::vector<Index> MaskedSystem::SetConstrained(const std::vector<Index>& constrained,
                                                const std::vector<Index>& anchored) {
  FixedVertices choice = ChooseFixedVertices(components_, constrained, anchored);
  const Index n = num_vertices();
  std::vector<Index> changed;
  for (Index v = 0; v < n; ++v) {
    if (choice.fixed[v] != fixed_[v]) changed.push_back(v);
  }
  fixed_ = std::move(choice.fixed);
  pinned_vertices_ = std::move(choice.pinned);
  report_ = choice.report;
  // An entry (r, c) of M depends on whether r and c are fixed, so exactly the columns of the
  // changed vertices and, by symmetry, the entries of their rows in the other columns change.
  std::vector<unsigned char> touched(n, 0);
  for (Index v : changed) {
    touched[v] = 1;
    for (SparseMatrix::InnerIterator it(unmasked_, v); it; ++it) touched[it.row()] = 1;
  }
  for (Index v = 0; v < n; ++v) {
    if (touched[v]) MaskColumn(v);
  }
  fixed_vertices_ = constrained;
  fixed_vertices_.insert(fixed_vertices_.end(), pinned_vertices_.begin(), pinned_vertices_.end());
  free_vertices_.clear();
  for (Index v = 0; v < n; ++v) {
    if (!fixed_[v]) free_vertices_.push_back(v);
  }
  return changed;
}

bool MaskedSystem::SetMatrix(const SparseMatrix& a, std::vector<Index>& changed) {
  const Index n = num_vertices();
  if (a.rows() != n || a.cols() != n) return false;
  // Each column of `a` walked beside M's (both sorted by row): where each entry goes, or a misfit.
  const auto fits = [&](Index column, const auto& visit) {
    Index k = unmasked_.outerIndexPtr()[column];
    const Index end = unmasked_.outerIndexPtr()[column + 1];
    for (SparseMatrix::InnerIterator it(a, column); it; ++it) {
      for (; k < end && unmasked_.innerIndexPtr()[k] < it.row(); ++k) {
        if (unmasked_.valuePtr()[k] != 0.0) return false;
      }
      if (k == end || unmasked_.innerIndexPtr()[k] != it.row()) return false;
      // The components and isolated vertices (SystemComponents) follow the non-zero entries.
      if ((it.value() == 0.0) != (unmasked_.valuePtr()[k] == 0.0)) return false;
      visit(k++, it.value());
    }
    for (; k < end; ++k) {
      if (unmasked_.valuePtr()[k] != 0.0) return false;
    }
    return true;
  };
  for (Index column = 0; column < n; ++column) {
    if (!fits(column, [](Index, double) {})) return false;
  }
  std::vector<unsigned char> touched(n, 0);
  for (Index column = 0; column < n; ++column) {
    fits(column, [&](Index k, double value) {
      if (unmasked_.valuePtr()[k] == value) return;
      unmasked_.valuePtr()[k] = value;
      touched[column] = 1;
      touched[unmasked_.innerIndexPtr()[k]] = 1;
    });
  }
  // M changes only where the changed entries are not masked: compare before and after.
  std::vector<double> before;
  for (Index v = 0; v < n; ++v) {
    if (!touched[v]) continue;
    const Index begin = masked_.outerIndexPtr()[v], end = masked_.outerIndexPtr()[v + 1];
    before.assign(masked_.valuePtr() + begin, masked_.valuePtr() + end);
    MaskColumn(v);
    if (!std::equal(before.begin(), before.end(), masked_.valuePtr() + begin)) {
      changed.push_back(v);
    }
  }
  return true;
}

void MaskedSystem::SetFixedPositions(const Positions& u) {
  HARAP_CHECK(u.rows() == num_vertices(), "{} positions for {} vertices", u.rows(), num_vertices());
  // Free rows: A_fc U_c, gathered column by column of the fixed vertices (A is symmetric).
  for (Index v : free_vertices_) fixed_coupling_.row(v).setZero();
  for (Index c : fixed_vertices_) {
    fixed_coupling_.row(c) = u.row(c);
    for (SparseMatrix::InnerIterator it(unmasked_, c); it; ++it) {
      const Index row = static_cast<Index>(it.row());
      if (!fixed_[row]) fixed_coupling_.row(row) += it.value() * u.row(c);
    }
  }
}

void MaskedSystem::ReducedRhs(const Positions& b, Eigen::MatrixXd& rhs) const {
  const Index n = num_vertices();
  rhs.resize(n, 3);  // no-op after the first call
  tbb::parallel_for(tbb::blocked_range<Index>(0, n, 4096),
                    [&](const tbb::blocked_range<Index>& range) {
                      for (Index v = range.begin(); v != range.end(); ++v) {
                        if (fixed_[v]) {
                          rhs.row(v) = fixed_coupling_.row(v);
                        } else {
                          rhs.row(v) = b.row(v) - fixed_coupling_.row(v);
                        }
                      }
                    });
}

void MaskedSystem::GatherFree(const Positions& u, Eigen::MatrixXd& x) const { x = u; }

double MaskedSystem::ScatterFree(const Eigen::MatrixXd& x, Positions& u) const {
  return ScatterRows(free_vertices_, x, /*row_per_vertex=*/true, u);
}

}  // namespace harap
