// SPDX-License-Identifier: MIT
#include "energies/kernels/polar_decomposition.h"

#include <Eigen/Geometry>
#include <Eigen/SVD>
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
  Eigen::Matrix3d r = warm_start;
  for (int iteration = 0; iteration < 8; ++iteration) {
    const Eigen::Matrix3d x = r.transpose() * m;
    const Eigen::Vector3d g(x(2, 1) - x(1, 2), x(0, 2) - x(2, 0), x(1, 0) - x(0, 1));
    const Eigen::Matrix3d s = 0.5 * (x + x.transpose());
    const Eigen::Matrix3d h = s.trace() * Eigen::Matrix3d::Identity() - s;
    // Cholesky of the 3×3 H by hand, with a positive-definiteness margin relative to ‖m‖.
    const double margin = 1e-8 * std::sqrt(scale);
    const double l00 = h(0, 0);
    if (!(l00 > margin)) break;
    const double l10 = h(1, 0) / std::sqrt(l00), l20 = h(2, 0) / std::sqrt(l00);
    const double d1 = h(1, 1) - l10 * l10;
    if (!(d1 > margin)) break;
    const double l21 = (h(2, 1) - l20 * l10) / std::sqrt(d1);
    const double d2 = h(2, 2) - l20 * l20 - l21 * l21;
    if (!(d2 > margin)) break;
    // Solve H ω = g: forward then backward substitution.
    const double y0 = g(0) / std::sqrt(l00);
    const double y1 = (g(1) - l10 * y0) / std::sqrt(d1);
    const double y2 = (g(2) - l20 * y0 - l21 * y1) / std::sqrt(d2);
    Eigen::Vector3d omega;
    omega(2) = y2 / std::sqrt(d2);
    omega(1) = (y1 - l21 * omega(2)) / std::sqrt(d1);
    omega(0) = (y0 - l10 * omega(1) - l20 * omega(2)) / std::sqrt(l00);
    const double step = omega.squaredNorm();
    if (!(step < 1.0)) break;  // more than ~57°: not a local Newton regime
    // exp([ω]×) through the unit quaternion (cos θ/2, sin θ/2 · ω/θ), exact rotation.
    const double theta = std::sqrt(step);
    const double half_sin = theta > 1e-8 ? std::sin(0.5 * theta) / theta : 0.5;
    const Eigen::Quaterniond q(std::cos(0.5 * theta), half_sin * omega(0), half_sin * omega(1),
                               half_sin * omega(2));
    r = r * q.toRotationMatrix();
    // Quadratic convergence: after a step of size ‖ω‖ the error is O(‖ω‖²), so ‖ω‖ < 1e-8
    // leaves an error near machine precision.
    if (step < 1e-16) return r;
  }
  return ClosestRotationSvd(m);
}

Eigen::Matrix3d ClosestPlanarRotation(const Eigen::Matrix3d& m) {
  const double theta = std::atan2(m(1, 0) - m(0, 1), m(0, 0) + m(1, 1));
  const double c = std::cos(theta), s = std::sin(theta);
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
  r(0, 0) = c;
  r(0, 1) = -s;
  r(1, 0) = s;
  r(1, 1) = c;
  return r;
}

}  // namespace harap
