// SPDX-License-Identifier: MIT
#include "solvers/optimizers/admm_elements.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "framework/error.h"
#include "framework/rotation.h"
#include "solvers/optimizers/coarse_constraints.h"
#include "solvers/optimizers/local_global_solver.h"
#include "solvers/optimizers/small_svd.h"

namespace harap {
namespace {

// The degeneracy tests of energy `elements` (energies/kernels/cotangent_weights.h): a simplex
// whose |6·volume| (|2·area|) is below this fraction of its longest edge cubed (squared) has zero
// weight. Repeated here because optimizers do not depend on energies; the level-0 comparison of
// the Laplacians (AdmmLevelSolver's constructor) catches any disagreement.
constexpr double kDegenerateRatio = 1e-12;

/// The closest rotation to f (planar meshes: a rotation of the plane).
Eigen::Matrix3d ClosestElementRotation(const Eigen::Matrix3d& f, bool planar) {
  if (planar) return NearestPlanarRotation(f);
  return ClosestRotationFromSvd(f, ComputeSignedRightSvd(f));
}

/// The symmetric stretch S = V Σ Vᵀ of F = R S.
Eigen::Matrix3d Stretch(const SignedRightSvd& svd) {
  return svd.v * svd.sigma.asDiagonal() * svd.v.transpose();
}

template <class Body>
void ForElements(Index count, const Context& context, Body&& body) {
  context.Run([&] {
    tbb::parallel_for(tbb::blocked_range<Index>(0, count, 256),
                      [&](const tbb::blocked_range<Index>& range) {
                        for (Index t = range.begin(); t < range.end(); ++t) body(t);
                      });
  });
}

/// Σ of body(t) over elements, and the number of elements for which it flagged an inversion.
/// A deterministic reduction: the same input and thread count give bit-identical energies.
template <class Body>
std::pair<double, Index> SumOverElements(Index count, const Context& context, Body&& body) {
  using Sum = std::pair<double, Index>;
  return context.Run([&] {
    return tbb::parallel_deterministic_reduce(
        tbb::blocked_range<Index>(0, count, 256), Sum{0.0, 0},
        [&](const tbb::blocked_range<Index>& range, Sum sum) {
          for (Index t = range.begin(); t < range.end(); ++t) {
            bool inverted = false;
            sum.first += body(t, inverted);
            sum.second += inverted ? 1 : 0;
          }
          return sum;
        },
        [](const Sum& a, const Sum& b) {
          return Sum{a.first + b.first, a.second + b.second};
        });
  });
}

double FrobeniusDot(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a.array() * b.array()).sum();
}

}  // namespace

AdmmOptions ReadAdmmOptions(OptionReader node, AdmmVariant variant) {
  AdmmOptions options;
  options.variant = variant;
  options.beta =
      node.Get("beta", options.beta,
               "ADMM weights w_t² = beta·vol_t (in WRAPD's units, energy ½ vol ‖F − R‖²)",
               Range::Above(0.0));
  options.tolerance = node.Get("tolerance", options.tolerance,
                               "stop when the relative energy change stays below this for "
                               "`patience` iterations and no element is inverted (0: never)",
                               Range::AtLeast(0.0));
  options.patience =
      node.Get("patience", options.patience, "consecutive iterations the tolerance test must hold",
               Range::AtLeast(1));
  options.max_iterations = node.Get("max_iterations", options.max_iterations,
                                    "cap on ADMM iterations (per level)", Range::AtLeast(1));
  if (variant == AdmmVariant::kRotationAware) {
    options.lbfgs_iterations = node.Get("lbfgs_iterations", options.lbfgs_iterations,
                                        "L-BFGS iterations per global step", Range::AtLeast(1));
    options.lbfgs_history =
        node.Get("lbfgs_history", options.lbfgs_history,
                 "L-BFGS (s, y) pairs kept within a global step", Range::AtLeast(1));
  }
  return options;
}

