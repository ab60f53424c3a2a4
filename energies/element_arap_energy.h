// SPDX-License-Identifier: MIT
#pragma once

#include <memory>
#include <string_view>
#include <vector>

#include "energies/kernels/rotation_coupling.h"
#include "framework/config.h"

namespace harap {

/// Per-simplex ARAP, Section 6 of the paper [Chao et al. 2010, Liu et al. 2008]: one rotation
/// per element,
///
///     E(U, R) = Σ_t Σ_{edges jk of t} w_t,jk ‖(u_j − u_k) − R_t (v̄_j − v̄_k)‖²,
///
///   - tetrahedra: w_t,jk = ℓ_lm cot θ_lm / 6 (lm the opposite edge, θ_lm its dihedral angle):
///     the paper's Eq. (9) with its ⅙ and w = ℓ cot θ; R_t ∈ SO(3);
///   - triangles of a planar mesh (Mesh::planar, z = 0): w_t,jk = ½ cot(angle opposite jk): the
///     paper's Eq. (8) with its ½; R_t a rotation of the plane (2×2 block, z row/column identity).
///
/// Both sums run over the unordered edges, so E = Σ_t |t| ‖F_t − R_t‖²_F exactly, |t| the rest
/// volume or area and F_t the deformation gradient: twice WRAPD's energy Σ_t ½ vol_t ‖F_t − R_t‖²
/// (docs/energies.md). AuxiliaryMeasures() reports that value as "energy_wrapd" = E / 2.
///
/// A = L, the volumetric (or planar) cotangent Laplacian; it is positive semi-definite for any
/// non-degenerate elements, also with the negative weights of obtuse dihedral angles, because
/// each element adds |t|·G_tᵀG_t (G_t the gradients of its barycentric coordinates). The weights
/// do not depend on the orientation of the rest elements; degenerate rest elements get zero
/// weight (see docs/energies.md). Surface triangle meshes (not planar) are rejected.
class ElementArapEnergy final : public CoupledQuadraticEnergy {
 public:
  static constexpr std::string_view kName = "elements";

  /// Options: none (CoupledQuadraticEnergy's NoOptions).
  explicit ElementArapEnergy(const Options& /*options*/)
      : CoupledQuadraticEnergy(RotationSite::kElement) {}

  void PrecomputeCoupledForm(const Mesh& rest, const Context& context) override;

  /// {"energy_wrapd": Σ_t ½ |t| ‖F_t − R_t‖²_F}, WRAPD's formula evaluated from the deformation
  /// gradients: E(u, rotations) / 2 up to round-off, but a sum of squares, so it stays accurate
  /// (and ≥ 0) near zero energy, where E's expanded form tr(UᵀAU) − 2⟨R, M⟩ + c cancels.
  /// Degenerate elements are left out, as from E.
  std::map<std::string, double> AuxiliaryMeasures(const Positions& u, const Rotations& rotations,
                                                  const Context& context) const override;

  /// Elements whose weights were zeroed as degenerate in the last Precompute().
  Index num_degenerate_elements() const { return num_degenerate_; }

 private:
  template <int K>
  void Assemble(const Mesh& rest, const Eigen::MatrixXd& edge_weights);

  Index num_degenerate_ = 0;
  Positions rest_vertices_;      ///< for the deformation gradients of AuxiliaryMeasures()
  std::vector<double> measure_;  ///< rest volume (area) per element, 0 if degenerate
};

}  // namespace harap
