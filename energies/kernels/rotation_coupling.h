// SPDX-License-Identifier: MIT
#pragma once

#include <mutex>
#include <utility>
#include <vector>

#include "framework/config.h"
#include "framework/context.h"
#include "framework/energy.h"
#include "framework/types.h"

namespace harap {

/// How the rotations enter an ARAP-type energy written as
///
///     E(U, R) = tr(Uᵀ A U) − 2 Σ_s ⟨R_s, M_s(U)⟩_F + c,     M_s(U) = Σ_j u_j c_sjᵀ  (3×3),
///
/// where s runs over rotation sites (vertices or elements) and c_sj ∈ R³ are constants of the rest
/// mesh. Every ARAP variant in harap has this form: expanding ‖(u_j − u_k) − R_s ē_jk‖² gives a
/// quadratic term in U, a cross term linear in R_s, and ‖R_s ē_jk‖² = ‖ē_jk‖², a constant.
/// So the local step is R_s = ClosestRotation(M_s) and the global right-hand side is
/// B_j = Σ_s R_s c_sj (the same coefficients, gathered by vertex).
///
/// Stored twice in CSR form, by site (for the local step) and by vertex (for the right-hand
/// side), so both kernels stream through memory in parallel without scatter conflicts.
struct RotationCoupling {
  Index num_sites = 0;
  Index num_vertices = 0;
  bool planar = false;  ///< Rotations in the xy-plane only (2D per-triangle energies).
  double constant = 0.0;

  std::vector<Index> site_offsets;                   ///< num_sites + 1
  std::vector<Index> site_vertices;                  ///< j of each (s, j)
  std::vector<Eigen::Vector3d> site_coefficients;    ///< c_sj, site-major
  std::vector<Index> vertex_offsets;                 ///< num_vertices + 1
  std::vector<Index> vertex_sites;                   ///< s of each (s, j)
  std::vector<Eigen::Vector3d> vertex_coefficients;  ///< c_sj, vertex-major

  /// Set by MakeVertexSiteCoupling: the index arrays of the pattern the by-site CSR copies. When
  /// the local step is handed a matrix A with these very arrays (same layout), it reads A's
  /// values alongside c_sj and gets tr(UᵀAU) from the same pass over memory instead of a second
  /// sweep. A matrix rebuilt or reassigned afterwards has other arrays and takes the general path.
  const Index* layout_outer = nullptr;
  const Index* layout_inner = nullptr;
};

/// The coupling of a per-vertex energy whose c_sj live on the symmetric pattern `pattern` (the
/// adjacency pattern of the mesh): `coefficient_by_entry[p]` is c_{col(p), row(p)}, i.e. the
/// column is the site and the row the vertex.
RotationCoupling MakeVertexSiteCoupling(const SparseMatrix& pattern,
                                        std::vector<Eigen::Vector3d> coefficient_by_entry,
                                        double constant);

/// The coupling of a per-element energy: site t is element t, coupled to its K vertices with
/// `coefficient_by_corner[K·t + a]` = c_{t, elements(t, a)}. `planar`: rotations in the xy-plane.
RotationCoupling MakeElementSiteCoupling(Index num_vertices, const Elements& elements,
                                         std::vector<Eigen::Vector3d> coefficient_by_corner,
                                         double constant, bool planar);

/// Local step: rotations[s] = argmax_R ⟨R, M_s(u)⟩ (warm-started from rotations[s]); returns
/// E(u, rotations) with the fitted rotations.
///
/// With `fit_coefficients` (site-major, same layout as coupling.site_coefficients) the rotations
/// are fitted to the covariances Σ_j u_j f_sjᵀ of those coefficients instead — a part of the
/// energy, as some published methods do — and the returned value is still the whole energy
/// E(u, rotations), which then need not be minimal (nor decrease).
double FitCoupledRotations(const RotationCoupling& coupling, const SparseMatrix& a,
                           const Positions& u, Rotations& rotations, const Context& context,
                           const std::vector<Eigen::Vector3d>* fit_coefficients = nullptr);

/// rhs_j = Σ_s R_s c_sj.
void AssembleCoupledRhs(const RotationCoupling& coupling, const Rotations& rotations,
                        Positions& rhs, const Context& context);

/// E(u, rotations) in the form above.
double EvaluateCoupledEnergy(const RotationCoupling& coupling, const SparseMatrix& a,
                             const Positions& u, const Rotations& rotations,
                             const Context& context);

/// Energy::PrepareRotationDerivative for the coupled form, rotations fitted to the full M_s(u).
/// With M_s = R_s S_s (polar decomposition; S_s = R_sᵀ M_s is symmetric at the fit), a variation
/// dM_s gives dR_s = R_s [w]× with ((tr S_s) I − S_s) w = a, a = axial(X − Xᵀ), X = R_sᵀ dM_s
/// (from R_sᵀ dM = W S + dS and W S + S W = [((tr S) I − S) w]× for symmetric S). `curvature[s]`
/// is K_s = ((tr S_s) I − S_s)⁻¹, eigenvalues 1/(σ_a + σ_b) over pairs of signed singular values
/// of M_s; the site's rotation term of the Hessian is −2 aᵀ K_s a.
///
/// `twist_metric` null: the exact derivative. Pairs with σ_a + σ_b ≤ 1e-8 · max (a site
/// collapsed onto a line, or inverted) get 0 instead of a huge or negative curvature.
///
/// `twist_metric` = TwistMetrics(): K_s projected so that every site's Hessian is positive
/// semi-definite, the convex model a Newton step needs. If each site's energy is a sum of
/// squares ‖D_s u − R_s D_s ū‖² with A = Σ_s Q_s (true for every energy in harap with
/// non-negative weights), the site Hessian is 2 Q_s − 2 T_sᵀ K_s T_s with T_s v = a(v), and
/// T_s Q_s⁺ T_sᵀ = N_s = (tr S̄_s) I − S̄_s, S̄_s = M_s(rest) (c_sj = (Q_s ū)_j). So it is PSD iff
/// N_s^½ K_s N_s^½ ⪯ I: K_s is replaced by N_s^-½ B̃ N_s^-½ with B̃ the eigenvalues β of
/// N_s^½ K_s N_s^½ clamped to ≤ 1 (compressed twist modes; β = 1 at rest, > 1 when compressed,
/// and for σ_a + σ_b ≤ 0 the rotation is held fixed in that direction, β̃ = 0). Stretched sites
/// keep the exact curvature. The Teran/Smith-style eigenvalue clamp of the "twist" modes, in the
/// rest metric.
void PrepareCoupledRotationDerivative(const RotationCoupling& coupling, const Positions& u,
                                      const Rotations& rotations,
                                      const std::vector<Eigen::Matrix3d>* twist_metric,
                                      std::vector<Eigen::Matrix3d>& curvature,
                                      const Context& context);

/// N_s^-½ (pseudo-inverse square root, eigenvalues ≤ 1e-8 · max dropped) of N_s = (tr S̄_s) I −
/// S̄_s, S̄_s = M_s(rest), per site: the metric of PrepareCoupledRotationDerivative's projection.
/// Planar couplings: entry (2, 2) = (tr of S̄_s's 2×2 block)^-½.
std::vector<Eigen::Matrix3d> TwistMetrics(const RotationCoupling& coupling, const Positions& rest,
                                          const Context& context);

/// Energy::RotationDerivative for the coupled form: d_rotations[s] = R_s [w_s]×,
/// w_s = curvature[s] · axial(X − Xᵀ), X = R_sᵀ M_s(v).
void CoupledRotationDerivative(const RotationCoupling& coupling, const Positions& v,
                               const Rotations& rotations,
                               const std::vector<Eigen::Matrix3d>& curvature,
                               Rotations& d_rotations, const Context& context);

/// The Options of an energy that has none: the shape Registry::Add<T>() builds from
/// (T::Options::FromConfig), which still rejects every key, so a typo fails loudly.
struct NoOptions {
  static NoOptions FromConfig(OptionReader node) {
    node.RejectUnknownKeys();
    return {};
  }
};

/// Shared implementation of the Energy interface for energies that are fully described by
/// (A, RotationCoupling): concrete energies only build `a_` and `coupling_` in
/// PrecomputeCoupledForm().
class CoupledQuadraticEnergy : public Energy {
 public:
  /// An energy of this form has no options unless it declares its own `Options`: the weights of
  /// spokes, spokes_and_rims and elements are fixed by their definitions.
  using Options = NoOptions;

