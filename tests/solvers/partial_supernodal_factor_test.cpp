// SPDX-License-Identifier: MIT
// PartialSupernodalFactor::FactorAll on a hand-made supernodal structure: the same values for
// every thread count, also when threads refuse their subtrees.
#include <catch2/catch.hpp>

#ifdef HARAP_HAVE_CHOLMOD

#include <atomic>
#include <vector>

#include "framework/context.h"
#include "solvers/linear/partial_supernodal_factor.h"

namespace harap::testing {
namespace {

// A forest of stars whose hubs hang from one root: leaves, then their hub, star after star,
// then the root (a postorder: every subtree is a contiguous range ending at its root). Its
// Cholesky factor has no fill: column j holds rows j and its parent. Each column is a supernode
// of its own.
struct StarForest {
  int stars = 0, leaves = 0, n = 0;
  SparseMatrix a;
  std::vector<int> first, row_start, value_start, row;

  StarForest(int stars_, int leaves_) : stars(stars_), leaves(leaves_) {
    n = stars * (leaves + 1) + 1;
    const int root = n - 1;
    std::vector<int> parent(n, -1);
    for (int s = 0; s < stars; ++s) {
      const int hub = s * (leaves + 1) + leaves;
      for (int l = 0; l < leaves; ++l) parent[s * (leaves + 1) + l] = hub;
      parent[hub] = root;
    }
    std::vector<Eigen::Triplet<double>> entries;
    std::vector<double> diagonal(n, 1.0);
    for (int j = 0; j < n; ++j) {
      if (parent[j] < 0) continue;
      const double w = 0.5 + 0.01 * (j % 13);  // weighted edges, diagonally dominant
      entries.emplace_back(j, parent[j], -w);
      entries.emplace_back(parent[j], j, -w);
      diagonal[j] += w;
      diagonal[parent[j]] += w;
    }
    for (int j = 0; j < n; ++j) entries.emplace_back(j, j, diagonal[j]);
    a.resize(n, n);
    a.setFromTriplets(entries.begin(), entries.end());
    a.makeCompressed();
    first.resize(n + 1);
    row_start.assign(1, 0);
    value_start.assign(1, 0);
    for (int j = 0; j <= n; ++j) first[j] = j;
    for (int j = 0; j < n; ++j) {
      row.push_back(j);
      if (parent[j] >= 0) row.push_back(parent[j]);
      row_start.push_back(static_cast<int>(row.size()));
      value_start.push_back(static_cast<int>(row.size()));  // one column: rows × 1 values
    }
  }

  // The view over `values` (sized by the caller).
  SupernodalFactorView View(std::vector<double>& values) const {
    SupernodalFactorView view;
    view.n = n;
    view.num_supernodes = n;
    view.first = first.data();
    view.row_start = row_start.data();
    view.value_start = value_start.data();
    view.row = row.data();
    view.value = values.data();
    return view;
  }
};

std::atomic<int> g_calls{0};
std::atomic<int> g_refusals{0};

// Refuses every other range of subtrees, the first one included, whichever thread takes it: the
// refused subtrees are then factored in order by the calling thread (deterministic, whatever the
// scheduler does).
bool EveryOtherRange() {
  if (g_calls++ % 2 == 1) return true;
  ++g_refusals;
  return false;
}

}  // namespace

TEST_CASE(
    "PartialSupernodalFactor: FactorAll gives the same factor on any threads, also when "
    "threads refuse their subtrees",
    "[solvers][cholmod]") {
  const StarForest forest(24, 40);
  std::vector<int> identity(forest.n);
  for (int j = 0; j < forest.n; ++j) identity[j] = j;
  const size_t size = static_cast<size_t>(forest.value_start.back());

  std::vector<double> reference(size, 0.0);
  PartialSupernodalFactor sequential;
  REQUIRE(sequential.FactorAll(forest.View(reference), forest.a, identity, 1) == -1);
  CHECK(sequential.subtrees() == 0);
  // It is A's Cholesky factor: L Lᵀ = A.
  SparseMatrix l(forest.n, forest.n);
  std::vector<Eigen::Triplet<double>> entries;
  for (int j = 0; j < forest.n; ++j) {
    for (int q = forest.row_start[j]; q < forest.row_start[j + 1]; ++q) {
      entries.emplace_back(forest.row[q], j, reference[q]);
    }
  }
  l.setFromTriplets(entries.begin(), entries.end());
  CHECK((Eigen::MatrixXd(l * SparseMatrix(l.transpose())) - Eigen::MatrixXd(forest.a)).norm() <
        1e-12 * Eigen::MatrixXd(forest.a).norm());

  for (const bool refuse : {false, true}) {
    INFO((refuse ? "every other range refused" : "all threads ready"));
    const Context context = Context::WithThreads(4);
    std::vector<double> values(size, 0.0);
    PartialSupernodalFactor parallel;
    g_calls = 0;
    g_refusals = 0;
    const int result = context.Run([&] {
      return parallel.FactorAll(forest.View(values), forest.a, identity, 4,
                                refuse ? &EveryOtherRange : nullptr);
    });
    CHECK(result == -1);
    CHECK(parallel.subtrees() >= 24);
    CHECK(values == reference);  // bit for bit
    if (refuse) CHECK(g_refusals > 0);
  }
}

}  // namespace harap::testing

#endif  // HARAP_HAVE_CHOLMOD
