// SPDX-License-Identifier: MIT
#include "solvers/linear/multigrid_transfer.h"

#include <cmath>
#include <vector>

#include "solvers/linear/spectral_bounds.h"

namespace harap::multigrid {

std::vector<Index> AggregateByStrength(const SparseMatrix& a, double strength_threshold,
                                       Index& count) {
  const Index n = static_cast<Index>(a.rows());
  Eigen::VectorXd diagonal = a.diagonal();
  auto strong = [&](Index i, Index j, double value) {
    return i != j && std::abs(value) >= strength_threshold * std::sqrt(diagonal[i] * diagonal[j]);
  };
  constexpr Index kFree = -1;
  std::vector<Index> aggregate(n, kFree);
  count = 0;
  // (1) Roots whose strong neighbourhood is entirely free.
  for (Index i = 0; i < n; ++i) {
    if (aggregate[i] != kFree) continue;
    bool all_free = true;
    for (SparseMatrix::InnerIterator it(a, i); it && all_free; ++it) {
      const Index j = static_cast<Index>(it.row());
      if (strong(i, j, it.value()) && aggregate[j] != kFree) all_free = false;
    }
    if (!all_free) continue;
    aggregate[i] = count;
    for (SparseMatrix::InnerIterator it(a, i); it; ++it) {
      const Index j = static_cast<Index>(it.row());
      if (strong(i, j, it.value())) aggregate[j] = count;
    }
    ++count;
  }
  // (2) The rest joins the aggregate of its most strongly coupled aggregated neighbour (decided
  // from phase (1)'s aggregates only, so the order of the rows does not chain aggregates).
  std::vector<Index> joined = aggregate;
  for (Index i = 0; i < n; ++i) {
    if (aggregate[i] != kFree) continue;
    double best = 0.0;
    for (SparseMatrix::InnerIterator it(a, i); it; ++it) {
      const Index j = static_cast<Index>(it.row());
      if (aggregate[j] == kFree || !strong(i, j, it.value())) continue;
      const double strength = std::abs(it.value()) / std::sqrt(diagonal[i] * diagonal[j]);
      if (strength > best) {
        best = strength;
        joined[i] = aggregate[j];
      }
    }
  }
  aggregate.swap(joined);
  // (3) Unknowns without an aggregated strong neighbour (isolated ones included).
  for (Index i = 0; i < n; ++i) {
    if (aggregate[i] != kFree) continue;
    aggregate[i] = count;
    for (SparseMatrix::InnerIterator it(a, i); it; ++it) {
      const Index j = static_cast<Index>(it.row());
      if (aggregate[j] == kFree && strong(i, j, it.value())) aggregate[j] = count;
    }
    ++count;
  }
  return aggregate;
}

SparseMatrix ConstantProlongation(const std::vector<Index>& aggregate, Index count) {
  const Index n = static_cast<Index>(aggregate.size());
  SparseMatrix p(n, count);
  std::vector<Eigen::Triplet<double, Index>> entries;
  entries.reserve(aggregate.size());
  for (Index i = 0; i < n; ++i) entries.emplace_back(i, aggregate[i], 1.0);
  p.setFromTriplets(entries.begin(), entries.end());
  return p;
}

SparseMatrix SmoothedProlongation(const SparseMatrix& a, const SparseMatrix& constant) {
  const double omega = 4.0 / (3.0 * GershgorinUpperBound(a, SpectrumScaling::kJacobi));
  const Eigen::VectorXd scale = omega * a.diagonal().cwiseInverse();
  SparseMatrix smoothing = scale.asDiagonal() * a;
  SparseMatrix p = constant - SparseMatrix(smoothing * constant);
  p.makeCompressed();
  return p;
}

SparseMatrix GalerkinProduct(const SparseMatrix& a, const SparseMatrix& p) {
  const SparseMatrix pt = p.transpose();
  const SparseMatrix ap = a * p;
  const SparseMatrix coarse = pt * ap;
  // The two triangles were summed in different orders; their mean is exactly symmetric.
  SparseMatrix symmetric = 0.5 * (coarse + SparseMatrix(coarse.transpose()));
  symmetric.makeCompressed();
  return symmetric;
}

}  // namespace harap::multigrid
