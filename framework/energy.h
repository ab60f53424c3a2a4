// SPDX-License-Identifier: MIT
#pragma once

#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "framework/context.h"
#include "framework/error.h"
#include "framework/mesh.h"
#include "framework/types.h"

namespace harap {

/// Where an energy's rotations live: one per vertex (spokes, spokes-and-rims, smooth ARAP) or
/// one per element (per-triangle / per-tetrahedron ARAP, Section 6 of the paper).
enum class RotationSite { kVertex, kElement };

/// The weights an energy was precomputed with, for the report (per level) and its warnings.
struct EnergyWeights {
  /// The weight scheme's name ("cotan", "intrinsic_delaunay", ...); empty for energies whose
  /// weights are fixed by their definition.
  std::string scheme;
  Index edges = 0;           ///< vertex pairs coupled by a weight
  Index negative_edges = 0;  ///< of them, those whose (summed) weight is negative
  /// Negative weights take the energy out of the sum-of-squares form: it is then not bounded
  /// below, can be negative, and minimizing it exploits the negative terms. (Energies that are
  /// sums of per-element squares stay ≥ 0 whatever the sign of single weights.)
  bool can_be_negative = false;
};

/// An ARAP-type energy E(U, R) on one mesh level, minimized by local/global iterations.
///
/// Contract (every implementation): for fixed rotations R the energy is quadratic in the
/// deformed positions U (#V×3),
///
///     E(U, R) = tr(Uᵀ A U) − 2 tr(Uᵀ B(R)) + c,
///
/// with A (#V×#V, symmetric positive semi-definite) independent of U and R, so that
///   - the global step (fixed R) solves A U = B(R) on the free vertices, with A factored once;
///   - the gradient is ∂E/∂U = 2 (A U − B(R)) (checked by finite differences in the tests);
///   - the local step (fixed U) minimizes E over each rotation independently.
///
/// Lifetime: Precompute() once per mesh level (weights, A, rotation coupling; the expensive part);
/// the other methods are const, allocation-free and thread-safe, and may be called any number of
/// times. Implementations parallelize internally with TBB inside `context`'s arena.
///
///   auto energy = registries.energies.Create(config.Child("energy"), "spokes_and_rims");
///   energy->Precompute(mesh, context);
///   double e = energy->FitRotations(u, rotations, context);   // local step
///   energy->AssembleRhs(rotations, rhs, context);             // global step: A u = rhs
class Energy {
 public:
  virtual ~Energy() = default;

  /// Precomputes everything that depends only on the rest mesh. Throws InputError for meshes the
  /// energy does not support (e.g. tetrahedra for a surface energy).
  virtual void Precompute(const Mesh& rest, const Context& context) = 0;

  /// The mesh being deformed, given before Precompute() when `rest` will be a coarser level of a
  /// hierarchy. Energies whose definition depends on the mesh resolution (smooth_arap rescales its
  /// mass matrix to mean 1 over the vertices of the mesh) take their normalization from it, so that
  /// every level approximates the same energy. Without the call an energy uses the mesh it is
  /// precomputed on, which is the same thing on the input mesh. Implementations keep only the
  /// global quantities they need, not a reference; the default ignores it.
  virtual void SetInputMesh(const Mesh& /*input*/, const Context& /*context*/) {}

  /// The weights of the last Precompute() (default: none to report).
  virtual EnergyWeights weights() const { return {}; }

  /// Stiffness for the next Precompute(): one factor > 0 per element of the mesh it will be
  /// precomputed on, multiplying that element's terms (framework/stiffness.h; docs/energies.md,
  /// "Stiffness"). Empty: 1 everywhere, the energy as defined. The default accepts only empty.
  virtual void SetStiffness(std::vector<double> element_stiffness) {
    if (!element_stiffness.empty()) throw InputError("this energy takes no stiffness");
  }

