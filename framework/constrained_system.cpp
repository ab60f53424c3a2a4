// SPDX-License-Identifier: MIT
#include "framework/constrained_system.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <numeric>

#include "framework/disjoint_sets.h"
#include "framework/error.h"

namespace harap {

namespace {


}  // namespace

ConstrainedSystem::ConstrainedSystem(const SparseMatrix& a, const std::vector<Index>& constrained) {
  const Index n = static_cast<Index>(a.rows());
  HARAP_CHECK(a.rows() == a.cols(), "global matrix is {}x{}", a.rows(), a.cols());
  std::vector<unsigned char> fixed(n, 0);
  for (Index v : constrained) {
    HARAP_CHECK(v >= 0 && v < n, "constrained vertex {} out of range (n = {})", v, n);
    HARAP_CHECK(!fixed[v], "vertex {} constrained twice", v);
    fixed[v] = 1;
  }
  report_.constrained_vertices = static_cast<Index>(constrained.size());

  // Components over non-zero off-diagonal couplings; vertices with an empty row are isolated.
  DisjointSets<Index> sets(n);  // connected components of A's graph
  std::vector<unsigned char> coupled(n, 0);
  for (Index col = 0; col < n; ++col) {
    for (SparseMatrix::InnerIterator it(a, col); it; ++it) {
      if (it.value() == 0.0) continue;
      coupled[col] = 1;
      if (it.row() != col) sets.Unite(static_cast<Index>(it.row()), col);
    }
  }
  std::vector<unsigned char> component_constrained(n, 0);
  for (Index v : constrained) component_constrained[sets.Find(v)] = 1;
  for (Index v = 0; v < n; ++v) {
    if (fixed[v]) continue;
    if (!coupled[v]) {
      fixed[v] = 1;
      pinned_vertices_.push_back(v);
      ++report_.isolated_vertices;
      continue;
    }
    const Index root = sets.Find(v);
    if (!component_constrained[root]) {
      // `root` is the component's lowest index, so this is the first vertex we meet of it.
      component_constrained[root] = 1;
      fixed[v] = 1;
      pinned_vertices_.push_back(v);
      ++report_.free_components;
    }
  }
  if (report_.free_components > 0) {
    for (Index v = 0; v < n; ++v) {
      if (coupled[v]) {
        const Index root = sets.Find(v);
        bool root_pinned = std::binary_search(pinned_vertices_.begin(), pinned_vertices_.end(),
                                              root);
        if (root_pinned) ++report_.vertices_in_free_components;
      }
    }
  }

  fixed_vertices_ = constrained;
  fixed_vertices_.insert(fixed_vertices_.end(), pinned_vertices_.begin(), pinned_vertices_.end());
  free_index_.assign(n, kNoVertex);
  std::vector<Index> fixed_index(n, kNoVertex);
  for (Index k = 0; k < static_cast<Index>(fixed_vertices_.size()); ++k) {
    fixed_index[fixed_vertices_[k]] = k;
  }
  for (Index v = 0; v < n; ++v) {
    if (!fixed[v]) {
      free_index_[v] = static_cast<Index>(free_vertices_.size());
      free_vertices_.push_back(v);
    }
  }

  // Split the columns of the free vertices into A_ff and A_fc (already sorted by row).
  const Index num_free = static_cast<Index>(free_vertices_.size());
  std::vector<Eigen::Triplet<double>> ff, fc;
  ff.reserve(a.nonZeros());
  for (Index col = 0; col < n; ++col) {
    for (SparseMatrix::InnerIterator it(a, col); it; ++it) {
      const Index row_free = free_index_[it.row()];
      if (row_free == kNoVertex) continue;
      if (free_index_[col] != kNoVertex) {
        ff.emplace_back(row_free, free_index_[col], it.value());
      } else {
        fc.emplace_back(row_free, fixed_index[col], it.value());
      }
    }
  }
  a_ff_.resize(num_free, num_free);
  a_ff_.setFromTriplets(ff.begin(), ff.end());
  a_fc_.resize(num_free, static_cast<Index>(fixed_vertices_.size()));
  a_fc_.setFromTriplets(fc.begin(), fc.end());
  fixed_coupling_ = Eigen::MatrixXd::Zero(num_free, 3);
  fixed_positions_.resize(fixed_vertices_.size(), 3);
}

void ConstrainedSystem::SetFixedPositions(const Positions& u) {
  HARAP_CHECK(u.rows() == num_vertices(), "{} positions for {} vertices", u.rows(),
              num_vertices());
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
  return tbb::parallel_deterministic_reduce(
      tbb::blocked_range<Index>(0, num_free(), 4096), 0.0,
      [&](const tbb::blocked_range<Index>& range, double largest) {
        for (Index k = range.begin(); k != range.end(); ++k) {
          const Index v = free_vertices_[k];
          largest = std::max(largest, (x_f.row(k) - u.row(v)).squaredNorm());
          u.row(v) = x_f.row(k);
        }
        return largest;
      },
      [](double x, double y) { return std::max(x, y); });
}

}  // namespace harap
