// SPDX-License-Identifier: MIT
// Micro-benchmarks of the per-element kernels of the ADMM optimizers and of the Anderson
// acceleration step of local/global:
//   SignedSvd_{jacobi_svd,right_svd,right_svd_warm}: one 3×3 signed SVD (Eigen's JacobiSVD, the
//     cold and the warm-started Jacobi-on-FᵀF of solvers/optimizers/small_svd.h) over 100K
//     deformation gradients near rotations (stretch ±5%), as wrapd sees them; time per item = per
//     element.
//   AndersonStep/<rows>: one AndersonAcceleration::Step with a full history of 5 pairs, on
//     rows×3 iterates (173K: the armadillo's free vertices).
//
//   ./build/harap_benchmarks --benchmark_filter='SignedSvd|AndersonStep'
#include <benchmark/benchmark.h>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <random>
#include <vector>

#include "framework/context.h"
#include "solvers/optimizers/anderson_acceleration.h"
#include "solvers/optimizers/small_svd.h"

namespace {

using namespace harap;

std::vector<Eigen::Matrix3d> DeformationGradients(std::size_t count) {
  std::mt19937 random(5);
  std::normal_distribution<double> normal;
  std::vector<Eigen::Matrix3d> result(count);
  for (Eigen::Matrix3d& f : result) {
    Eigen::Matrix3d stretch = Eigen::Matrix3d::Identity();
    for (int i = 0; i < 9; ++i) stretch(i) += 0.05 * normal(random);
    f = Eigen::Quaterniond(normal(random), normal(random), normal(random), normal(random))
            .normalized()
            .toRotationMatrix() *
        stretch;
  }
  return result;
}

constexpr std::size_t kElements = 100000;

void SignedSvdJacobiSvd(benchmark::State& state) {
  const std::vector<Eigen::Matrix3d> gradients = DeformationGradients(kElements);
  for (auto _ : state) {
    for (const Eigen::Matrix3d& f : gradients) {
      const Eigen::JacobiSVD<Eigen::Matrix3d, Eigen::NoQRPreconditioner> svd(
          f, Eigen::ComputeFullU | Eigen::ComputeFullV);
      benchmark::DoNotOptimize(svd.singularValues().data());
      benchmark::DoNotOptimize(svd.matrixV().data());
    }
  }
  state.SetItemsProcessed(state.iterations() * kElements);
}

void SignedSvdRight(benchmark::State& state) {
  const std::vector<Eigen::Matrix3d> gradients = DeformationGradients(kElements);
  for (auto _ : state) {
    for (const Eigen::Matrix3d& f : gradients) {
      const SignedRightSvd svd = ComputeSignedRightSvd(f);
      benchmark::DoNotOptimize(svd.sigma.data());
      benchmark::DoNotOptimize(svd.v.data());
    }
  }
  state.SetItemsProcessed(state.iterations() * kElements);
}

void SignedSvdRightWarm(benchmark::State& state) {
  // Warm starts from the decomposition of a nearby matrix (a line-search neighbour: 1% apart).
  std::vector<Eigen::Matrix3d> gradients = DeformationGradients(kElements);
  std::vector<Eigen::Matrix3d> warm(kElements);
  std::mt19937 random(6);
  std::normal_distribution<double> normal;
  for (std::size_t k = 0; k < kElements; ++k) {
    Eigen::Matrix3d nearby = gradients[k];
    for (int i = 0; i < 9; ++i) nearby(i) += 0.01 * normal(random);
    warm[k] = ComputeSignedRightSvd(nearby).v;
  }
  for (auto _ : state) {
    for (std::size_t k = 0; k < kElements; ++k) {
      const SignedRightSvd svd = ComputeSignedRightSvd(gradients[k], warm[k]);
      benchmark::DoNotOptimize(svd.sigma.data());
      benchmark::DoNotOptimize(svd.v.data());
    }
  }
  state.SetItemsProcessed(state.iterations() * kElements);
}

void AndersonStep(benchmark::State& state) {
  const Eigen::Index rows = state.range(0);
  const Context context;
  AndersonAcceleration anderson;
  anderson.Reset(rows, 5);
  Eigen::MatrixXd x = Eigen::MatrixXd::Random(rows, 3), g(rows, 3), next(rows, 3);
  // Fill the history with pairs of a linear contraction.
  const auto map = [&](const Eigen::MatrixXd& u) { return Eigen::MatrixXd(0.9 * u.array() + 0.1); };
  for (int k = 0; k < 6; ++k) {
    g = map(x);
    anderson.Step(x, g, next, context);
    x = next;
  }
  g = map(x);
  for (auto _ : state) {
    anderson.Step(x, g, next, context);
    benchmark::DoNotOptimize(next.data());
  }
}

BENCHMARK(SignedSvdJacobiSvd)->Name("SignedSvd_jacobi_svd")->Unit(benchmark::kMillisecond);
BENCHMARK(SignedSvdRight)->Name("SignedSvd_right_svd")->Unit(benchmark::kMillisecond);
BENCHMARK(SignedSvdRightWarm)->Name("SignedSvd_right_svd_warm")->Unit(benchmark::kMillisecond);
BENCHMARK(AndersonStep)->Arg(172966)->Unit(benchmark::kMillisecond);

}  // namespace
