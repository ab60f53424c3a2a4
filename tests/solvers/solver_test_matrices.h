// SPDX-License-Identifier: MIT
#pragma once

// Matrices and checks shared by the linear-solver tests.

#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "framework/config.h"
#include "framework/linear_solver.h"
#include "framework/registry.h"
#include "framework/types.h"
#include "solvers/linear/register_solvers.h"

namespace harap::testing {

/// A registry holding exactly what RegisterLinearSolvers() provides.
inline Registry<LinearSolver> LinearSolverRegistry() {
  Registry<LinearSolver> registry("solver");
  RegisterLinearSolvers(registry);
  return registry;
}

/// Creates `name` from TOML option text (e.g. "mode = \"simplicial\"").
inline std::unique_ptr<LinearSolver> MakeSolver(const Registry<LinearSolver>& registry,
                                                const std::string& name,
                                                const std::string& toml = "") {
  return registry.Create(name, ConfigNode::Parse(toml, "<test>"));
}

/// Iterative solvers read a `tolerance` option; direct ones do not.
inline bool IsIterative(const Registry<LinearSolver>& registry, const std::string& name) {
  for (const auto& option : registry.DescribeOptions(name)) {
    if (option.key == "tolerance") return true;
  }
  return false;
}

/// Tolerance the conformance tests give iterative solvers; their answers are then checked
/// against the direct solution to within kIterativeAccuracy instead of 1e-10.
inline constexpr double kConformanceTolerance = 1e-12;
inline constexpr double kIterativeAccuracy = 1e-8;

/// Creates `name` so that it solves to kConformanceTolerance (iterative solvers; a cap of 20000
/// iterations keeps non-converging cases fast) or exactly (direct solvers), plus `toml`.
inline std::unique_ptr<LinearSolver> MakeAccurateSolver(const Registry<LinearSolver>& registry,
                                                        const std::string& name,
                                                        const std::string& toml = "") {
  if (!IsIterative(registry, name)) return MakeSolver(registry, name, toml);
  return MakeSolver(
      registry, name,
      fmt::format("tolerance = {}\nmax_iterations = 20000\n{}", kConformanceTolerance, toml));
}

/// Graph Laplacian of a rows×cols grid (4-neighbour), random edge weights in [0.5, 2]: symmetric
/// PSD, singular (constants are in its null space), full storage.
inline SparseMatrix GridLaplacian(int rows, int cols, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> weight(0.5, 2.0);
  std::vector<Eigen::Triplet<double>> triplets;
  auto add_edge = [&](int i, int j) {
    const double w = weight(rng);
    triplets.emplace_back(i, j, -w);
    triplets.emplace_back(j, i, -w);
    triplets.emplace_back(i, i, w);
    triplets.emplace_back(j, j, w);
  };
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const int i = r * cols + c;
      if (c + 1 < cols) add_edge(i, i + 1);
      if (r + 1 < rows) add_edge(i, i + cols);
    }
  }
  SparseMatrix laplacian(rows * cols, rows * cols);
  laplacian.setFromTriplets(triplets.begin(), triplets.end());
  return laplacian;
}

/// The grid Laplacian with its boundary vertices pinned (their rows and columns removed), as the
/// global step eliminates constrained vertices: SPD, (rows−2)·(cols−2) unknowns.
inline SparseMatrix PinnedGridLaplacian(int rows, int cols, unsigned seed) {
  const SparseMatrix full = GridLaplacian(rows, cols, seed);
  std::vector<int> reduced(rows * cols, -1);
  int n = 0;
  for (int r = 1; r + 1 < rows; ++r) {
    for (int c = 1; c + 1 < cols; ++c) reduced[r * cols + c] = n++;
  }
  std::vector<Eigen::Triplet<double>> triplets;
  for (int j = 0; j < full.outerSize(); ++j) {
    for (SparseMatrix::InnerIterator it(full, j); it; ++it) {
      if (reduced[it.row()] >= 0 && reduced[it.col()] >= 0) {
        triplets.emplace_back(reduced[it.row()], reduced[it.col()], it.value());
      }
    }
  }
  SparseMatrix a(n, n);
  a.setFromTriplets(triplets.begin(), triplets.end());
  return a;
}

