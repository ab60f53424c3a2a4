// SPDX-License-Identifier: MIT
#include "energies/kernels/polar_decomposition.h"

#include <catch2/catch.hpp>
#include <random>

#include "tests/support/test_meshes.h"

using namespace harap;

namespace {

double Alignment(const Eigen::Matrix3d& r, const Eigen::Matrix3d& m) {
  return r.cwiseProduct(m).sum();
}

void CheckIsRotation(const Eigen::Matrix3d& r) {
  CHECK((r.transpose() * r - Eigen::Matrix3d::Identity()).norm() < 1e-12);
  CHECK(r.determinant() == Approx(1.0).epsilon(1e-12));
}

}  // namespace

TEST_CASE("ClosestRotation equals the SVD solution for any warm start", "[energies][kernels]") {
  std::mt19937 rng(42);
  std::normal_distribution<double> normal;
  for (int trial = 0; trial < 2000; ++trial) {
    Eigen::Matrix3d m;
    for (int i = 0; i < 9; ++i) m.data()[i] = normal(rng);
    if (trial % 4 == 1) {
      // Nearly flat neighbourhood: third singular value tiny.
      Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
      Eigen::Vector3d sigma = svd.singularValues();
      sigma(2) = 1e-9 * sigma(0);
      m = svd.matrixU() * sigma.asDiagonal() * svd.matrixV().transpose();
    }
    if (trial % 4 == 2) {
      // Exactly rank 2 (a planar rest neighbourhood).
      m.col(2).setZero();
    }
    const Eigen::Matrix3d reference = ClosestRotationSvd(m);
    // Warm starts: identity, a random rotation, and one close to the answer.
    const Eigen::Matrix3d close =
        reference *
        Eigen::AngleAxisd(0.05, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
    for (const Eigen::Matrix3d& warm :
         {Eigen::Matrix3d(Eigen::Matrix3d::Identity()),
          testing::RandomRotation(static_cast<unsigned>(trial)), close}) {
      const Eigen::Matrix3d r = ClosestRotation(m, warm);
      CheckIsRotation(r);
      CHECK(Alignment(r, m) >= Alignment(reference, m) - 1e-12 * m.norm());
    }
  }
}

TEST_CASE("ClosestPlanarRotation maximizes the 2x2 alignment", "[energies][kernels]") {
  std::mt19937 rng(1);
  std::normal_distribution<double> normal;
  for (int trial = 0; trial < 200; ++trial) {
    Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2; ++j) m(i, j) = normal(rng);
    const Eigen::Matrix3d r = ClosestPlanarRotation(m);
    CheckIsRotation(r);
    CHECK(r(2, 2) == 1.0);
    for (int k = 0; k < 64; ++k) {
      const double angle = 2.0 * M_PI * k / 64.0;
      Eigen::Matrix3d other = Eigen::Matrix3d::Identity();
      other.topLeftCorner<2, 2>() << std::cos(angle), -std::sin(angle), std::sin(angle),
          std::cos(angle);
      CHECK(Alignment(r, m) >= Alignment(other, m) - 1e-12);
    }
  }
}