  /// Keeps the rest positions (for the projected rotation derivative) and calls
  /// PrecomputeCoupledForm.
  void Precompute(const Mesh& rest, const Context& context) final;
  RotationSite rotation_site() const override { return site_; }
  /// Every element's weights are multiplied by its factor before A, the coupling and the
  /// constant are assembled, so the energy keeps the coupled form.
  void SetStiffness(std::vector<double> element_stiffness) override {
    stiffness_ = std::move(element_stiffness);
  }
  Index num_rotations() const override { return coupling_.num_sites; }
  const SparseMatrix& system_matrix() const override { return a_; }
  double FitRotations(const Positions& u, Rotations& rotations,
                      const Context& context) const override;
  void AssembleRhs(const Rotations& rotations, Positions& rhs,
                   const Context& context) const override;
  double Evaluate(const Positions& u, const Rotations& rotations,
                  const Context& context) const override;
  /// Not with fit_coefficients_: the rotations then do not minimize the energy.
  bool has_rotation_derivative() const override { return fit_coefficients_.empty(); }
  void PrepareRotationDerivative(const Positions& u, const Rotations& rotations, bool project,
                                 std::vector<Eigen::Matrix3d>& curvature,
                                 const Context& context) const override;
  void RotationDerivative(const Positions& v, const Rotations& rotations,
                          const std::vector<Eigen::Matrix3d>& curvature, Rotations& d_rotations,
                          const Context& context) const override;

 protected:
  explicit CoupledQuadraticEnergy(RotationSite site) : site_(site) {}

  RotationSite site_;
  SparseMatrix a_;
  RotationCoupling coupling_;
  /// Empty: the local step minimizes the whole energy (the default for every energy). Otherwise
  /// the coefficients the rotations are fitted to (see FitCoupledRotations), for options that
  /// reproduce a published variant.
  std::vector<Eigen::Vector3d> fit_coefficients_;
  /// SetStiffness()'s factors per element of the next rest mesh; empty: 1 everywhere.
  std::vector<double> stiffness_;
  /// Builds a_ and coupling_ (and whatever else the energy needs) for the rest mesh.
  virtual void PrecomputeCoupledForm(const Mesh& rest, const Context& context) = 0;

 private:
  // The rest positions, for the projected rotation derivative, whose TwistMetrics are computed
  // on first use (most runs never need them).
  Positions rest_positions_;
  mutable std::mutex twist_mutex_;
  mutable std::vector<Eigen::Matrix3d> twist_metric_;  ///< empty until first needed
};

}  // namespace harap