std::unique_ptr<LevelSolver> AdmmLevelSolver::CreateAnother() const {
  return std::make_unique<AdmmLevelSolver>(options_);
}

void AdmmLevelSolver::ElementOperators(const Mesh& mesh, bool drop_misoriented,
                                       const Context& context) {
  const bool tetrahedra = mesh.kind() == ElementKind::kTetrahedron;
  const Index num_elements = mesh.num_elements();
  const double beta = options_.beta;
  gradients_.assign(num_elements, Eigen::Matrix<double, 4, 3>::Zero());
  volume_.assign(num_elements, 0.0);
  weight_.assign(num_elements, 0.0);
  std::vector<double> signed_volume(num_elements, 0.0);
  ForElements(num_elements, context, [&](Index t) {
    const int k = simplex_size_;
    Eigen::Matrix3d edges = Eigen::Matrix3d::Identity();  // columns v_a − v_0
    double longest = 0.0;
    for (int a = 0; a < k; ++a) {
      for (int b = a + 1; b < k; ++b) {
        longest = std::max(
            longest,
            (mesh.vertices.row(elements_(t, a)) - mesh.vertices.row(elements_(t, b))).norm());
      }
    }
    for (int a = 1; a < k; ++a) {
      edges.col(a - 1) =
          (mesh.vertices.row(elements_(t, a)) - mesh.vertices.row(elements_(t, 0))).transpose();
    }
    if (!tetrahedra) edges.col(2) = Eigen::Vector3d::UnitZ();  // planar: z column of identity
    const double determinant = edges.determinant();            // 6·vol or 2·area, signed
    const double scale = tetrahedra ? longest * longest * longest : longest * longest;
    if (!(std::abs(determinant) >= kDegenerateRatio * scale) || scale == 0.0) return;
    signed_volume[t] = determinant / (tetrahedra ? 6.0 : 2.0);
    // Rows of edges⁻¹ are ∇φ_1..∇φ_{k−1}; ∇φ_0 = −Σ of them, so F = Σ_a x_a ∇φ_aᵀ.
    const Eigen::Matrix3d inverse = edges.inverse();
    Eigen::Matrix<double, 4, 3>& g = gradients_[t];
    g.setZero();
    for (int a = 1; a < k; ++a) {
      g.row(a) = inverse.row(a - 1);
      if (!tetrahedra) g(a, 2) = 0.0;
      g.row(0) -= g.row(a);
    }
  });
  // Misoriented elements: signed volume against the (volume-weighted) majority orientation.
  double orientation = 0.0;
  for (Index t = 0; t < num_elements; ++t) orientation += signed_volume[t];
  const double majority = orientation >= 0.0 ? 1.0 : -1.0;
  for (Index t = 0; t < num_elements; ++t) {
    if (signed_volume[t] == 0.0) continue;
    if (drop_misoriented && signed_volume[t] * majority < 0.0) {
      ++dropped_;
      gradients_[t].setZero();
      continue;
    }
    volume_[t] = std::abs(signed_volume[t]);
    weight_[t] = beta * volume_[t];
  }
}

void AdmmLevelSolver::AssembleA0() {
  const Index num_elements = elements_.rows();
  const Index num_vertices = mesh_->num_vertices();
  // Vertex → (element, corner) incidence, for the allocation-free parallel gathers.
  incidence_start_.assign(num_vertices + 1, 0);
  for (Index t = 0; t < num_elements; ++t) {
    for (int a = 0; a < simplex_size_; ++a) ++incidence_start_[elements_(t, a) + 1];
  }
  for (Index v = 0; v < num_vertices; ++v) incidence_start_[v + 1] += incidence_start_[v];
  incidence_.resize(incidence_start_[num_vertices]);
  {
    std::vector<Index> next(incidence_start_.begin(), incidence_start_.end() - 1);
    for (Index t = 0; t < num_elements; ++t) {
      for (int a = 0; a < simplex_size_; ++a) incidence_[next[elements_(t, a)]++] = {t, a};
    }
  }

  // A₀ = Σ_t w_t² D_tᵀ D_t: entry (i, j) of element t is w_t² ∇φ_a·∇φ_b.
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(static_cast<size_t>(num_elements) * simplex_size_ * simplex_size_);
  for (Index t = 0; t < num_elements; ++t) {
    if (volume_[t] == 0.0) continue;
    for (int a = 0; a < simplex_size_; ++a) {
      for (int b = 0; b < simplex_size_; ++b) {
        triplets.emplace_back(elements_(t, a), elements_(t, b),
                              weight_[t] * gradients_[t].row(a).dot(gradients_[t].row(b)));
      }
    }
  }
  a0_.resize(num_vertices, num_vertices);
  a0_.setFromTriplets(triplets.begin(), triplets.end());
}

