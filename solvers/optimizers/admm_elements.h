// SPDX-License-Identifier: MIT
#pragma once

#include <Eigen/Dense>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "framework/config.h"
#include "framework/constrained_system.h"
#include "framework/level_solver.h"
#include "framework/optimizer.h"
#include "solvers/optimizers/small_svd.h"

namespace harap {

/// Which ADMM splitting of the per-element ARAP energy a level runs.
enum class AdmmVariant {
  /// `admm_pd` [Overby et al. 2017, "ADMM ⊇ Projective Dynamics"]: Z_t ≈ F_t(x), rotation-unaware.
  kProjectiveDynamics,
  /// `wrapd` [Brown & Narain 2021], ARAP mode: Z_t ≈ S_t(x) = sym(polar(F_t(x))), rotation-aware.
  kRotationAware,
};

/// Options of the ADMM iteration on one level (shared by `admm_pd`, `wrapd` and `hierarchical`
/// with `inner = admm_pd | wrapd`).
struct AdmmOptions {
  AdmmVariant variant = AdmmVariant::kProjectiveDynamics;
  /// ADMM weights w_t² = beta · vol_t in WRAPD's units (energy ½ vol_t ‖F_t − R_t‖²). With 1 the
  /// proximal step is the midpoint of the rotation and the current value (WRAPD's ARAP default).
  double beta = 1.0;
  /// Stop when |E_{k−1} − E_k| / E_{k−1} stays below this for `patience` consecutive iterations
  /// and no element is inverted (WRAPD's test; E the per-element ARAP energy of the iterate).
  /// 0 runs to max_iterations.
  double tolerance = 1e-8;
  int patience = 3;
  int max_iterations = 1000;
  /// wrapd: L-BFGS iterations per global step and the number of (s, y) pairs kept.
  int lbfgs_iterations = 10;
  int lbfgs_history = 6;
};

/// Reads the ADMM options from an optimizer's config table (the L-BFGS keys for wrapd only).
AdmmOptions ReadAdmmOptions(OptionReader node, AdmmVariant variant);

/// The ADMM machinery of one mesh level for the per-element ARAP energy (energy `elements`,
/// E = Σ_t vol_t ‖F_t − R_t‖²_F on tetrahedra or planar triangles): per-element
/// deformation-gradient operators F_t = Σ_a x_a g_{t,a}ᵀ (g the gradients of the barycentric
/// coordinates at rest), weights, the prefactored weighted Laplacian A₀ = Σ_t w_t² D_tᵀ D_t on the
/// free vertices (the factory's LinearSolver, constrained vertices eliminated by
/// ConstrainedSystem), the ADMM iteration itself and inverted-element counting.
///
/// Precompute() is the P phase (operators, weights, A₀), Constrain() the C phase (elimination
/// and factorization). Degenerate rest elements get weight 0, exactly as in `elements`. On
/// coarse levels (coarse hierarchy levels, whose clustered elements can be turned inside out
/// relative to the input mesh) elements whose signed rest volume has the opposite sign of the
/// majority are dropped too: the paper's "filtering all inverted elements from the levels of the
/// hierarchy ... extending the definition of degenerated elements to inverted elements".
///
/// On the input level (LevelSetup::input_mesh null) the factory's energy is precomputed as well;
/// its A must be the level's unweighted Laplacian Σ_t vol_t D_tᵀ D_t (so it is the `elements`
/// energy), else ConfigError. The final energy and its auxiliary measures (energy_wrapd) come
/// from it, so the report uses one energy definition for every optimizer.
///
/// As a LevelSolver (registry names `admm_pd` and `wrapd`): the targets are placed once per
/// solve (with the handed-down rotations on coarse levels); Solve() leaves the polar rotations of
/// the elements in the state (the up-sampler's input; Eq. 11 averages them to vertices) and
/// reports "inverted_elements". Handle edits (LevelSetup::handle_edits) are not supported.
class AdmmLevelSolver final : public LevelSolver {
 public:
  explicit AdmmLevelSolver(const AdmmOptions& options) : options_(options) {}

  // LevelSolver.
  std::unique_ptr<LevelSolver> CreateAnother() const override;
  /// Per-element rotations (energy `elements`) and no session; Precompute() checks that the
  /// energy's matrix is A₀ once the mesh is known.
  void CheckCompatible(const Energy& energy, bool handle_edits) const override;
  void Precompute(const LevelSetup& setup, const ComponentFactory& factory,
                  const Context& context) override;
  ConstrainSummary Constrain(const LevelConstraints& constraints, const ComponentFactory& factory,
                             const Context& context) override;
  void MoveTargets(const Positions& mean_target) override;
  /// Run() with the level's options and the request's limits; on the input level the result's
  /// energy is the factory energy's (rotations fitted), as the report gives it.
  LevelSolveResult Solve(LevelState& state, const LevelSolveRequest& request,
                         const Context& context) override;
  /// Element rotations polar(F_t) refined by the factory's energy (input level only).
  double FitRotations(LevelState& state, const Context& context) override;
  std::map<std::string, double> AuxiliaryMeasures(const LevelState& state,
                                                  const Context& context) const override;
  RotationSite rotation_site() const override { return RotationSite::kElement; }
  Index num_unknowns() const override { return system_->num_free(); }
  ConstraintReport constraint_report() const override { return system_->report(); }

