// SPDX-License-Identifier: MIT
#pragma once

#include <Eigen/Dense>
#include <vector>

#include "framework/context.h"

namespace harap {

/// Anderson acceleration (type II, Walker & Ni 2011) of a fixed-point iteration x ← G(x), as
/// applied to the local/global ARAP iteration by Peng et al. 2018 ("Anderson Acceleration for
/// Geometry Optimization and Physics Simulation"): from the last m pairs (x_j, g_j = G(x_j)) and
/// their residuals f_j = g_j − x_j, the next iterate is
///   x⁺ = g_k − ΔG θ,   θ = argmin ‖f_k − ΔF θ‖²,
/// ΔF, ΔG the differences of consecutive residuals and images. It is not a descent method by
/// itself: the caller keeps x⁺ only if it lowers the energy and otherwise takes g_k (Peng et al.'s
/// safeguard), which keeps the iteration monotone.
///
/// Iterates are #free×3 matrices. The Gram matrix ΔFᵀΔF is updated incrementally (one new column
/// per step), so a step costs about 3m vector operations of the iterate's size and allocates
/// nothing after Reset.
class AndersonAcceleration {
 public:
  /// Sizes the buffers for iterates of `rows`×3 and `history` = m ≥ 1 difference pairs, and clears.
  void Reset(Eigen::Index rows, int history);
  /// Forgets the pairs (the map G changed, e.g. constraint targets moved).
  void Clear();
  /// Records the pair (x, g = G(x)) and writes the accelerated iterate into `next`. Returns false,
  /// with next = g, while there is no difference pair yet (the first step after Clear).
  bool Step(const Eigen::MatrixXd& x, const Eigen::MatrixXd& g, Eigen::MatrixXd& next,
            const Context& context);

 private:
  int history_ = 0;
  int stored_ = 0;   ///< difference pairs held (≤ history_)
  int newest_ = -1;  ///< ring-buffer slot of the newest pair
  bool has_previous_ = false;
  Eigen::MatrixXd residual_, previous_residual_, previous_image_;
  std::vector<Eigen::MatrixXd> residual_differences_, image_differences_;
  Eigen::MatrixXd gram_;  ///< ΔFᵀΔF in ring-buffer slots
  Eigen::VectorXd rhs_, theta_;
  Eigen::MatrixXd small_matrix_;
  Eigen::LDLT<Eigen::MatrixXd> ldlt_;
};

}  // namespace harap