namespace {

constexpr std::string_view kAdmmNoSessions =
    "the ADMM level solvers eliminate their constrained vertices once; they do not support "
    "handle edits (interactive sessions): use local_global";
constexpr std::string_view kAdmmNeedsElements =
    "the ADMM optimizers minimize the per-element ARAP energy: use energy `elements` (the "
    "configured energy has a different global-step matrix or rotation sites)";

}  // namespace

void AdmmLevelSolver::CheckCompatible(const Energy& energy, bool handle_edits) const {
  if (handle_edits) throw ConfigError(std::string(kAdmmNoSessions));
  if (energy.rotation_site() != RotationSite::kElement) {
    throw ConfigError(std::string(kAdmmNeedsElements));
  }
}

void AdmmLevelSolver::Precompute(const LevelSetup& setup, const ComponentFactory& factory,
                                 const Context& context) {
  if (setup.handle_edits) throw ConfigError(std::string(kAdmmNoSessions));
  if (setup.stiffness != nullptr && !setup.stiffness->empty()) {
    throw ConfigError(
        "the ADMM level solvers take no stiffness (their splitting weighs every element alike): "
        "use local_global");
  }
  const Mesh& mesh = *setup.mesh;
  const int level = setup.level;
  // Only the input level needs the factory's energy (final energy and measures); coarse levels
  // drop their inverted elements (Section 7: "filtering all inverted elements").
  const bool with_energy = setup.input_mesh == nullptr;
  const bool drop_misoriented = setup.input_mesh != nullptr;
  const double beta = options_.beta;
  mesh_ = &mesh;
  level_ = level;
  planar_ = mesh.planar;
  simplex_size_ = mesh.simplex_size();
  elements_ = mesh.elements;
  Stopwatch clock;
  context.ReportPhase(fmt::format("precomputing level {}", level));
  const bool tetrahedra = mesh.kind() == ElementKind::kTetrahedron;
  if (!tetrahedra && !mesh.planar) {
    throw InputError(
        "the ADMM optimizers work on tetrahedral or planar triangle meshes (energy "
        "`elements`); this mesh is a surface");
  }
  const Index num_elements = mesh.num_elements();
  const Index num_vertices = mesh.num_vertices();
  ElementOperators(mesh, drop_misoriented, context);
  AssembleA0();
  const SparseMatrix& a0 = a0_;

  if (with_energy) {
    energy_ = factory.MakeEnergy();
    energy_->Precompute(mesh, context);
    const SparseMatrix& laplacian = energy_->system_matrix();
    const double reference = laplacian.norm();
    const bool same_shape = energy_->rotation_site() == RotationSite::kElement &&
                            energy_->num_rotations() == num_elements &&
                            laplacian.rows() == num_vertices;
    if (!same_shape || (laplacian - a0 / beta).norm() > 1e-8 * reference) {
      throw ConfigError(std::string(kAdmmNeedsElements));
    }
  }
  f_.assign(num_elements, Eigen::Matrix3d::Zero());
  z_ = f_;
  dual_ = f_;
  target_ = f_;
  goal_ = f_;
  if (!planar_)
    svd_.assign(num_elements, SignedRightSvd{Eigen::Matrix3d::Identity(), {1.0, 1.0, 1.0}});
  rhs_.resize(num_vertices, 3);
  precompute_seconds_ = clock.Seconds();
}

