// SPDX-License-Identifier: MIT
#pragma once

#include <memory>
#include <string_view>

#include "energies/kernels/rotation_coupling.h"
#include "framework/config.h"

namespace harap {

/// Spokes ARAP [Sorkine & Alexa 2007]:
///
///     E(U, R) = Σ_i Σ_{j ∈ N(i)} w_ij ‖(u_i − u_j) − R_i (v̄_i − v̄_j)‖²,
///     w_ij = ½ (cot α_ij + cot β_ij)  (sum over the faces sharing edge ij; one term on a boundary).
///
/// One rotation per vertex over the edges of its 1-ring (the spokes). A = 2·L with L the
/// cotangent Laplacian (each edge is seen by the rotations of both ends). Triangle meshes only.
class SpokesEnergy final : public CoupledQuadraticEnergy {
 public:
  static constexpr std::string_view kName = "spokes";

  struct Options {
    static Options FromConfig(const ConfigNode& node);
  };

  explicit SpokesEnergy(const Options& options);
  static std::unique_ptr<Energy> Create(const ConfigNode& node);

  void Precompute(const Mesh& rest, const Context& context) override;

  Index num_degenerate_triangles() const { return num_degenerate_; }

 private:
  Options options_;
  Index num_degenerate_ = 0;
};

}  // namespace harap
