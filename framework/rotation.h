// SPDX-License-Identifier: MIT
#pragma once

#include <Eigen/Dense>
#include <cmath>

#include "framework/types.h"

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

/// The rotation of the xy-plane closest to the upper-left 2×2 block of `m` in the Frobenius norm,
/// embedded in a 3×3 matrix (z row and column of the identity): θ = atan2(m10 − m01, m00 + m11).
/// The projection for planar meshes, whose rotations must not tilt out of the plane.
inline Eigen::Matrix3d NearestPlanarRotation(const Eigen::Matrix3d& m) {
  const double theta = std::atan2(m(1, 0) - m(0, 1), m(0, 0) + m(1, 1));
  const double c = std::cos(theta), s = std::sin(theta);
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
  r(0, 0) = c;
  r(0, 1) = -s;
  r(1, 0) = s;
  r(1, 1) = c;
  return r;
}

/// NearestPlanarRotation for planar meshes, NearestRotation otherwise.
inline Eigen::Matrix3d NearestRotation(const Eigen::Matrix3d& m, bool planar) {
  return planar ? NearestPlanarRotation(m) : NearestRotation(m);
}

/// The paper's Eq. (11): the rotation of a vertex from the rotations of the `count` elements
/// around it (`element(i)`, i < count, their indices into `rotations`), their sum projected to
/// the nearest rotation (of the plane if `planar`); the identity without elements. One definition
/// for the up-sampling and the coarse constraint targets, so both average in the same order and
/// agree to the bit.
template <class ElementAt>
Eigen::Matrix3d MeanElementRotation(const Rotations& rotations, Index count, ElementAt&& element,
                                    bool planar) {
  if (count == 0) return Eigen::Matrix3d::Identity();
  Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
  for (Index i = 0; i < count; ++i) sum += rotations[element(i)];
  return NearestRotation(sum, planar);
}

}  // namespace harap