ConstrainSummary AdmmLevelSolver::Constrain(const LevelConstraints& constraints,
                                            const ComponentFactory& factory,
                                            const Context& context) {
  Stopwatch clock;
  if (!constraints.soft.empty()) {
    throw InputError(
        "soft handles (a handle with a `weight`) need the local/global level solver "
        "(optimizer classic or hierarchical with inner = \"local_global\"); ADMM pins its "
        "handles");
  }
  context.ReportPhase(fmt::format("factoring level {}", level_));
  const Index num_vertices = a0_.rows();
  for (Index v : constraints.vertices) {
    HARAP_CHECK(v >= 0 && v < num_vertices, "constrained vertex {} out of range", v);
  }
  HARAP_CHECK(static_cast<Index>(constraints.vertices.size()) == constraints.mean_target.rows(),
              "{} constrained vertices but {} targets", constraints.vertices.size(),
              constraints.mean_target.rows());
  constraints_ = constraints;
  if (constraints_.targets_follow_rotations()) FindIncidentElements(*mesh_, constraints_);
  system_ = std::make_unique<ConstrainedSystem>(a0_, constraints_.vertices);
  const ConstrainSummary summary = FactorGlobalStep(*system_, level_, factory, context, clock,
                                                    solver_, reduced_rhs_, reduced_x_);
  constrain_seconds_ = summary.seconds;
  return summary;
}

void AdmmLevelSolver::MoveTargets(const Positions& mean_target) {
  MoveMeanTargets(constraints_, mean_target);
}

LevelSolveResult AdmmLevelSolver::Solve(LevelState& state, const LevelSolveRequest& request,
                                        const Context& context) {
  if (request.global_step_only) {
    throw InputError("the ADMM level solvers have no rotation-driven global step (a preview)");
  }
  AdmmOptions options = options_;
  options.tolerance = request.Tolerance(options.tolerance);
  if (request.max_iterations > 0) options.max_iterations = request.max_iterations;
  // The targets are placed once (ADMM keeps no rotations to follow).
  const bool have_rotations = state.rotations.size() == f_.size();
  PlaceConstrainedVertices(constraints_, RotationSite::kElement,
                           have_rotations ? &state.rotations : nullptr, state.positions);
  const RunResult run = Run(state.positions, options, context);
  LevelSolveResult result;
  result.iterations = run.iterations;
  result.energy = run.energy;
  result.converged = run.converged;
  result.stopped_by_callback = run.stopped_by_callback;
  result.linear_solves = run.linear_solves;
  result.measures["inverted_elements"] = static_cast<double>(run.inverted_elements);
  if (energy_ != nullptr) {
    // The input level: the report's energy, by the factory's energy.
    result.energy = FitRotations(state, context);
    if (run.inverted_elements > 0) {
      result.notes.push_back(
          fmt::format("{} elements are inverted (det F < 0) at the end", run.inverted_elements));
    }
  } else {
    // The up-sampler's input: rotations of the elements' polar decompositions.
    state.rotations = ElementRotations(state.positions, context);
  }
  if (dropped_ > 0) {
    result.notes.push_back(fmt::format("level {}: {} inverted elements dropped", level_, dropped_));
  }
  return result;
}

Eigen::Matrix3d AdmmLevelSolver::DeformationGradient(const Positions& u, Index t) const {
  Eigen::Matrix3d f = Eigen::Matrix3d::Zero();
  for (int a = 0; a < simplex_size_; ++a) {
    f.noalias() += u.row(elements_(t, a)).transpose() * gradients_[t].row(a);
  }
  if (planar_) f(2, 2) = 1.0;  // the z direction stays rigid (rotations of the plane)
  return f;
}

void AdmmLevelSolver::DeformationGradients(const Positions& u, const Context& context) {
  ForElements(static_cast<Index>(f_.size()), context,
              [&](Index t) { f_[t] = DeformationGradient(u, t); });
}

