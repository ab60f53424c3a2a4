// SPDX-License-Identifier: MIT
#include <catch2/catch.hpp>

#include "energies/spokes_and_rims_energy.h"
#include "framework/constrained_system.h"
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
    CHECK((residual_full.row(system.free_vertices()[r]) - residual_reduced.row(r)).norm() <
          1e-10);
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
