// SPDX-License-Identifier: MIT
// The reported energies against a direct, independent evaluation of their defining formulas
// (own cotangents, own rotation fit through Eigen's SVD of the explicit cell covariance).
#include <Eigen/SVD>
#include <catch2/catch.hpp>
#include <map>

#include "energies/spokes_and_rims_energy.h"
#include "energies/spokes_energy.h"
#include "tests/support/test_meshes.h"

using namespace harap;
using namespace harap::testing;

namespace {

double Cot(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return a.dot(b) / a.cross(b).norm();
}

Eigen::Matrix3d BestRotation(const Eigen::Matrix3d& covariance) {
  // argmax_R tr(R covariance) with covariance = Σ w ē dᵀ → R = V Uᵀ of its SVD.
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d u = svd.matrixU();
  Eigen::Matrix3d r = svd.matrixV() * u.transpose();
  if (r.determinant() < 0) {
    u.col(2) *= -1;
    r = svd.matrixV() * u.transpose();
  }
  return r;
}

// Eq. (1): Σ_i Σ_{f∋i} Σ_{(j,k)∈f} ½cot(θ_f,jk) ‖(u_j − u_k) − R_i (v_j − v_k)‖².
double SpokesAndRimsReference(const Mesh& mesh, const Positions& u) {
  const Index n = mesh.num_vertices();
  std::vector<std::vector<Index>> faces_of(n);
  for (Index f = 0; f < mesh.num_elements(); ++f) {
    for (int a = 0; a < 3; ++a) faces_of[mesh.elements(f, a)].push_back(f);
  }
  auto terms = [&](Index f, auto&& visit) {
    for (int a = 0; a < 3; ++a) {
      const Index o = mesh.elements(f, a), j = mesh.elements(f, (a + 1) % 3),
                  k = mesh.elements(f, (a + 2) % 3);
      const Eigen::Vector3d vo = mesh.vertices.row(o), vj = mesh.vertices.row(j),
                            vk = mesh.vertices.row(k);
      const double w = 0.5 * Cot(vj - vo, vk - vo);
      visit(w, Eigen::Vector3d(u.row(j) - u.row(k)), Eigen::Vector3d(vj - vk));
    }
  };
  double energy = 0.0;
  for (Index i = 0; i < n; ++i) {
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for (Index f : faces_of[i]) {
      terms(f, [&](double w, const Eigen::Vector3d& d, const Eigen::Vector3d& e) {
        covariance += w * e * d.transpose();
      });
    }
    const Eigen::Matrix3d r = BestRotation(covariance);
    for (Index f : faces_of[i]) {
      terms(f, [&](double w, const Eigen::Vector3d& d, const Eigen::Vector3d& e) {
        energy += w * (d - r * e).squaredNorm();
      });
    }
  }
  return energy;
}

// Σ_i Σ_{j∈N(i)} ½(cot α + cot β) ‖(u_i − u_j) − R_i (v_i − v_j)‖².
double SpokesReference(const Mesh& mesh, const Positions& u) {
  std::map<std::pair<Index, Index>, double> weight;
  for (Index f = 0; f < mesh.num_elements(); ++f) {
    for (int a = 0; a < 3; ++a) {
      const Index o = mesh.elements(f, a), j = mesh.elements(f, (a + 1) % 3),
                  k = mesh.elements(f, (a + 2) % 3);
      const Eigen::Vector3d vo = mesh.vertices.row(o);
      const double w = 0.5 * Cot(Eigen::Vector3d(mesh.vertices.row(j)) - vo,
                                 Eigen::Vector3d(mesh.vertices.row(k)) - vo);
      weight[{j, k}] += w;
      weight[{k, j}] += w;
    }
  }
  std::vector<std::vector<std::pair<Index, double>>> spokes(mesh.num_vertices());
  for (const auto& [edge, w] : weight) spokes[edge.first].push_back({edge.second, w});
  double energy = 0.0;
  for (Index i = 0; i < mesh.num_vertices(); ++i) {
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for (auto [j, w] : spokes[i]) {
      covariance +=
          w * Eigen::Vector3d(mesh.vertices.row(i) - mesh.vertices.row(j)) * (u.row(i) - u.row(j));
    }
    const Eigen::Matrix3d r = BestRotation(covariance);
    for (auto [j, w] : spokes[i]) {
      const Eigen::Vector3d d = u.row(i) - u.row(j);
      const Eigen::Vector3d e = mesh.vertices.row(i) - mesh.vertices.row(j);
      energy += w * (d - r * e).squaredNorm();
    }
  }
  return energy;
}

}  // namespace