void AdmmLevelSolver::Gather(const std::vector<Eigen::Matrix3d>& m, Positions& out,
                             const Context& context) const {
  const Index num_vertices = static_cast<Index>(incidence_start_.size()) - 1;
  context.Run([&] {
    tbb::parallel_for(tbb::blocked_range<Index>(0, num_vertices, 512),
                      [&](const tbb::blocked_range<Index>& range) {
                        for (Index v = range.begin(); v < range.end(); ++v) {
                          Eigen::RowVector3d sum = Eigen::RowVector3d::Zero();
                          for (Index k = incidence_start_[v]; k < incidence_start_[v + 1]; ++k) {
                            const auto [t, a] = incidence_[k];
                            if (weight_[t] == 0.0) continue;
                            sum.noalias() +=
                                weight_[t] * (m[t] * gradients_[t].row(a).transpose()).transpose();
                          }
                          out.row(v) = sum;
                        }
                      });
  });
}

void AdmmLevelSolver::SolveA0(const Eigen::MatrixXd& rhs_f, Eigen::MatrixXd& x_f,
                              SolveStatistics& statistics, const Context& context) {
  const SolveSummary summary = solver_->Solve(rhs_f, x_f, context);
  statistics.Add(summary);
  if (!summary.success()) {
    throw NumericalError(
        fmt::format("linear solve failed on level {}: {}", level_, summary.message));
  }
}

double AdmmLevelSolver::Evaluate(const Positions& u, Index& inverted,
                                 const Context& context) const {
  const auto [energy, count] =
      SumOverElements(static_cast<Index>(f_.size()), context, [&](Index t, bool& is_inverted) {
        if (volume_[t] == 0.0) return 0.0;
        const Eigen::Matrix3d f = DeformationGradient(u, t);
        if (planar_) {
          is_inverted = f.determinant() < 0.0;
          return volume_[t] * (f - NearestPlanarRotation(f)).squaredNorm();
        }
        // ‖F − R‖² = Σ (σ_i − 1)² with σ₃ signed (small_svd.h).
        const SignedRightSvd svd = ComputeSignedRightSvd(f);
        is_inverted = svd.sigma(2) < 0.0;
        return volume_[t] * (svd.sigma.array() - 1.0).square().sum();
      });
  inverted = count;
  return energy;
}

Rotations AdmmLevelSolver::ElementRotations(const Positions& u, const Context& context) const {
  Rotations rotations(f_.size(), Rotation::Identity());
  ForElements(static_cast<Index>(f_.size()), context, [&](Index t) {
    if (volume_[t] == 0.0) return;
    rotations[t] = ClosestElementRotation(DeformationGradient(u, t), planar_);
  });
  return rotations;
}

double AdmmLevelSolver::FitRotations(LevelState& state, const Context& context) {
  HARAP_CHECK(energy_ != nullptr, "AdmmLevelSolver::FitRotations on a coarse level");
  state.rotations = ElementRotations(state.positions, context);
  return energy_->FitRotations(state.positions, state.rotations, context);
}

std::map<std::string, double> AdmmLevelSolver::AuxiliaryMeasures(const LevelState& state,
                                                                 const Context& context) const {
  HARAP_CHECK(energy_ != nullptr, "AdmmLevelSolver::AuxiliaryMeasures on a coarse level");
  return energy_->AuxiliaryMeasures(state.positions, state.rotations, context);
}

void AdmmLevelSolver::Decompose(const Positions& u, const Context& context) {
  const auto [energy, inverted] =
      SumOverElements(static_cast<Index>(f_.size()), context, [&](Index t, bool& is_inverted) {
        if (weight_[t] == 0.0) return 0.0;
        f_[t] = DeformationGradient(u, t);
        svd_[t] = ComputeSignedRightSvd(f_[t], svd_[t].v);  // warm: the last decomposition
        is_inverted = svd_[t].sigma(2) < 0.0;
        return volume_[t] * (svd_[t].sigma.array() - 1.0).square().sum();  // ‖F − R‖², small_svd.h
      });
  decomposed_energy_ = energy;
  decomposed_inverted_ = inverted;
}

