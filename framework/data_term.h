// SPDX-License-Identifier: MIT
#pragma once

#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "framework/energy.h"
#include "framework/types.h"

namespace harap {

/// Soft targets: the quadratic data term D(U) = Σ_k w_k ‖u_{v_k} − t_k‖² that pulls vertex v_k
/// towards t_k with weight w_k > 0 instead of pinning it (docs/solvers.md, "Soft targets").
/// Vertices may repeat (their terms add up).
struct SoftTargets {
  std::vector<Index> vertices;
  Positions targets = Positions(0, 3);  ///< #vertices×3
  std::vector<double> weights;          ///< #vertices, each finite and > 0

  bool empty() const { return vertices.empty(); }
  /// D(u).
  double Evaluate(const Positions& u) const;
  /// The same vertices and weights (then only the targets differ: the matrix is the same).
  bool SameWeights(const SoftTargets& other) const {
    return vertices == other.vertices && weights == other.weights;
  }
};

/// An energy of the coupled form (energy.h) plus a quadratic data term D(U). D has the same
/// form, D(U) = tr(Uᵀ W U) − 2 tr(Uᵀ W T) + Σ_k w_k ‖t_k‖² with W = diag(w) on the targeted
/// rows, so the sum keeps the contract with
///
///     A' = A + W,   B'(R) = B(R) + W T,   c' = c + Σ_k w_k ‖t_k‖²:
///
/// the global step stays one factorization for fixed weights, moving the targets changes only
/// the right-hand side, and every optimizer of the coupled form minimizes the sum. Rotations are
/// the wrapped energy's (D does not depend on them), so the local step is unchanged. Without a
/// data term (SetSoftTargets with an empty set) every call is the wrapped energy's, bit for bit.
///
/// B' is affine, not linear, in R: callers that apply B to rotation derivatives (Newton steps'
/// Hessian products) need the wrapped energy's B, inner().
class EnergyWithDataTerm final : public Energy {
 public:
  explicit EnergyWithDataTerm(std::unique_ptr<Energy> energy);

  /// Replaces the data term (vertices in this energy's numbering; checked: InternalError).
  /// Returns whether system_matrix() changed (other vertices or weights).
  bool SetSoftTargets(SoftTargets soft);
  /// New targets for the same vertices and weights: only B' changes.
  void MoveSoftTargets(const Positions& targets);
  const SoftTargets& soft_targets() const { return soft_; }
  const Energy& inner() const { return *energy_; }

  void Precompute(const Mesh& rest, const Context& context) override;
  void SetInputMesh(const Mesh& input, const Context& context) override;
  void SetStiffness(std::vector<double> element_stiffness) override {
    energy_->SetStiffness(std::move(element_stiffness));
  }
  RotationSite rotation_site() const override { return energy_->rotation_site(); }
  Index num_rotations() const override { return energy_->num_rotations(); }
  const SparseMatrix& system_matrix() const override;
  double FitRotations(const Positions& u, Rotations& rotations,
                      const Context& context) const override;
  void AssembleRhs(const Rotations& rotations, Positions& rhs,
                   const Context& context) const override;
  double Evaluate(const Positions& u, const Rotations& rotations,
                  const Context& context) const override;
  bool has_rotation_derivative() const override { return energy_->has_rotation_derivative(); }
  void PrepareRotationDerivative(const Positions& u, const Rotations& rotations, bool project,
                                 std::vector<Eigen::Matrix3d>& curvature,
                                 const Context& context) const override;
  void RotationDerivative(const Positions& v, const Rotations& rotations,
                          const std::vector<Eigen::Matrix3d>& curvature, Rotations& d_rotations,
                          const Context& context) const override;
  /// The wrapped energy's measures and, with a data term, "data_energy" (D of the state).
  std::map<std::string, double> AuxiliaryMeasures(const Positions& u, const Rotations& rotations,
                                                  const Context& context) const override;

 private:
  std::unique_ptr<Energy> energy_;
  SoftTargets soft_;
  SparseMatrix matrix_;  ///< A + W while there is a data term
};

}  // namespace harap
