// SPDX-License-Identifier: MIT
#pragma once

#include <memory>
#include <string_view>

#include "energies/kernels/cotangent_arap_energy.h"
#include "framework/config.h"

namespace harap {

/// Smooth ARAP [Oehri, Herholz, Sorkine-Hornung 2025, arXiv 2501.10335]: spokes-and-rims ARAP
/// blended with a term that asks the Laplacian vectors to rotate rigidly, which removes the spikes
/// and kinks ARAP shows at handles (the paper's Fig. 10 uses it):
///
///     E(U, R) = (1 − λ) · E_SR(U, R) + (3λ/2) · Σ_i ‖(L U)_i − R_i (L V̄)_i‖² / M_ii,
///
/// E_SR the `spokes_and_rims` energy (Eq. 1), L the positive semi-definite cotangent Laplacian
/// (L_ij = −½(cot α_ij + cot β_ij)), M the mixed Voronoi mass matrix (MixedVoronoiAreas) rescaled
/// so that its diagonal has mean 1 over the vertices with non-zero area, λ ∈ [0, 1).
///
/// The rescaling makes the λ-term depend on the resolution (≈ total area / #vertices times
/// ∫‖ΔU − RΔV̄‖²). On a coarse hierarchy level M is therefore rescaled with the factor of the
/// input mesh (Energy::SetInputMesh), so every level approximates the same energy;
/// `mass_normalization = "level"` rescales on each level's own mesh instead (for comparison).
///
/// This is 3 × the publication's E_SR/3 · (1 − λ) + λ/2 · Σ_i ‖…‖² / M_ii (its code weights the
/// spokes-and-rims edges by ½cot/3): the constant factor changes no minimizer and no iterate, it
/// keeps λ's meaning of the publication, and it makes λ = 0 *identical* to `spokes_and_rims`
/// (same A, coupling, constant, so the same iterates and energies bit for bit).
///
/// Global step: A = (1 − λ)·3L + (3λ/2)·L M⁻¹ L, a bi-Laplacian blend whose pattern is the 2-ring.
/// Local step: the λ-term adds (3λ/2) (L U)_i (L V̄)_iᵀ / M_ii to the covariance of vertex i (its
/// coupling coefficients are c_ij = (3λ/2) L_ij (L V̄)_i / M_ii for the 1-ring j of i), so the
/// default local step minimizes the whole energy and the iterations decrease it monotonically.
/// `rotation_fit = "spokes_and_rims"` fits the rotations to the spokes-and-rims covariances only,
/// as the published code does; the reported energy is then still the whole energy, which may
/// increase.
///
/// Triangle meshes only. Vertices without area (used by no or only degenerate triangles) have an
/// empty row of L and no λ-term.
class SmoothArapEnergy final : public CotangentArapEnergy {
 public:
  static constexpr std::string_view kName = "smooth_arap";

  enum class RotationFit {
    kWholeEnergy,    ///< "energy": minimize E over R_i (monotone; default)
    kSpokesAndRims,  ///< "spokes_and_rims": the published code's fit of the E_SR part only
  };

  struct Options {
    /// Weight of the Laplacian term, in [0, 1) (default 0.99).
    double lambda = 0.99;
    RotationFit rotation_fit = RotationFit::kWholeEnergy;
    /// M has mean 1 over the input mesh (true: the same energy on every hierarchy level) or over
    /// the mesh it is precomputed on (false: "level").
    bool normalize_mass_on_input = true;
    static Options FromConfig(OptionReader node);
  };

  explicit SmoothArapEnergy(const Options& options)
      : CotangentArapEnergy(kName), options_(options) {}

  void SetInputMesh(const Mesh& input, const Context& context) override;
  /// From the options (known before Precompute): a fit of the E_SR part alone does not minimize
  /// the energy.
  bool has_rotation_derivative() const override {
    return options_.rotation_fit == RotationFit::kWholeEnergy;
  }

 private:
  void AddFace(const Face& face, double* a_values, Eigen::Vector3d* coefficients,
               double& constant) const override;
  void AddNonFaceTerms(const RestGeometry& geometry, const Context& context) override;

  Options options_;
  /// Mean mixed Voronoi area of the input mesh's vertices with area (0: not given).
  double input_mean_area_ = 0.0;
};

}  // namespace harap