double AdmmLevelSolver::WrapdObjective(const std::vector<Eigen::Matrix3d>& p,
                                       Eigen::MatrixXd& gradient_f, const Context& context) {
  // For F = U Σ Vᵀ (signed), S = V Σ Vᵀ and P symmetric: ½‖S − P‖² = ½‖F‖² − ⟨S, P⟩ + ½‖P‖², and
  // d⟨S, P⟩ = ⟨U Σ K Vᵀ, dF⟩ with Q = Vᵀ P V, K_ij = (Q_ij + Q_ji) / (σ_i + σ_j) (from
  // differentiating S² = FᵀF in the V basis). So ∂/∂F = F − U Σ K Vᵀ = F (I − V K Vᵀ), as
  // U Σ = F V; target_ holds it.
  const auto [objective, unused] =
      SumOverElements(static_cast<Index>(f_.size()), context, [&](Index t, bool&) {
        if (weight_[t] == 0.0) {
          target_[t].setZero();
          return 0.0;
        }
        const Eigen::Matrix3d& f = f_[t];
        const SignedRightSvd& svd = svd_[t];
        const Eigen::Matrix3d q = svd.v.transpose() * p[t] * svd.v;
        Eigen::Matrix3d k;
        for (int i = 0; i < 3; ++i) {
          for (int j = 0; j < 3; ++j) {
            double denominator = svd.sigma(i) + svd.sigma(j);
            // σ_i + σ_j = 0 only for a collapsed element, where S is not differentiable; the
            // clamp keeps the gradient finite (a subgradient-like choice).
            const double floor = 1e-12 * std::max(1.0, std::abs(svd.sigma(0)));
            if (std::abs(denominator) < floor) denominator = denominator < 0.0 ? -floor : floor;
            k(i, j) = (q(i, j) + q(j, i)) / denominator;
          }
        }
        target_[t] = f - (f * svd.v) * k * svd.v.transpose();
        return 0.5 * weight_[t] * (Stretch(svd) - p[t]).squaredNorm();
      });
  Gather(target_, rhs_, context);
  // Only the free rows: the gradient with respect to the unknowns.
  const auto& free = system_->free_vertices();
  for (size_t r = 0; r < free.size(); ++r)
    gradient_f.row(static_cast<Index>(r)) = rhs_.row(free[r]);
  return objective;
}

