// SPDX-License-Identifier: MIT
#include "energies/kernels/polar_decomposition.h"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

#include "framework/rotation.h"

namespace harap {

Eigen::Matrix3d ClosestRotationSvd(const Eigen::Matrix3d& m) { return NearestRotation(m); }

Eigen::Matrix3d ClosestRotation(const Eigen::Matrix3d& m, const Eigen::Matrix3d& warm_start) {
  const double scale = m.squaredNorm();
  if (!(scale > 0.0)) return warm_start;  // m = 0: every rotation is optimal; keep the old one.
  // Newton's method on the rotation manifold [ZJA21]: with R ← R·exp([ω]×) and X = Rᵀm,
  //   tr((R exp[ω])ᵀ m) ≈ tr X + gᵀω − ½ ωᵀ H ω,   g = axial(X − Xᵀ),  H = tr(S) I − S,
  // S = sym(X). At the optimum X is symmetric with eigenvalues σ1 ≥ σ2 ≥ ±σ3, so H has
  // eigenvalues σi + σj: well conditioned even for (nearly) flat neighbourhoods where σ3 ≈ 0,
  // which is where the classic polar Newton iteration crawls. From the previous iteration's
  // rotation this takes 1–3 steps. Steps that leave the region where H is positive definite
  // (a poor warm start, reflections) go to the SVD.
  // Plain scalar code: this runs once or twice per vertex per iteration, and Eigen's generic
  // 3×3 expressions compile to more instructions here (callgrind; the kernel's cost is in
  // docs/benchmarks.md, "Rotation fitting").
  double r[3][3], a[3][3];
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      r[i][j] = warm_start(i, j);
      a[i][j] = m(i, j);
    }
  }
  const double margin = 1e-8 * std::sqrt(scale);
  for (int iteration = 0; iteration < 8; ++iteration) {
    double x[3][3];  // X = Rᵀ m
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j)
        x[i][j] = r[0][i] * a[0][j] + r[1][i] * a[1][j] + r[2][i] * a[2][j];
    }
    const double g0 = x[2][1] - x[1][2], g1 = x[0][2] - x[2][0], g2 = x[1][0] - x[0][1];
    // H = tr(S) I − S with S = sym(X), written out.
    const double trace = x[0][0] + x[1][1] + x[2][2];
    const double h00 = trace - x[0][0], h11 = trace - x[1][1], h22 = trace - x[2][2];
    const double h01 = -0.5 * (x[0][1] + x[1][0]), h02 = -0.5 * (x[0][2] + x[2][0]),
                 h12 = -0.5 * (x[1][2] + x[2][1]);
    // Positive definite (Sylvester: leading minors > 0, with a margin relative to ‖m‖); then
    // ω = H⁻¹ g through the adjugate: one division, no square roots on the critical path.
    const double c00 = h11 * h22 - h12 * h12, c01 = h02 * h12 - h01 * h22,
                 c02 = h01 * h12 - h02 * h11;
    const double det = h00 * c00 + h01 * c01 + h02 * c02;
    if (!(h00 > margin && h00 * h11 - h01 * h01 > margin * margin &&
          det > margin * margin * margin)) {
      break;
    }
    const double c11 = h00 * h22 - h02 * h02, c12 = h01 * h02 - h00 * h12,
                 c22 = h00 * h11 - h01 * h01;
    const double inverse_det = 1.0 / det;
    const double w0 = (c00 * g0 + c01 * g1 + c02 * g2) * inverse_det;
    const double w1 = (c01 * g0 + c11 * g1 + c12 * g2) * inverse_det;
    const double w2 = (c02 * g0 + c12 * g1 + c22 * g2) * inverse_det;
    const double step = w0 * w0 + w1 * w1 + w2 * w2;
    if (!(step < 1.0)) break;  // more than ~57°: not a local Newton regime
    // R ← R·cay(ω): the rotation of the unit quaternion (1, ω/2)/‖·‖. It agrees with
    // exp([ω]×) up to O(‖ω‖³), which keeps Newton's quadratic convergence, and needs no
    // trigonometry.
    const double qx = 0.5 * w0, qy = 0.5 * w1, qz = 0.5 * w2;
    const double s2 = 2.0 / (1.0 + qx * qx + qy * qy + qz * qz);
    const double q[3][3] = {
        {1.0 - s2 * (qy * qy + qz * qz), s2 * (qx * qy - qz), s2 * (qx * qz + qy)},
        {s2 * (qx * qy + qz), 1.0 - s2 * (qx * qx + qz * qz), s2 * (qy * qz - qx)},
        {s2 * (qx * qz - qy), s2 * (qy * qz + qx), 1.0 - s2 * (qx * qx + qy * qy)}};
    double next[3][3];
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j)
        next[i][j] = r[i][0] * q[0][j] + r[i][1] * q[1][j] + r[i][2] * q[2][j];
    }
    std::copy(&next[0][0], &next[0][0] + 9, &r[0][0]);
    // Quadratic convergence: after a step of size ‖ω‖ the remaining error is O(‖ω‖²), so a step
    // below 1e-4 rad leaves an angle error near 1e-8 rad, i.e. an alignment (energy) error of
    // O(1e-16)·‖m‖: round-off level.
    if (step < 1e-8) {
      Eigen::Matrix3d result;
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) result(i, j) = r[i][j];
      }
      return result;
    }
  }
  return ClosestRotationSvd(m);
}

Eigen::Matrix3d ClosestPlanarRotation(const Eigen::Matrix3d& m) { return NearestPlanarRotation(m); }

}  // namespace harap