/// 7-point Laplacian of a side³ block with unit weights and one face pinned (Dirichlet): SPD,
/// side³ unknowns, and much more fill in its Cholesky factor than a surface mesh of that size.
inline SparseMatrix PinnedCubeLaplacian(int side) {
  auto index = [side](int x, int y, int z) { return (z * side + y) * side + x; };
  std::vector<Eigen::Triplet<double>> triplets;
  for (int z = 0; z < side; ++z) {
    for (int y = 0; y < side; ++y) {
      for (int x = 0; x < side; ++x) {
        const int i = index(x, y, z);
        double degree = z == 0 ? 1.0 : 0.0;  // The edge to the pinned face below.
        auto neighbour = [&](int j) {
          triplets.emplace_back(i, j, -1.0);
          degree += 1.0;
        };
        if (x > 0) neighbour(index(x - 1, y, z));
        if (x + 1 < side) neighbour(index(x + 1, y, z));
        if (y > 0) neighbour(index(x, y - 1, z));
        if (y + 1 < side) neighbour(index(x, y + 1, z));
        if (z > 0) neighbour(index(x, y, z - 1));
        if (z + 1 < side) neighbour(index(x, y, z + 1));
        triplets.emplace_back(i, i, degree);
      }
    }
  }
  SparseMatrix a(side * side * side, side * side * side);
  a.setFromTriplets(triplets.begin(), triplets.end());
  return a;
}

/// The block-diagonal matrix of `blocks` (independent components, a forest of elimination trees).
inline SparseMatrix BlockDiagonal(const std::vector<SparseMatrix>& blocks) {
  std::vector<Eigen::Triplet<double>> entries;
  Index offset = 0;
  for (const SparseMatrix& block : blocks) {
    for (Index j = 0; j < block.outerSize(); ++j) {
      for (SparseMatrix::InnerIterator it(block, j); it; ++it) {
        entries.emplace_back(offset + it.row(), offset + it.col(), it.value());
      }
    }
    offset += block.rows();
  }
  SparseMatrix matrix(offset, offset);
  matrix.setFromTriplets(entries.begin(), entries.end());
  return matrix;
}

inline SparseMatrix FromDense(const Eigen::MatrixXd& dense) { return dense.sparseView(); }

/// Indefinite 12×12 arrow matrix with a positive diagonal: vertex 0 is coupled to the 11 others
/// (A_00 = 1, A_0j = 0.5, A_jj = 2). Every fill-reducing ordering eliminates the hub last, and
/// its pivot 1 − 11 · 0.25 / 2 = −0.375 is the only bad one: row 0, column 11 of the factor.
inline SparseMatrix IndefiniteArrowMatrix() {
  Eigen::MatrixXd dense = 2.0 * Eigen::MatrixXd::Identity(12, 12);
  dense(0, 0) = 1.0;
  dense.row(0).tail(11).setConstant(0.5);
  dense.col(0).tail(11).setConstant(0.5);
  return FromDense(dense);
}

/// Max over columns of ‖b − A x‖ / ‖b‖.
inline double RelativeResidual(const SparseMatrix& a, const Eigen::MatrixXd& b,
                               const Eigen::MatrixXd& x) {
  const Eigen::MatrixXd r = b - a * x;
  double worst = 0.0;
  for (Eigen::Index j = 0; j < b.cols(); ++j) {
    worst = std::max(worst, r.col(j).norm() / b.col(j).norm());
  }
  return worst;
}

/// ‖x − y‖ / ‖y‖ (Frobenius).
inline double RelativeDifference(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y) {
  return (x - y).norm() / y.norm();
}

inline Eigen::MatrixXd RandomRhs(Eigen::Index rows, Eigen::Index cols, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  return Eigen::MatrixXd::NullaryExpr(rows, cols, [&] { return value(rng); });
}

}  // namespace harap::testing
