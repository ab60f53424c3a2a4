// SPDX-License-Identifier: MIT
#pragma once

#include <Eigen/Dense>

namespace harap {

/// The rotation R ∈ SO(3) closest to `m` in the Frobenius norm, i.e. the maximizer of
/// tr(Rᵀ m) — the rotational factor of the polar decomposition when det(m) > 0, and
/// U diag(1, 1, −1) Vᵀ from the SVD m = U Σ Vᵀ otherwise (Kabsch / [SHR17]).
///
/// Fast path: Newton's method on SO(3) from `warm_start` (the previous iteration's rotation), which
/// converges quadratically in 1–3 steps in double precision, also for nearly flat
/// neighbourhoods. Poor warm starts and reflected or rank-deficient cases fall back to a 3×3
/// Jacobi SVD, so the result is always the exact maximizer (the local step must never increase
/// the energy).
Eigen::Matrix3d ClosestRotation(const Eigen::Matrix3d& m, const Eigen::Matrix3d& warm_start);

/// Same via the SVD only (reference implementation, used by tests and as the fallback).
Eigen::Matrix3d ClosestRotationSvd(const Eigen::Matrix3d& m);

/// The planar case: the rotation in the xy-plane closest to the upper-left 2×2 block of `m`,
/// embedded in a 3×3 matrix with R(2,2) = 1. Exact closed form: θ = atan2(m10 − m01, m00 + m11).
Eigen::Matrix3d ClosestPlanarRotation(const Eigen::Matrix3d& m);

}  // namespace harap
