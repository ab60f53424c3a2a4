// SPDX-License-Identifier: MIT
#pragma once

#include <memory>
#include <string_view>

#include "energies/kernels/cotangent_arap_energy.h"
#include "framework/config.h"

namespace harap {

/// Spokes-and-rims ARAP [Chao et al. 2010], the paper's Eq. (1):
///
///     E(U, R) = Σ_i Σ_{f ∋ i} Σ_{(j,k) ∈ f} w_fjk ‖(u_j − u_k) − R_i (v̄_j − v̄_k)‖²,
///     w_fjk = ½ cot(angle of f opposite edge jk).
///
/// One rotation per vertex; every edge of every incident face (spokes and rims) enters the
/// vertex's cell. A = 3·L with L the cotangent Laplacian (each face edge is seen by the three
/// rotations of its face). Triangle meshes only. Degenerate triangles get zero weight.
class SpokesAndRimsEnergy final : public WeightedCotangentEnergy<SpokesAndRimsEnergy> {
 public:
  static constexpr std::string_view kName = "spokes_and_rims";
  static constexpr WeightOptions kDefaultWeights{WeightScheme::kCotangent,
                                                 WeightScheme::kAsInputLevel, 0.01};
  /// Per-face sums: a negative edge weight does not take the energy out of its form.
  static constexpr bool kNegativeWeightsBreakSquares = false;

  explicit SpokesAndRimsEnergy(const Options& options) : WeightedCotangentEnergy(options) {}

 private:
  void AddFace(const Face& face, double* a_values, Eigen::Vector3d* coefficients,
               double& constant) const override;
};

}  // namespace harap
