// SPDX-License-Identifier: MIT
#pragma once

#include <Eigen/Dense>
#include <vector>

#include "framework/constrained_system.h"
#include "framework/context.h"
#include "framework/energy.h"
#include "framework/linear_solver.h"

namespace harap {

/// Truncated Newton steps on the energy of the positions alone, E(u) = E(u, R(u)) with R(u) the
/// local step's rotations, for the tail of a local/global run where the plain iteration crawls.
///
/// The local/global step is a preconditioned gradient step: with g = 2 (A u − B(R(u))) on the free
/// vertices and P = 2 A_ff (the factored global matrix), u⁺ = u − P⁻¹ g. Its rate is set by the
/// smallest eigenvalues of P⁻¹H, H the Hessian (Energy::RotationDerivative), which the soft
/// bending modes of large meshes make tiny. Here P⁻¹ instead preconditions conjugate gradients on
/// H d = −g, whose iteration count grows only with the square root of P⁻¹H's condition number.
/// Two models of H:
///   - projected: every rotation site's Hessian clamped to positive semi-definite
///     (Energy::PrepareRotationDerivative with `project`), so 0 ⪯ H ⪯ P; the step is u + α d
///     with Armijo backtracking on E. The first CG iterate is the local/global step scaled by an
///     exact line search (α ≥ 1, since H ⪯ P), so a Newton step with one CG iteration is an
///     over-relaxed local/global step. The projection ignores negative curvature, so near a
///     saddle point the steps crawl as the plain iteration does.
///   - exact (default): the true, indefinite H in a trust region of the P-norm (Steihaug–Toint CG:
///   to the
///     region's boundary along a direction of negative curvature), radius adapted by the ratio of
///     actual to predicted decrease [Nocedal & Wright, Alg. 4.1, 7.2]; it leaves saddles along
///     their negative curvature.
/// If a step fails (no sufficient decrease), the plain local/global step is taken: the iteration
/// stays monotone.
///
/// Inexact Newton [Eisenstat & Walker 1996]: CG stops when ‖r‖_P⁻¹ ≤ η ‖g‖_P⁻¹ with
/// η = min(½, √(‖g‖_P⁻¹ / ‖g₀‖_P⁻¹)), g₀ the first gradient after Reset(): loose far from the
/// minimum, tighter near it (superlinear convergence), and never more than `max_cg_iterations`.
/// A CG iteration costs one Hessian product (two passes over the rotation coupling, one
/// product with A_ff) and one solve with the factored matrix: about one local/global iteration.
class NewtonCgStep {
 public:
  /// Sizes the buffers for a level (`num_vertices` rows, `num_free` free ones) and forgets g₀
  /// (and the trust radius). `exact_hessian`: the exact, indefinite Hessian in a trust region
  /// instead of the projected one with a line search (see the class comment).
  void Reset(Index num_vertices, Index num_free, bool exact_hessian = true);

  struct Outcome {
    bool newton = false;    ///< false: the plain local/global step was taken.
    int cg_iterations = 0;  ///< CG iterations of this step (Hessian products).
    double energy = 0.0;    ///< E(u⁺, R(u⁺)) of the new state.
    /// max_i ‖z_i‖² of the plain local/global step z = A_ff⁻¹ rhs − u_f (the convergence test's
    /// displacement, before scaling by the diagonal).
    double plain_step_displacement = 0.0;
  };

  /// One step from `positions` (rotations fitted to them, energy `energy`). `reduced_rhs` is the
  /// global step's B_f(R) − A_fc U_c for these rotations and `global_step` its solution A_ff⁻¹ ·
  /// reduced_rhs (the plain local/global step's free positions). Writes the new positions and
  /// fitted rotations in place.
  Outcome Step(const Energy& energy_function, const ConstrainedSystem& system, LinearSolver& solver,
               int max_cg_iterations, Positions& positions, Rotations& rotations, double energy,
               const Eigen::MatrixXd& reduced_rhs, const Eigen::MatrixXd& global_step,
               const Context& context);

 private:
  /// What the CG iterations on H d = r₀ found (d in step_).
  struct CgSearch {
    double slope = 0.0;        ///< ⟨r₀, d⟩: the slope of E/2 along d is −slope
    double dd = 0.0;           ///< ‖d‖² in the P-norm
    bool on_boundary = false;  ///< trust region: d ends on its boundary
  };
  /// Preconditioned CG from d = 0 on H d = r₀ (r₀ in residual_, z₀ = P⁻¹ r₀ in
  /// preconditioned_, ⟨r₀, z₀⟩ = initial_rz): Steihaug–Toint in the trust region with the exact
  /// Hessian; stops when ‖r‖_P⁻¹ ≤ tolerance or after max_cg_iterations (counted in
  /// cg_iterations).
  CgSearch NewtonDirection(const Energy& energy_function, const ConstrainedSystem& system,
                           LinearSolver& solver, const Rotations& rotations, int max_cg_iterations,
                           double initial_rz, double tolerance, int& cg_iterations,
                           const Context& context);
  /// hp = H p on the free vertices (P's half: the factor 2 of E's derivatives is left out of
  /// both H and P, which leaves P⁻¹H unchanged).
  void HessianProduct(const Energy& energy_function, const ConstrainedSystem& system,
                      const Rotations& rotations, const Eigen::MatrixXd& p, Eigen::MatrixXd& hp,
                      const Context& context);

  double first_gradient_norm_ = 0.0;  ///< ‖g₀‖_P⁻¹ (0: not yet seen)
  bool exact_ = false;
  double radius_ = 0.0;  ///< trust radius in the P-norm (exact Hessian; 0: not yet set)
  std::vector<Eigen::Matrix3d> curvature_;
  Rotations d_rotations_;
  Positions direction_full_, rhs_full_, trial_positions_;
  Eigen::MatrixXd free_, step_, residual_, preconditioned_, search_, hessian_search_,
      rotation_term_, step_hessian_;
};

}  // namespace harap
