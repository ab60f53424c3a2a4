// SPDX-License-Identifier: MIT
#include "framework/constrained_system.h"

#include <catch2/catch.hpp>

#include "energies/spokes_and_rims_energy.h"
#include "tests/support/test_meshes.h"

using namespace harap;
using namespace harap::testing;

TEST_CASE("ConstrainedSystem splits A and pins unconstrained components", "[framework]") {
  const Mesh mesh = Concatenate(Tube(5, 6), Icosphere(0));  // 30 + 12 vertices
  SpokesAndRimsEnergy energy({});
  energy.Precompute(mesh, Context());
  const SparseMatrix& a = energy.system_matrix();
  ConstrainedSystem system(a, {0, 1, 2});
  CHECK(system.report().constrained_vertices == 3);
  CHECK(system.report().free_components == 1);
  CHECK(system.report().vertices_in_free_components == 12);
  CHECK(system.pinned_vertices() == std::vector<Index>{30});
  CHECK(system.num_free() == 42 - 4);
  // A_ff is the submatrix of A on the free vertices, and positive definite.
  const Eigen::MatrixXd dense_a = Eigen::MatrixXd(a);
  const Eigen::MatrixXd a_ff = Eigen::MatrixXd(system.reduced_matrix());
  for (Index r = 0; r < system.num_free(); ++r) {
    for (Index c = 0; c < system.num_free(); ++c) {
      CHECK(a_ff(r, c) == dense_a(system.free_vertices()[r], system.free_vertices()[c]));
    }
  }
  CHECK(Eigen::LLT<Eigen::MatrixXd>(a_ff).info() == Eigen::Success);
  // The reduced right-hand side subtracts the coupling to the fixed vertices.
  Positions u = SmoothlyDeformed(mesh.vertices, 0.5);
  Positions b = Positions::Random(mesh.num_vertices(), 3);
  system.SetFixedPositions(u);
  Eigen::MatrixXd rhs_f;
  system.ReducedRhs(b, rhs_f);
  Eigen::MatrixXd x_f;
  system.GatherFree(u, x_f);
  const Eigen::MatrixXd residual_full = dense_a * u - b;  // rows of free vertices
  const Eigen::MatrixXd residual_reduced = a_ff * x_f - rhs_f;
  for (Index r = 0; r < system.num_free(); ++r) {
    CHECK((residual_full.row(system.free_vertices()[r]) - residual_reduced.row(r)).norm() < 1e-10);
  }
  // Scatter writes free rows only and returns the largest squared displacement.
  Positions v = u;
  Eigen::MatrixXd moved = x_f;
  moved(0, 0) += 2.0;
  CHECK(system.ScatterFree(moved, v) == Approx(4.0));
  CHECK(v.row(0) == u.row(0));  // constrained vertex untouched
}

TEST_CASE("ConstrainedSystem keeps isolated vertices fixed", "[framework]") {
  Mesh mesh = Tube(4, 5);
  mesh.vertices.conservativeResize(mesh.num_vertices() + 1, 3);
  mesh.vertices.row(mesh.num_vertices() - 1) << 5, 5, 5;
  SpokesAndRimsEnergy energy({});
  energy.Precompute(mesh, Context());
  ConstrainedSystem system(energy.system_matrix(), {0});
  CHECK(system.report().isolated_vertices == 1);
  CHECK(system.report().free_components == 0);
  CHECK(system.num_free() == mesh.num_vertices() - 2);
}

namespace {

// Whether two compressed matrices have the same size and sparsity pattern.
bool SamePattern(const SparseMatrix& a, const SparseMatrix& b) {
  if (a.rows() != b.rows() || a.cols() != b.cols() || a.nonZeros() != b.nonZeros()) return false;
  for (Index c = 0; c <= a.cols(); ++c) {
    if (a.outerIndexPtr()[c] != b.outerIndexPtr()[c]) return false;
  }
  for (Index k = 0; k < a.nonZeros(); ++k) {
    if (a.innerIndexPtr()[k] != b.innerIndexPtr()[k]) return false;
  }
  return true;
}

}  // namespace