  struct RunResult {
    int iterations = 0;
    double energy = 0.0;  ///< Σ_t vol_t ‖F_t − R_t‖² of the final positions (`elements` units).
    bool converged = false;
    bool stopped_by_callback = false;
    Index inverted_elements = 0;  ///< det F_t < 0 at the end.
    SolveStatistics linear_solves;
  };

  /// Runs ADMM from `u` (#V×3; constrained rows already at their targets) and leaves the final
  /// positions in it. Reports every iteration through context.iteration_callback.
  RunResult Run(Positions& u, const AdmmOptions& options, const Context& context);

  /// Per-element rotations R_t = polar(F_t(u)) (identity for elements of weight 0); the input of
  /// the element-rotation up-sampling (Eq. 11 averages them to vertices).
  Rotations ElementRotations(const Positions& u, const Context& context) const;

  /// Σ_t vol_t ‖F_t − R_t‖² of `u` (weight-0 elements left out) and the inverted-element count.
  double Evaluate(const Positions& u, Index& inverted, const Context& context) const;

 private:
  /// The P phase's per-element part: gradients of the barycentric coordinates, rest volumes and
  /// weights (degenerate and, with `drop_misoriented`, misoriented elements get weight 0).
  void ElementOperators(const Mesh& mesh, bool drop_misoriented, const Context& context);
  /// The vertex → (element, corner) incidence and A₀ = Σ_t w_t² D_tᵀ D_t into a0_.
  void AssembleA0();
  /// F_t(u) = Σ_a u_a ∇φ_aᵀ of element t (planar meshes: z row and column of the identity).
  Eigen::Matrix3d DeformationGradient(const Positions& u, Index t) const;
  /// F_t(u) for every element into f_.
  void DeformationGradients(const Positions& u, const Context& context);
  /// out.row(v) = Σ_{(t, a): corner a of t is v} w_t² (m_t g_{t,a})ᵀ: the normal-equation
  /// right-hand side of Σ_t ½ w_t² ‖F_t(x) − m_t‖² for targets m_t, and the gradient of the wrapd
  /// global objective for m_t = its ∂/∂F_t.
  void Gather(const std::vector<Eigen::Matrix3d>& m, Positions& out, const Context& context) const;
  /// One linear solve A₀ x_f = rhs_f (reduced), result in x_f.
  void SolveA0(const Eigen::MatrixXd& rhs_f, Eigen::MatrixXd& x_f, SolveStatistics& statistics,
               const Context& context);
  /// wrapd: F_t(u) and its signed right SVD for every element into f_ and svd_, with the ARAP
  /// energy Σ_t vol_t ‖F_t − R_t‖² and the inverted-element count of u as by-products.
  void Decompose(const Positions& u, const Context& context);
  /// wrapd's global objective Σ_t ½ w_t² ‖S_t(u) − p_t‖² and, into gradient_f (#free×3), its
  /// gradient with respect to the free positions, at the u last passed to Decompose.
  double WrapdObjective(const std::vector<Eigen::Matrix3d>& p, Eigen::MatrixXd& gradient_f,
                        const Context& context);
  /// A few L-BFGS iterations on WrapdObjective from u, A₀ as the initial Hessian.
  void WrapdGlobalStep(Positions& u, const AdmmOptions& options, SolveStatistics& statistics,
                       const Context& context);

  AdmmOptions options_;
  const Mesh* mesh_ = nullptr;  ///< the level's (outlives the solver)
  int level_ = 0;
  bool planar_ = false;
  int simplex_size_ = 3;
  LevelConstraints constraints_;
  SparseMatrix a0_;  ///< A₀ on all vertices (Precompute), eliminated by Constrain
  Elements elements_;
  std::vector<Eigen::Matrix<double, 4, 3>> gradients_;  ///< rows: ∇φ_a at rest (unused rows 0)
  std::vector<double> volume_;          ///< rest volume (area); 0 for degenerate/dropped
  std::vector<double> weight_;          ///< w_t² = beta · vol_t (WRAPD's units)
  std::vector<Index> incidence_start_;  ///< CSR: vertex → (element, corner) pairs
  std::vector<std::pair<Index, int>> incidence_;
  Index dropped_ = 0;
  std::unique_ptr<Energy> energy_;
  std::unique_ptr<ConstrainedSystem> system_;
  std::unique_ptr<LinearSolver> solver_;
  // Per-iteration buffers, allocated once.
  std::vector<Eigen::Matrix3d> f_, z_, dual_, target_, goal_;  ///< goal_ = Z − U
  std::vector<SignedRightSvd> svd_;  ///< wrapd: of f_ (not for planar meshes)
  double decomposed_energy_ = 0.0;   ///< wrapd: energy and inverted count of the decomposed u
  Index decomposed_inverted_ = 0;
  Positions rhs_;
  Eigen::MatrixXd reduced_rhs_, reduced_x_;
  // wrapd's L-BFGS state.
  std::vector<Eigen::MatrixXd> lbfgs_s_, lbfgs_y_;
  std::vector<double> lbfgs_rho_, lbfgs_alpha_;
  Eigen::MatrixXd gradient_f_, trial_gradient_f_, direction_f_, x_f_, trial_x_f_;
  Positions trial_u_;
};

}  // namespace harap
