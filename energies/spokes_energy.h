// SPDX-License-Identifier: MIT
#pragma once

#include <memory>
#include <string_view>

#include "energies/kernels/cotangent_arap_energy.h"
#include "framework/config.h"

namespace harap {

/// Spokes ARAP [Sorkine & Alexa 2007]:
///
///     E(U, R) = Σ_i Σ_{j ∈ N(i)} w_ij ‖(u_i − u_j) − R_i (v̄_i − v̄_j)‖²,
///     w_ij = ½ (cot α_ij + cot β_ij)  (sum over the faces sharing edge ij; one term on a
///     boundary), the angles of the intrinsic Delaunay triangulation by default (`weights`).
///
/// One rotation per vertex over the edges of its 1-ring (the spokes). A = 2·L with L the
/// cotangent Laplacian (each edge is seen by the rotations of both ends). Triangle meshes only.
class SpokesEnergy final : public WeightedCotangentEnergy<SpokesEnergy> {
 public:
  static constexpr std::string_view kName = "spokes";
  /// Intrinsic Delaunay weights on every level: the raw cotangent weights of obtuse angles make
  /// the spokes energy unbounded below (docs/energies.md, "Weight schemes"), and the coarse
  /// levels of a hierarchy keep non-negative weights even when `weights = "cotan"` reproduces the
  /// published definition on the input mesh.
  static constexpr WeightOptions kDefaultWeights{WeightScheme::kIntrinsicDelaunay,
                                                 WeightScheme::kIntrinsicDelaunay, 0.01};
  /// Each edge is its own square.
  static constexpr bool kNegativeWeightsBreakSquares = true;

  explicit SpokesEnergy(const Options& options) : WeightedCotangentEnergy(options) {}

 private:
  void AddFace(const Face& face, double* a_values, Eigen::Vector3d* coefficients,
               double& constant) const override;
};

}  // namespace harap
