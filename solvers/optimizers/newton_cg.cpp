// SPDX-License-Identifier: MIT
#include "solvers/optimizers/newton_cg.h"

#include <algorithm>
#include <cmath>

#include "framework/error.h"
#include "solvers/optimizers/block_vectors.h"

namespace harap {
namespace {

/// out = A x for a symmetric A in full column storage: column c of A is row c, so each output row
/// is a gather over one column, in parallel without write conflicts.
void SymmetricProduct(const SparseMatrix& a, const Eigen::MatrixXd& x, Eigen::MatrixXd& out,
                      const Context& context) {
  context.Run([&] {
    tbb::parallel_for(tbb::blocked_range<Index>(0, static_cast<Index>(a.outerSize()), 2048),
                      [&](const tbb::blocked_range<Index>& range) {
                        const Index* outer = a.outerIndexPtr();
                        const Index* inner = a.innerIndexPtr();
                        const double* value = a.valuePtr();
                        for (Index c = range.begin(); c != range.end(); ++c) {
                          double s0 = 0.0, s1 = 0.0, s2 = 0.0;
                          for (Index p = outer[c]; p < outer[c + 1]; ++p) {
                            const Index r = inner[p];
                            s0 += value[p] * x(r, 0);
                            s1 += value[p] * x(r, 1);
                            s2 += value[p] * x(r, 2);
                          }
                          out(c, 0) = s0;
                          out(c, 1) = s1;
                          out(c, 2) = s2;
                        }
                      });
  });
}

// Armijo's sufficient-decrease constant and the backtracking schedule of the line search.
constexpr double kArmijo = 1e-4;
constexpr double kBacktrack = 0.5;
constexpr int kLineSearchTrials = 3;
// The trust region's bookkeeping (Nocedal & Wright, Algorithm 4.1): accept a step whose actual
// decrease is at least this share of the model's, shrink the radius below kShrinkBelow, grow it
// above kGrowAbove when the step reached the boundary.
constexpr double kAcceptAbove = 0.1;
constexpr double kShrinkBelow = 0.25;
constexpr double kGrowAbove = 0.75;
constexpr double kShrinkFactor = 0.25;

}  // namespace

void NewtonCgStep::Reset(Index num_vertices, Index num_free, bool exact_hessian) {
  first_gradient_norm_ = 0.0;
  radius_ = 0.0;
  exact_ = exact_hessian;
  direction_full_.setZero(num_vertices, 3);
  rhs_full_.resize(num_vertices, 3);
  for (Eigen::MatrixXd* buffer : {&free_, &step_, &residual_, &preconditioned_, &search_,
                                  &hessian_search_, &rotation_term_, &step_hessian_}) {
    buffer->resize(num_free, 3);
  }
}

void NewtonCgStep::HessianProduct(const Energy& energy_function, const ConstrainedSystem& system,
                                  const Rotations& rotations, const Eigen::MatrixXd& p,
                                  Eigen::MatrixXd& hp, const Context& context) {
  // Fixed rows of direction_full_ stay 0 (set in Reset): constrained vertices do not move.
  system.ScatterFree(p, direction_full_);
  energy_function.RotationDerivative(direction_full_, rotations, curvature_, d_rotations_, context);
  energy_function.AssembleRhs(d_rotations_, rhs_full_, context);
  system.GatherFree(rhs_full_, rotation_term_);
  SymmetricProduct(system.reduced_matrix(), p, hp, context);
  ForBlockChunks(hp.size(), context, [&](Eigen::Index begin, Eigen::Index length) {
    Chunk(hp.data() + begin, length) -= ConstChunk(rotation_term_.data() + begin, length);
  });
}

NewtonCgStep::CgSearch NewtonCgStep::NewtonDirection(
    const Energy& energy_function, const ConstrainedSystem& system, LinearSolver& solver,
    const Rotations& rotations, int max_cg_iterations, double initial_rz, double tolerance,
    int& cg_iterations, const Context& context) {
  const bool trust_region = exact_;
  step_.setZero();
  if (trust_region) step_hessian_.setZero();
  search_ = preconditioned_;
  double rz = initial_rz;
  // ⟨r₀, d⟩ = Σ α_i ⟨r_i, z_i⟩ for CG from 0 (r_i·p_i = r₀·p_i by conjugacy): the slope of E/2
  // along d is −slope.
  double slope = 0.0;
  // P-norms for the trust region, by the recurrences of preconditioned Steihaug–Toint CG:
  // ‖d‖², ⟨d, p⟩ and ‖p‖² in the metric of P = A_ff.
  double dd = 0.0, dp = 0.0, pp = initial_rz;
  bool on_boundary = false;
  const auto add_to_step = [&](double length, double rz_of_search) {
    ForBlockChunks(step_.size(), context, [&](Eigen::Index begin, Eigen::Index size) {
      Chunk(step_.data() + begin, size) += length * ConstChunk(search_.data() + begin, size);
      if (trust_region) {
        Chunk(step_hessian_.data() + begin, size) +=
            length * ConstChunk(hessian_search_.data() + begin, size);
      }
    });
    slope += length * rz_of_search;
  };
  while (true) {
    HessianProduct(energy_function, system, rotations, search_, hessian_search_, context);
    ++cg_iterations;
    const double curvature = BlockDot(search_, hessian_search_, context);
    const double alpha = curvature > 0.0 ? rz / curvature : 0.0;
    if (trust_region &&
        (!(curvature > 0.0) || dd + 2.0 * alpha * dp + alpha * alpha * pp >= radius_ * radius_)) {
      // Negative curvature or leaving the region: to the boundary along p (Steihaug–Toint).
      const double tau = (-dp + std::sqrt(dp * dp + pp * (radius_ * radius_ - dd))) / pp;
      add_to_step(tau, rz);
      on_boundary = true;
      break;
    }
    if (!(curvature > 0.0)) {
      // Negative curvature (projected model: only from round-off): keep the step so far; on the
      // first iteration take the local/global direction, always a descent direction.
      if (cg_iterations == 1) {
        step_ = preconditioned_;
        slope = initial_rz;
      }
      break;
    }
    add_to_step(alpha, rz);
    ForBlockChunks(residual_.size(), context, [&](Eigen::Index begin, Eigen::Index size) {
      Chunk(residual_.data() + begin, size) -=
          alpha * ConstChunk(hessian_search_.data() + begin, size);
    });
    dd += 2.0 * alpha * dp + alpha * alpha * pp;
    if (cg_iterations >= max_cg_iterations) break;
    const SolveSummary summary = solver.Solve(residual_, preconditioned_, context);
    if (!summary.success()) {
      throw NumericalError(fmt::format("preconditioner solve failed: {}", summary.message));
    }
    const double next_rz = BlockDot(residual_, preconditioned_, context);
    if (!(next_rz > 0.0) || std::sqrt(next_rz) <= tolerance) break;
    const double beta = next_rz / rz;
    ForBlockChunks(search_.size(), context, [&](Eigen::Index begin, Eigen::Index size) {
      Chunk p(search_.data() + begin, size);
      p = ConstChunk(preconditioned_.data() + begin, size) + beta * p;
    });
    dp = beta * (dp + alpha * pp);
    pp = next_rz + beta * beta * pp;
    rz = next_rz;
  }

  return CgSearch{slope, dd, on_boundary};
}

NewtonCgStep::Outcome NewtonCgStep::Step(const Energy& energy_function,
                                         const ConstrainedSystem& system, LinearSolver& solver,
                                         int max_cg_iterations, Positions& positions,
                                         Rotations& rotations, double energy,
                                         const Eigen::MatrixXd& reduced_rhs,
                                         const Eigen::MatrixXd& global_step,
                                         const Context& context) {
  HARAP_CHECK(free_.rows() == system.num_free() && direction_full_.rows() == positions.rows(),
              "NewtonCgStep sized for {} free of {} vertices, called with {} of {}", free_.rows(),
              direction_full_.rows(), system.num_free(), positions.rows());
  Outcome outcome;
  const auto take_global_step = [&] {
    system.ScatterFree(global_step, positions);
    outcome.newton = false;
    outcome.energy = energy_function.FitRotations(positions, rotations, context);
    return outcome;
  };
  // In the units of E/2: the negative gradient r = B_f − A_ff u_f − A_fc u_c = reduced_rhs −
  // A_ff u_f, and z = A_ff⁻¹ r = global_step − u_f, the local/global step.
  system.GatherFree(positions, free_);
  SymmetricProduct(system.reduced_matrix(), free_, residual_, context);
  ForBlockChunks(free_.size(), context, [&](Eigen::Index begin, Eigen::Index length) {
    const ConstChunk u(free_.data() + begin, length);
    Chunk r(residual_.data() + begin, length);
    r = ConstChunk(reduced_rhs.data() + begin, length) - r;
    Chunk(preconditioned_.data() + begin, length) =
        ConstChunk(global_step.data() + begin, length) - u;
  });
  for (Index i = 0; i < preconditioned_.rows(); ++i) {
    outcome.plain_step_displacement =
        std::max(outcome.plain_step_displacement, preconditioned_.row(i).squaredNorm());
  }
  const double initial_rz = BlockDot(residual_, preconditioned_, context);
  if (!(initial_rz > 0.0)) return take_global_step();  // stationary (or not finite)
  const double gradient_norm = std::sqrt(initial_rz);
  if (first_gradient_norm_ == 0.0) first_gradient_norm_ = gradient_norm;
  const double forcing = std::min(0.5, std::sqrt(gradient_norm / first_gradient_norm_));

  energy_function.PrepareRotationDerivative(positions, rotations, /*project=*/!exact_, curvature_,
                                            context);
  const bool trust_region = exact_;
  if (trust_region && radius_ == 0.0) radius_ = gradient_norm;  // the local/global step's length
  const CgSearch cg =
      NewtonDirection(energy_function, system, solver, rotations, max_cg_iterations, initial_rz,
                      forcing * gradient_norm, outcome.cg_iterations, context);
  const double slope = cg.slope, dd = cg.dd;
  const bool on_boundary = cg.on_boundary;

  trial_positions_ = positions;
  const auto try_step = [&](double step_length) {
    ForBlockChunks(search_.size(), context, [&](Eigen::Index begin, Eigen::Index size) {
      Chunk(search_.data() + begin, size) = ConstChunk(free_.data() + begin, size) +
                                            step_length * ConstChunk(step_.data() + begin, size);
    });
    system.ScatterFree(search_, trial_positions_);
    // Fitted in place: a rejected trial leaves them as the next fit's warm start, near enough.
    return energy_function.FitRotations(trial_positions_, rotations, context);
  };
  const auto accept = [&](double trial_energy) {
    std::swap(positions, trial_positions_);
    outcome.newton = true;
    outcome.energy = trial_energy;
    return outcome;
  };
  if (trust_region) {
    // ρ = actual / predicted decrease of E/2, the model m(d) = −⟨r₀, d⟩ + ½ ⟨d, H d⟩.
    const double predicted = slope - 0.5 * BlockDot(step_, step_hessian_, context);
    const double trial_energy = try_step(1.0);
    const double ratio = 0.5 * (energy - trial_energy) / predicted;
    const double length = std::sqrt(std::max(dd, 0.0));
    if (!(ratio >= kShrinkBelow)) {
      radius_ = kShrinkFactor * (on_boundary ? radius_ : length);
    } else if (ratio > kGrowAbove && on_boundary) {
      radius_ *= 2.0;
    }
    if (predicted > 0.0 && ratio >= kAcceptAbove) return accept(trial_energy);
    return take_global_step();
  }
  // Backtracking line search on E (rotations fitted at each trial point), Armijo's condition
  // with E's slope along d, −2·slope.
  double step_length = 1.0;
  for (int trial = 0; trial < kLineSearchTrials; ++trial, step_length *= kBacktrack) {
    const double trial_energy = try_step(step_length);
    if (trial_energy <= energy - 2.0 * kArmijo * step_length * slope) return accept(trial_energy);
  }
  return take_global_step();
}

}  // namespace harap
