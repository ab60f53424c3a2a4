// SPDX-License-Identifier: MIT
#include "solvers/optimizers/small_svd.h"

#include <catch2/catch.hpp>
#include <random>

#include "framework/rotation.h"

namespace harap {
namespace {

Eigen::Matrix3d RandomRotation(std::mt19937& random) {
  std::normal_distribution<double> normal;
  return Eigen::Quaterniond(normal(random), normal(random), normal(random), normal(random))
      .normalized()
      .toRotationMatrix();
}

// Eigen's JacobiSVD with signs fixed so both factors are rotations: the reference.
Eigen::Vector3d ReferenceSignedSigma(const Eigen::Matrix3d& f) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(f, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Vector3d sigma = svd.singularValues();
  if (f.determinant() < 0.0) sigma(2) = -sigma(2);
  return sigma;
}

void CheckDecomposition(const Eigen::Matrix3d& f) {
  CAPTURE(f);
  const SignedRightSvd svd = ComputeSignedRightSvd(f);
  const double scale = std::max(f.norm(), 1e-300);
  // V is a rotation, Σ sorted by magnitude with the sign of det F on σ₃.
  CHECK((svd.v.transpose() * svd.v - Eigen::Matrix3d::Identity()).norm() < 1e-13);
  CHECK(svd.v.determinant() == Approx(1.0).epsilon(1e-12));
  CHECK(svd.sigma(0) >= svd.sigma(1));
  CHECK(svd.sigma(1) >= std::abs(svd.sigma(2)));
  CHECK((svd.sigma - ReferenceSignedSigma(f)).norm() < 1e-13 * scale);
  // F V = U Σ with orthonormal U: (F V)ᵀ(F V) = Σ².
  const Eigen::Matrix3d fv = f * svd.v;
  const Eigen::Matrix3d sigma_squared = svd.sigma.array().square().matrix().asDiagonal();
  CHECK((fv.transpose() * fv - sigma_squared).norm() < 1e-13 * scale * scale);
  // The stretch reproduces F = R S with the closest rotation R.
  const Eigen::Matrix3d rotation = ClosestRotationFromSvd(f, svd);
  CHECK((rotation - NearestRotation(f)).norm() < 1e-9);
  const Eigen::Matrix3d stretch = svd.v * svd.sigma.asDiagonal() * svd.v.transpose();
  CHECK((rotation * stretch - f).norm() < 1e-12 * scale);
  // ‖F − R‖ = ‖σ − 1‖, both to round-off relative to ‖F‖.
  CHECK(std::abs((f - rotation).norm() - (svd.sigma.array() - 1.0).matrix().norm()) <
        1e-13 * std::max(scale, 1.0));
}

TEST_CASE("the signed right SVD agrees with Eigen's JacobiSVD", "[small_svd]") {
  std::mt19937 random(7);
  std::normal_distribution<double> normal;
  const auto random_matrix = [&](double scale) {
    Eigen::Matrix3d e;
    for (int i = 0; i < 9; ++i) e(i) = scale * normal(random);
    return e;
  };
  SECTION("general matrices") {
    for (int k = 0; k < 200; ++k) CheckDecomposition(random_matrix(1.0));
  }
  SECTION("near rotations: clustered singular values, where closed-form solvers lose digits") {
    for (const double scale : {1e-3, 1e-6, 1e-9, 1e-13}) {
      for (int k = 0; k < 50; ++k) {
        CheckDecomposition(RandomRotation(random) *
                           (Eigen::Matrix3d::Identity() + random_matrix(scale)));
      }
    }
  }
  SECTION("inverted and nearly flat elements") {
    for (const double third : {-0.3, -1e-6, 1e-6, 0.0}) {
      for (int k = 0; k < 50; ++k) {
        Eigen::Matrix3d base = Eigen::Matrix3d::Identity();
        base(2, 2) = third;
        CheckDecomposition(RandomRotation(random) * (base + random_matrix(1e-9)) *
                           RandomRotation(random));
      }
    }
  }
}

TEST_CASE("a warm start changes the signed right SVD only by round-off", "[small_svd]") {
  std::mt19937 random(11);
  std::normal_distribution<double> normal;
  for (int k = 0; k < 200; ++k) {
    Eigen::Matrix3d f;
    for (int i = 0; i < 9; ++i) f(i) = normal(random);
    if (k % 2 == 0) f = RandomRotation(random) * (Eigen::Matrix3d::Identity() + 1e-4 * f);
    const SignedRightSvd cold = ComputeSignedRightSvd(f);
    // A nearby warm start (the usual case), an arbitrary rotation, and a drifted, slightly
    // non-orthogonal frame (what a long chain of warm starts could leave).
    const Eigen::Matrix3d nearby =
        cold.v * Eigen::AngleAxisd(1e-3, Eigen::Vector3d::UnitY()).toRotationMatrix();
    for (const Eigen::Matrix3d& warm :
         {nearby, RandomRotation(random), Eigen::Matrix3d(nearby * 1.001 + 1e-6 * f)}) {
      const SignedRightSvd svd = ComputeSignedRightSvd(f, warm);
      CAPTURE(f, warm);
      CHECK((svd.sigma - cold.sigma).norm() < 1e-13 * f.norm());
      CHECK(svd.v.determinant() == Approx(1.0).epsilon(1e-13));
      const Eigen::Matrix3d stretch = svd.v * svd.sigma.asDiagonal() * svd.v.transpose();
      const Eigen::Matrix3d cold_stretch = cold.v * cold.sigma.asDiagonal() * cold.v.transpose();
      CHECK((stretch - cold_stretch).norm() < 1e-13 * f.norm());
    }
  }
}

TEST_CASE("the signed right SVD of degenerate matrices", "[small_svd]") {
  SECTION("zero") {
    const SignedRightSvd svd = ComputeSignedRightSvd(Eigen::Matrix3d::Zero());
    CHECK(svd.sigma.norm() == 0.0);
    CHECK(svd.v.determinant() == Approx(1.0));
  }
  SECTION("rank one: the closest rotation falls back to the full SVD") {
    const Eigen::Matrix3d f = Eigen::Vector3d(1.0, 2.0, 3.0) * Eigen::RowVector3d(0.5, -1.0, 2.0);
    const SignedRightSvd svd = ComputeSignedRightSvd(f);
    CHECK(svd.sigma(1) < 1e-12 * svd.sigma(0));
    const Eigen::Matrix3d rotation = ClosestRotationFromSvd(f, svd);
    CHECK((rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).norm() < 1e-12);
    CHECK(rotation.determinant() == Approx(1.0));
  }
  SECTION("a reflection is inverted") {
    const Eigen::Matrix3d f = Eigen::Vector3d(1.0, 1.0, -1.0).asDiagonal();
    const SignedRightSvd svd = ComputeSignedRightSvd(f);
    CHECK(svd.sigma(2) == Approx(-1.0));
    CHECK((svd.sigma.array() - 1.0).square().sum() == Approx(4.0));
  }
}

}  // namespace
}  // namespace harap