TEST_CASE("MaskedSystem solves the eliminated system with one pattern for every constraint set",
          "[framework]") {
  // A tube with an isolated vertex and a separate sphere: pins of both kinds.
  Mesh mesh = Concatenate(Tube(5, 6), Icosphere(0));  // 30 + 12 vertices
  mesh.vertices.conservativeResize(mesh.num_vertices() + 1, 3);
  mesh.vertices.row(mesh.num_vertices() - 1) << 5, 5, 5;
  SpokesAndRimsEnergy energy({});
  energy.Precompute(mesh, Context());
  const SparseMatrix& a = energy.system_matrix();
  MaskedSystem masked(a);
  const std::vector<std::vector<Index>> sets = {{0, 1, 2}, {0, 1, 2, 20, 35}, {29, 3}, {0}};
  const SparseMatrix first_pattern = [&] {
    masked.SetConstrained(sets[0]);
    return masked.system_matrix();
  }();
  std::vector<unsigned char> was_fixed(mesh.num_vertices(), 0);
  for (Index v : masked.fixed_vertices()) was_fixed[v] = 1;
  for (const auto& set : sets) {
    INFO("constrained set of " << set.size() << " vertices starting with " << set[0]);
    const std::vector<Index> changed = masked.SetConstrained(set);
    const ConstrainedSystem reduced(a, set);
    // Same pins and report as the eliminated system.
    CHECK(masked.pinned_vertices() == reduced.pinned_vertices());
    CHECK(masked.fixed_vertices() == reduced.fixed_vertices());
    CHECK(masked.free_vertices() == reduced.free_vertices());
    CHECK(masked.report().free_components == reduced.report().free_components);
    CHECK(masked.report().isolated_vertices == reduced.report().isolated_vertices);
    CHECK(masked.report().vertices_in_free_components ==
          reduced.report().vertices_in_free_components);
    // The changed rows are exactly the vertices whose fixedness flipped.
    std::vector<unsigned char> fixed(mesh.num_vertices(), 0);
    for (Index v : masked.fixed_vertices()) fixed[v] = 1;
    std::vector<Index> flipped;
    for (Index v = 0; v < mesh.num_vertices(); ++v) {
      if (fixed[v] != was_fixed[v]) flipped.push_back(v);
    }
    CHECK(changed == flipped);
    was_fixed = fixed;
    // One pattern for all sets, values equal to a masked system built for this set alone.
    CHECK(SamePattern(masked.system_matrix(), first_pattern));
    MaskedSystem fresh(a);
    fresh.SetConstrained(set);
    CHECK(Eigen::MatrixXd(masked.system_matrix()) == Eigen::MatrixXd(fresh.system_matrix()));
    // The masked solution equals the eliminated one on the free rows and the fixed positions.
    Positions u = SmoothlyDeformed(mesh.vertices, 0.3);
    const Positions b = Positions::Random(mesh.num_vertices(), 3);
    masked.SetFixedPositions(u);

    Eigen::MatrixXd rhs, x;
    masked.ReducedRhs(b, rhs);
    x = Eigen::MatrixXd(masked.system_matrix()).llt().solve(rhs);
    ConstrainedSystem eliminated(a, set);
    eliminated.SetFixedPositions(u);
    Eigen::MatrixXd rhs_f;
    eliminated.ReducedRhs(b, rhs_f);
    const Eigen::MatrixXd x_f = Eigen::MatrixXd(eliminated.reduced_matrix()).llt().solve(rhs_f);
    Positions from_masked = u, from_reduced = u;
    masked.ScatterFree(x, from_masked);
    eliminated.ScatterFree(x_f, from_reduced);
    CHECK((from_masked - from_reduced).cwiseAbs().maxCoeff() < 1e-10);
    for (Index v : masked.fixed_vertices()) {
      CHECK((x.row(v) - u.row(v)).norm() < 1e-12);
      CHECK(from_masked.row(v) == u.row(v));
    }
  }
}

TEST_CASE("MaskedSystem takes another diagonal in place and names the rows it changed",
          "[framework]") {
  const Mesh mesh = Tube(5, 6);  // 30 vertices
  SpokesAndRimsEnergy energy({});
  energy.Precompute(mesh, Context());
  const SparseMatrix& a = energy.system_matrix();
  const std::vector<Index> constrained = {0, 1, 2};
  MaskedSystem masked(a);
  masked.SetConstrained(constrained);
  // A + W: a weight on two free vertices and on a fixed one (whose row is the identity's).
  SparseMatrix weighted = a;
  for (const Index v : {1, 7, 20}) weighted.coeffRef(v, v) += 3.0;
  std::vector<Index> changed;
  REQUIRE(masked.SetMatrix(weighted, changed));
  CHECK(changed == std::vector<Index>{7, 20});
  MaskedSystem fresh(weighted);
  fresh.SetConstrained(constrained);
  CHECK(Eigen::MatrixXd(masked.system_matrix()) == Eigen::MatrixXd(fresh.system_matrix()));
  // A new coupling (another component structure) or a size mismatch does not fit: unchanged.
  SparseMatrix coupled = weighted;
  coupled.coeffRef(0, 29) = -1.0;
  coupled.coeffRef(29, 0) = -1.0;
  changed.clear();
  CHECK_FALSE(masked.SetMatrix(coupled, changed));
  CHECK_FALSE(masked.SetMatrix(SparseMatrix(3, 3), changed));
  CHECK(changed.empty());
  CHECK(Eigen::MatrixXd(masked.system_matrix()) == Eigen::MatrixXd(fresh.system_matrix()));
}

TEST_CASE("ConstrainedSystem builds A_ff compressed and sorted, A_fc in the fixed order",
          "[framework]") {
  // Constrained vertices out of order: A_fc's columns follow fixed_vertices(), not the index.
  const Mesh mesh = Tube(5, 6);
  SpokesAndRimsEnergy energy({});
  energy.Precompute(mesh, Context());
  const SparseMatrix& a = energy.system_matrix();
  ConstrainedSystem system(a, {17, 3, 9});
  const SparseMatrix& a_ff = system.reduced_matrix();
  REQUIRE(a_ff.isCompressed());
  for (Index c = 0; c < a_ff.outerSize(); ++c) {
    for (Index p = a_ff.outerIndexPtr()[c] + 1; p < a_ff.outerIndexPtr()[c + 1]; ++p) {
      CHECK(a_ff.innerIndexPtr()[p - 1] < a_ff.innerIndexPtr()[p]);
    }
  }
  CHECK(a_ff.nonZeros() == (Eigen::MatrixXd(a_ff).array() != 0.0).count());
  // A_fc through the reduced right-hand side: b = 0 leaves −A_fc U_c.
  const Eigen::MatrixXd dense_a = Eigen::MatrixXd(a);
  const Positions u = Positions::Random(mesh.num_vertices(), 3);
  system.SetFixedPositions(u);
  Eigen::MatrixXd rhs_f;
  system.ReducedRhs(Positions::Zero(mesh.num_vertices(), 3), rhs_f);
  for (Index r = 0; r < system.num_free(); ++r) {
    Eigen::RowVector3d expected = Eigen::RowVector3d::Zero();
    for (Index f : system.fixed_vertices()) {
      expected -= dense_a(system.free_vertices()[r], f) * u.row(f);
    }
    CHECK((rhs_f.row(r) - expected).norm() < 1e-12);
  }
}