TEST_CASE("spokes_and_rims energy equals Eq. (1) evaluated directly", "[energies]") {
  const Context context;
  for (const auto& mesh : {Icosphere(2), Tube(10, 14)}) {
    SpokesAndRimsEnergy energy({});
    energy.Precompute(mesh, context);
    for (double amount : {0.3, 1.0, 2.5}) {
      const Positions u = SmoothlyDeformed(mesh.vertices, amount);
      Rotations rotations(mesh.num_vertices(), Rotation::Identity());
      const double ours = energy.FitRotations(u, rotations, context);
      const double reference = SpokesAndRimsReference(mesh, u);
      REQUIRE(reference > 1e-3);
      CHECK(ours == Approx(reference).epsilon(1e-9));
      CHECK(energy.Evaluate(u, rotations, context) == Approx(reference).epsilon(1e-9));
    }
  }
}

TEST_CASE("spokes energy equals Sorkine & Alexa's formula evaluated directly", "[energies]") {
  const Context context;
  for (const auto& mesh : {Icosphere(2), Tube(10, 14)}) {
    SpokesEnergy energy({});
    energy.Precompute(mesh, context);
    for (double amount : {0.3, 1.0, 2.5}) {
      const Positions u = SmoothlyDeformed(mesh.vertices, amount);
      Rotations rotations(mesh.num_vertices(), Rotation::Identity());
      const double ours = energy.FitRotations(u, rotations, context);
      const double reference = SpokesReference(mesh, u);
      REQUIRE(reference > 1e-3);
      CHECK(ours == Approx(reference).epsilon(1e-9));
    }
  }
}

TEST_CASE("degenerate triangles get zero weight instead of inf/NaN", "[energies]") {
  Mesh mesh = Tube(6, 8);
  // Collapse one triangle to a segment (three collinear vertices) and one to a point.
  const Index a = mesh.elements(0, 0), b = mesh.elements(0, 1), c = mesh.elements(0, 2);
  mesh.vertices.row(c) = 0.5 * (mesh.vertices.row(a) + mesh.vertices.row(b));
  const Index p = mesh.elements(20, 0), q = mesh.elements(20, 1), r = mesh.elements(20, 2);
  mesh.vertices.row(q) = mesh.vertices.row(p);
  mesh.vertices.row(r) = mesh.vertices.row(p);
  const Context context;
  for (int which = 0; which < 2; ++which) {
    std::unique_ptr<CoupledQuadraticEnergy> energy;
    if (which == 0)
      energy = std::make_unique<SpokesAndRimsEnergy>(SpokesAndRimsEnergy::Options{});
    else
      energy = std::make_unique<SpokesEnergy>(SpokesEnergy::Options{});
    energy->Precompute(mesh, context);
    const SparseMatrix& m = energy->system_matrix();
    CHECK(Eigen::Map<const Eigen::VectorXd>(m.valuePtr(), m.nonZeros()).allFinite());
    Rotations rotations(mesh.num_vertices(), Rotation::Identity());
    const double e = energy->FitRotations(SmoothlyDeformed(mesh.vertices, 1.0), rotations, context);
    CHECK(std::isfinite(e));
    for (const auto& rotation : rotations) CHECK(rotation.allFinite());
  }
  SpokesAndRimsEnergy energy({});
  energy.Precompute(mesh, context);
  CHECK(energy.num_degenerate_triangles() >= 2);
}
