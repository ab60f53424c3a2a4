// SPDX-License-Identifier: MIT
#include "solvers/optimizers/anderson_acceleration.h"

#include <catch2/catch.hpp>
#include <random>

#include "tests/support/test_factory.h"
#include "tests/support/test_meshes.h"

using namespace harap;
using namespace harap::testing;

TEST_CASE("Anderson acceleration solves a linear contraction far sooner than the plain iteration",
          "[optimizers][anderson]") {
  // x ← M x + b with a symmetric M of spectral radius 0.99: the plain iteration gains a factor
  // 0.99 per step; Anderson with m pairs is GMRES-like on (I − M) and needs few steps for a
  // spectrum clustered in a few values.
  const Eigen::Index rows = 200;
  std::mt19937 random(3);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Eigen::MatrixXd q = Eigen::MatrixXd::NullaryExpr(rows, rows, [&] { return uniform(random); });
  q = Eigen::HouseholderQR<Eigen::MatrixXd>(q).householderQ();
  Eigen::VectorXd spectrum(rows);
  for (Eigen::Index i = 0; i < rows; ++i)
    spectrum(i) = i % 3 == 0 ? 0.99 : (i % 3 == 1 ? 0.5 : -0.3);
  const Eigen::MatrixXd m = q * spectrum.asDiagonal() * q.transpose();
  const Eigen::MatrixXd b = Eigen::MatrixXd::NullaryExpr(rows, 3, [&] { return uniform(random); });
  const Eigen::MatrixXd fixed_point =
      (Eigen::MatrixXd::Identity(rows, rows) - m).partialPivLu().solve(b);
  const auto error_after = [&](int steps, bool accelerated) {
    AndersonAcceleration anderson;
    anderson.Reset(rows, 5);
    const Context context;
    Eigen::MatrixXd x = Eigen::MatrixXd::Zero(rows, 3), g(rows, 3), next(rows, 3);
    for (int k = 0; k < steps; ++k) {
      g = m * x + b;
      if (accelerated) {
        anderson.Step(x, g, next, context);
        x = next;
      } else {
        x = g;
      }
    }
    return (x - fixed_point).norm() / fixed_point.norm();
  };
  CHECK(error_after(30, false) > 0.5);  // 0.99³⁰ ≈ 0.74
  CHECK(error_after(30, true) < 1e-8);
}

TEST_CASE("Anderson acceleration: no extrapolation before a difference pair or without change",
          "[optimizers][anderson]") {
  AndersonAcceleration anderson;
  anderson.Reset(4, 3);
  const Context context;
  const Eigen::MatrixXd x = Eigen::MatrixXd::Ones(4, 3);
  Eigen::MatrixXd next(4, 3);
  CHECK_FALSE(anderson.Step(x, x * 0.5, next, context));
  CHECK(next == x * 0.5);
  // The same pair again: zero differences, nothing to extrapolate from.
  CHECK_FALSE(anderson.Step(x, x * 0.5, next, context));
  CHECK(next == x * 0.5);
  anderson.Clear();
  CHECK_FALSE(anderson.Step(x * 0.5, x * 0.25, next, context));
}

TEST_CASE("local/global with Anderson acceleration: monotone, same minimum, fewer iterations",
          "[optimizers][anderson]") {
  const Mesh mesh = Tube(24, 16);
  DeformationProblem problem;
  problem.mesh = &mesh;
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(1.2, Eigen::Vector3d::UnitX()).toRotationMatrix();
  for (int s = 0; s < 16; ++s) problem.constraints.indices.push_back(s);
  for (int s = 0; s < 16; ++s) problem.constraints.indices.push_back(23 * 16 + s);
  problem.constraints.targets.resize(32, 3);
  for (int k = 0; k < 32; ++k) {
    Eigen::Vector3d p = mesh.vertices.row(problem.constraints.indices[k]);
    if (k >= 16) p = turn * p + Eigen::Vector3d(0.0, 0.4, -0.2);
    problem.constraints.targets.row(k) = p.transpose();
  }
  const auto run = [&](const char* optimizer, int anderson, EnergyTrace& trace) {
    // Coarse targets that follow the rotations are not a descent step (and switch the
    // acceleration off); fixed ones keep every level monotone.
    const std::string fixed_targets =
        std::string(optimizer) == "hierarchical" ? "targets_follow_rotations = false\n" : "";
    TestSetup setup(
        fmt::format("[optimizer]\ntype = \"{}\"\ntolerance = 1e-12\n"
                    "max_iterations = 3000\nanderson = {}\n{}",
                    optimizer, anderson, fixed_targets));
    return OptimizeWithTrace(setup, problem, trace);
  };
  for (const char* optimizer : {"classic", "hierarchical"}) {
    DYNAMIC_SECTION(optimizer) {
      EnergyTrace plain_trace, accelerated_trace;
      const OptimizeResult plain = run(optimizer, 0, plain_trace);
      const OptimizeResult accelerated = run(optimizer, 5, accelerated_trace);
      CheckEnergiesNeverIncrease(accelerated_trace);
      REQUIRE(plain.converged);
      REQUIRE(accelerated.converged);
      CHECK(accelerated.energy == Approx(plain.energy).epsilon(1e-6));
      CHECK((accelerated.positions - plain.positions).cwiseAbs().maxCoeff() < 1e-4);
      CHECK(2 * accelerated.iterations < plain.iterations);
    }
  }
}