  virtual RotationSite rotation_site() const = 0;
  /// Number of rotations: #V for per-vertex energies, #elements for per-element energies.
  virtual Index num_rotations() const = 0;

  /// A of the contract above (#V×#V, full symmetric storage). Rows of vertices no element
  /// touches are empty.
  virtual const SparseMatrix& system_matrix() const = 0;

  /// Local step: replaces `rotations` (size num_rotations(); the input is a warm start) by the
  /// minimizers of E(u, ·), and returns E(u, rotations) for the new rotations. (An energy may
  /// offer an option that reproduces a published variant fitting the rotations to a part of the
  /// energy, e.g. smooth_arap's rotation_fit; the returned value is then still E(u, rotations),
  /// which need not decrease. Defaults always minimize.)
  virtual double FitRotations(const Positions& u, Rotations& rotations,
                              const Context& context) const = 0;

  /// Global-step right-hand side B(R) (#V×3); `rhs` must have #V rows.
  virtual void AssembleRhs(const Rotations& rotations, Positions& rhs,
                           const Context& context) const = 0;

  /// E(u, rotations).
  virtual double Evaluate(const Positions& u, const Rotations& rotations,
                          const Context& context) const = 0;

  /// Second-order information for Newton-type optimizers (optional: see
  /// has_rotation_derivative()). With R(u) the rotations the local step fits to u, the energy of
  /// the positions alone, E(u) = E(u, R(u)), has the gradient 2 (A u − B(R(u))) (R(u) minimizes,
  /// so the rotations' own variation drops out) and, B being linear in R, the Hessian-vector
  /// product
  ///
  ///     H v = 2 (A v − B(R'(u)[v])).
  ///
  /// These methods give R'(u)[v], the derivative of the fitted rotations in direction v.
  /// Energies without it (or with an option that fits rotations to a part of the energy, so that
  /// R(u) does not minimize E) return false. Answered from the options alone, before Precompute():
  /// a run checks it when its configuration is resolved.
  virtual bool has_rotation_derivative() const { return false; }

  /// With `rotations` fitted to `u` (the local step's result), stores in `curvature` (resized to
  /// num_rotations()) what RotationDerivative needs at u, one 3×3 matrix per rotation site.
  /// `project`: instead of the exact derivative, one whose Hessian H is positive semi-definite
  /// (each rotation site's part of it projected), the model a Newton step minimizes; it equals
  /// the exact one where the mesh is locally stretched, not compressed.
  virtual void PrepareRotationDerivative(const Positions& /*u*/, const Rotations& /*rotations*/,
                                         bool /*project*/,
                                         std::vector<Eigen::Matrix3d>& /*curvature*/,
                                         const Context& /*context*/) const {
    throw InternalError("this energy has no rotation derivative (has_rotation_derivative())");
  }

  /// d_rotations[s] = R_s'(u)[v] (size num_rotations()), from PrepareRotationDerivative's
  /// `curvature` and `rotations` at u. Directions v are #V×3 like positions.
  virtual void RotationDerivative(const Positions& /*v*/, const Rotations& /*rotations*/,
                                  const std::vector<Eigen::Matrix3d>& /*curvature*/,
                                  Rotations& /*d_rotations*/, const Context& /*context*/) const {
    throw InternalError("this energy has no rotation derivative (has_rotation_derivative())");
  }

  /// Further named measures of the state (u, rotations), e.g. the energy in another package's
  /// units so results compare directly (`elements`: "energy_wrapd"). Optimizers call it once
  /// for the final state, with rotations fitted to u, and report each value under its name next
  /// to `energy`; never per iteration. Names must be valid report keys (lower_snake_case) and not
  /// clash with the report's own keys. Default: none.
  virtual std::map<std::string, double> AuxiliaryMeasures(const Positions& /*u*/,
                                                          const Rotations& /*rotations*/,
                                                          const Context& /*context*/) const {
    return {};
  }

 protected:
  Energy() = default;
};

}  // namespace harap
