// SPDX-License-Identifier: MIT
#pragma once

#include <Eigen/Dense>

namespace harap {

/// The rotation (det = +1) closest to `m` in the Frobenius norm, by the SVD m = U Σ Vᵀ:
/// R = U diag(1, 1, det(U Vᵀ)) Vᵀ (Kabsch). The reference for every rotation projection (averaged
/// rotations in up-sampling, the local step's fallback).
inline Eigen::Matrix3d NearestRotation(const Eigen::Matrix3d& m) {
  Eigen::JacobiSVD<Eigen::Matrix3d, Eigen::NoQRPreconditioner> svd(
      m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d u = svd.matrixU();
  const Eigen::Matrix3d& v = svd.matrixV();
  if ((u * v.transpose()).determinant() < 0.0) u.col(2) = -u.col(2);
  return u * v.transpose();
}

}  // namespace harap
