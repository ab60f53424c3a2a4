// SPDX-License-Identifier: MIT
#pragma once

#include <vector>

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

/// Shared implementation of the Energy interface for energies that are fully described by
/// (A, RotationCoupling): concrete energies only build `a_` and `coupling_` in Precompute().
class CoupledQuadraticEnergy : public Energy {
 public:
  RotationSite rotation_site() const override { return site_; }
  Index num_rotations() const override { return coupling_.num_sites; }
  const SparseMatrix& system_matrix() const override { return a_; }
  double FitRotations(const Positions& u, Rotations& rotations,
                      const Context& context) const override;
  void AssembleRhs(const Rotations& rotations, Positions& rhs,
                   const Context& context) const override;
  double Evaluate(const Positions& u, const Rotations& rotations,
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
};

}  // namespace harap