void AdmmLevelSolver::WrapdGlobalStep(Positions& u, const AdmmOptions& options,
                                      SolveStatistics& statistics, const Context& context) {
  // Quasi-Newton on Σ_t ½ w_t² ‖S_t(x) − (Z_t − U_t)‖² over the free positions, with
  // H₀ = A₀⁻¹ (the Hessian of the same objective with F_t in place of S_t): L-BFGS two-loop
  // recursion, Armijo backtracking from the full step.
  const int history = options.lbfgs_history;
  const Index n = system_->num_free();
  if (static_cast<int>(lbfgs_s_.size()) != history || (history > 0 && lbfgs_s_[0].rows() != n)) {
    lbfgs_s_.assign(history, Eigen::MatrixXd(n, 3));
    lbfgs_y_.assign(history, Eigen::MatrixXd(n, 3));
    lbfgs_rho_.assign(history, 0.0);
    lbfgs_alpha_.assign(history, 0.0);
  }
  gradient_f_.resize(n, 3);
  trial_gradient_f_.resize(n, 3);
  direction_f_.resize(n, 3);
  x_f_.resize(n, 3);
  trial_x_f_.resize(n, 3);
  trial_u_ = u;
  ForElements(static_cast<Index>(goal_.size()), context,
              [&](Index t) { goal_[t] = z_[t] - dual_[t]; });
  const std::vector<Eigen::Matrix3d>& p = goal_;

  // The decomposition (f_, svd_) is that of u on entry (Run keeps it so) and of the last
  // evaluated point during the line search.
  system_->GatherFree(u, x_f_);
  double objective = WrapdObjective(p, gradient_f_, context);
  bool decomposition_is_current = true;
  int stored = 0, newest = -1;
  for (int iteration = 0; iteration < options.lbfgs_iterations; ++iteration) {
    // Two-loop recursion: direction = −H g.
    direction_f_ = gradient_f_;
    for (int k = 0; k < stored; ++k) {
      const int i = (newest - k + history) % history;
      lbfgs_alpha_[i] = lbfgs_rho_[i] * FrobeniusDot(lbfgs_s_[i], direction_f_);
      direction_f_ -= lbfgs_alpha_[i] * lbfgs_y_[i];
    }
    trial_gradient_f_.setZero();  // the warm start of iterative solvers
    SolveA0(direction_f_, trial_gradient_f_, statistics, context);  // r = H₀ q
    direction_f_ = trial_gradient_f_;
    for (int k = stored - 1; k >= 0; --k) {
      const int i = (newest - k + history) % history;
      const double b = lbfgs_rho_[i] * FrobeniusDot(lbfgs_y_[i], direction_f_);
      direction_f_ += (lbfgs_alpha_[i] - b) * lbfgs_s_[i];
    }
    direction_f_ = -direction_f_;
    const double slope = FrobeniusDot(gradient_f_, direction_f_);
    if (!(slope < 0.0)) break;  // no descent direction left (converged to round-off)
    double step = 1.0, trial = 0.0;
    bool accepted = false;
    for (int halving = 0; halving < 30; ++halving) {
      trial_x_f_ = x_f_ + step * direction_f_;
      system_->ScatterFree(trial_x_f_, trial_u_);
      Decompose(trial_u_, context);
      decomposition_is_current = false;
      trial = WrapdObjective(p, trial_gradient_f_, context);
      if (std::isfinite(trial) && trial <= objective + 1e-4 * step * slope) {
        accepted = true;
        break;
      }
      step *= 0.5;
    }
    if (!accepted) break;
    newest = (newest + 1) % history;
    lbfgs_s_[newest] = trial_x_f_ - x_f_;
    lbfgs_y_[newest] = trial_gradient_f_ - gradient_f_;
    const double curvature = FrobeniusDot(lbfgs_s_[newest], lbfgs_y_[newest]);
    if (curvature > 1e-300) {
      lbfgs_rho_[newest] = 1.0 / curvature;
      stored = std::min(stored + 1, history);
    } else {
      newest = (newest - 1 + history) % history;  // drop a pair without positive curvature
    }
    const double decrease = objective - trial;
    decomposition_is_current = true;
    x_f_ = trial_x_f_;
    gradient_f_ = trial_gradient_f_;
    objective = trial;
    if (decrease <= 1e-14 * std::max(objective, 1e-300)) break;
  }
  system_->ScatterFree(x_f_, u);
  if (!decomposition_is_current) Decompose(u, context);  // a rejected trial was decomposed last
}

