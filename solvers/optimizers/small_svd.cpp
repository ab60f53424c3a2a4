// SPDX-License-Identifier: MIT
#include "solvers/optimizers/small_svd.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "framework/rotation.h"

namespace harap {

namespace {

/// Cyclic Jacobi on the symmetric a (only read through a[p][q], kept symmetric), accumulating the
/// rotations into v's columns; then σ_i = ‖F v_i‖, sorted, signed.
SignedRightSvd JacobiRightSvd(const Eigen::Matrix3d& f, double a[3][3], double v[3][3]) {
  constexpr int kRow[3] = {0, 0, 1}, kColumn[3] = {1, 2, 2};
  // Each sweep annihilates the three off-diagonal entries in turn; the rotation angle is the
  // smaller root (|t| ≤ 1), which is what makes cyclic Jacobi converge quadratically. Converged
  // when the off-diagonal mass is at round-off relative to the diagonal (2–4 sweeps in practice;
  // the cap only matters for NaN input, which then stays NaN).
  for (int sweep = 0; sweep < 12; ++sweep) {
    const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    const double diagonal = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
    if (!(off > 1e-32 * diagonal)) break;
    for (int k = 0; k < 3; ++k) {
      const int p = kRow[k], q = kColumn[k], r = 3 - p - q;
      const double apq = a[p][q];
      if (apq == 0.0) continue;
      const double theta = (a[q][q] - a[p][p]) / (2.0 * apq);
      const double t =
          (theta >= 0.0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1.0));
      const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
      const double arp = a[r][p], arq = a[r][q];
      a[p][p] -= t * apq;
      a[q][q] += t * apq;
      a[p][q] = a[q][p] = 0.0;
      a[r][p] = a[p][r] = c * arp - s * arq;
      a[r][q] = a[q][r] = s * arp + c * arq;
      for (int i = 0; i < 3; ++i) {
        const double vip = v[i][p], viq = v[i][q];
        v[i][p] = c * vip - s * viq;
        v[i][q] = s * vip + c * viq;
      }
    }
  }
  SignedRightSvd result;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) result.v(i, j) = v[i][j];  // a product of rotations: det = +1
  }
  for (int i = 0; i < 3; ++i) result.sigma(i) = (f * result.v.col(i)).norm();
  // Sort descending; every swap of two columns also negates one, so det V stays +1.
  const auto swap_columns = [&](int i, int j) {
    std::swap(result.sigma(i), result.sigma(j));
    result.v.col(i).swap(result.v.col(j));
    result.v.col(j) = -result.v.col(j);
  };
  if (result.sigma(1) > result.sigma(0)) swap_columns(0, 1);
  if (result.sigma(2) > result.sigma(1)) swap_columns(1, 2);
  if (result.sigma(1) > result.sigma(0)) swap_columns(0, 1);
  if (f.determinant() < 0.0) result.sigma(2) = -result.sigma(2);
  return result;
}

}  // namespace

SignedRightSvd ComputeSignedRightSvd(const Eigen::Matrix3d& f) {
  // Plain scalar arrays: Eigen's generic small-matrix expressions cost more in this loop.
  double a[3][3];
  for (int i = 0; i < 3; ++i) {
    for (int j = i; j < 3; ++j) a[i][j] = a[j][i] = f.col(i).dot(f.col(j));  // C = FᵀF
  }
  double v[3][3] = {{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}};
  return JacobiRightSvd(f, a, v);
}

SignedRightSvd ComputeSignedRightSvd(const Eigen::Matrix3d& f, const Eigen::Matrix3d& warm_v) {
  // Gram–Schmidt and a cross product: a right-handed orthonormal frame close to warm_v.
  Eigen::Matrix3d w;
  w.col(0) = warm_v.col(0).normalized();
  w.col(1) = (warm_v.col(1) - w.col(0).dot(warm_v.col(1)) * w.col(0)).normalized();
  w.col(2) = w.col(0).cross(w.col(1));
  if (!w.allFinite()) return ComputeSignedRightSvd(f);
  const Eigen::Matrix3d fw = f * w;
  double a[3][3], v[3][3];
  for (int i = 0; i < 3; ++i) {
    for (int j = i; j < 3; ++j) a[i][j] = a[j][i] = fw.col(i).dot(fw.col(j));  // wᵀ C w
    for (int j = 0; j < 3; ++j) v[i][j] = w(i, j);
  }
  return JacobiRightSvd(f, a, v);
}

Eigen::Matrix3d ClosestRotationFromSvd(const Eigen::Matrix3d& f, const SignedRightSvd& svd) {
  if (!(svd.sigma(1) > 1e-12 * svd.sigma(0))) return NearestRotation(f);
  Eigen::Matrix3d u;
  u.col(0) = f * svd.v.col(0) / svd.sigma(0);
  u.col(1) = f * svd.v.col(1) / svd.sigma(1);
  // Re-orthogonalize u₂ against u₁ (round-off in F v), then complete the right-handed frame: with
  // σ₃ signed, U is a rotation and U Vᵀ the closest rotation also for inverted F.
  u.col(1) -= u.col(0).dot(u.col(1)) * u.col(0);
  u.col(1).normalize();
  u.col(0).normalize();
  u.col(2) = u.col(0).cross(u.col(1));
  return u * svd.v.transpose();
}

}  // namespace harap