AdmmLevelSolver::RunResult AdmmLevelSolver::Run(Positions& u, const AdmmOptions& options,
                                                const Context& context) {
  HARAP_CHECK(u.rows() == system_->num_vertices(), "{} positions for {} vertices", u.rows(),
              system_->num_vertices());
  const bool rotation_aware = options.variant == AdmmVariant::kRotationAware;
  if (rotation_aware && planar_) {
    throw InputError("wrapd works on tetrahedral meshes; use admm_pd for planar meshes");
  }
  system_->SetFixedPositions(u);
  RunResult result;
  const Index num_elements = static_cast<Index>(f_.size());
  const double beta = options.beta;
  double energy = Evaluate(u, result.inverted_elements, context);
  if (system_->num_free() == 0) {
    result.energy = energy;
    result.converged = true;
    return result;
  }
  // Initialization [Overby et al. 2017; Brown & Narain 2021]: Z = D x (or its stretch S), U = 0.
  // wrapd keeps f_ and svd_ of the current positions from one iteration to the next (Decompose,
  // then the global step's line search), so each iteration decomposes every element only once per
  // line-search evaluation.
  if (rotation_aware) {
    Decompose(u, context);
  } else {
    DeformationGradients(u, context);
  }
  ForElements(num_elements, context, [&](Index t) {
    z_[t] = rotation_aware ? Stretch(svd_[t]) : f_[t];
    dual_[t].setZero();
  });
  int quiet_iterations = 0;
  while (result.iterations < options.max_iterations) {
    // Local step: the proximal map of the ARAP term (½ vol ‖·‖² in WRAPD's units, weight
    // w² = β vol), in closed form, then the dual update U += D x − Z.
    //   admm_pd: Z = argmin ½ vol dist(Z, SO(3))² + ½ w² ‖Z − (F + U)‖² = (R + β y) / (1 + β),
    //            y = F + U, R = polar(y) (for fixed R the minimizer in Z is that blend, and the
    //            best R for it is the closest rotation to y);
    //   wrapd:   Z = argmin ½ vol ‖Z − I‖² + ½ w² ‖Z − (S + U)‖² = (I + β y) / (1 + β), y = S + U,
    //            since ‖F − R‖ = ‖S − I‖ for F = R S.
    ForElements(num_elements, context, [&](Index t) {
      if (weight_[t] == 0.0) return;
      const Eigen::Matrix3d current = rotation_aware ? Stretch(svd_[t]) : f_[t];
      const Eigen::Matrix3d y = current + dual_[t];
      const Eigen::Matrix3d anchor =
          rotation_aware ? Eigen::Matrix3d::Identity() : ClosestElementRotation(y, planar_);
      z_[t] = (anchor + beta * y) / (1.0 + beta);
      dual_[t] += current - z_[t];
    });
    // Global step.
    if (rotation_aware) {
      WrapdGlobalStep(u, options, result.linear_solves, context);
    } else {
      // argmin_x Σ_t ½ w_t² ‖D_t x − (Z_t − U_t)‖²: A₀ x = Σ_t w_t² D_tᵀ (Z_t − U_t).
      ForElements(num_elements, context, [&](Index t) { target_[t] = z_[t] - dual_[t]; });
      Gather(target_, rhs_, context);
      system_->ReducedRhs(rhs_, reduced_rhs_);
      if (!solver_->is_direct()) system_->GatherFree(u, reduced_x_);
      SolveA0(reduced_rhs_, reduced_x_, result.linear_solves, context);
      system_->ScatterFree(reduced_x_, u);
    }
    const double previous = energy;
    if (rotation_aware) {
      energy = decomposed_energy_;  // the decomposition is of the new u (WrapdGlobalStep)
      result.inverted_elements = decomposed_inverted_;
    } else {
      DeformationGradients(u, context);
      energy = Evaluate(u, result.inverted_elements, context);
    }
    ++result.iterations;
    if (!std::isfinite(energy)) {
      throw NumericalError(fmt::format("the energy became {} on level {} at ADMM iteration {}",
                                       energy, level_, result.iterations));
    }
    if (context.iteration_callback) {
      IterationSummary summary{level_, result.iterations, energy, 0.0, context.run_clock.Seconds()};
      summary.inverted_elements = result.inverted_elements;
      if (context.iteration_callback(summary) == CallbackAction::kStop) {
        result.stopped_by_callback = true;
        break;
      }
    }
    const double change = std::abs(previous - energy) / std::max(previous, 1e-300);
    quiet_iterations = change < options.tolerance ? quiet_iterations + 1 : 0;
    if (quiet_iterations >= options.patience && result.inverted_elements == 0) {
      result.converged = true;
      break;
    }
  }
  result.energy = energy;
  return result;
}

}  // namespace harap
