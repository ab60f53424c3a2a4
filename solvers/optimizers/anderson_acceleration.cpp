// SPDX-License-Identifier: MIT
#include "solvers/optimizers/anderson_acceleration.h"

#include "framework/error.h"
#include "solvers/optimizers/block_vectors.h"

namespace harap {

void AndersonAcceleration::Reset(Eigen::Index rows, int history) {
  HARAP_CHECK(history >= 1, "Anderson acceleration needs a history of at least 1, got {}", history);
  history_ = history;
  residual_.resize(rows, 3);
  previous_residual_.resize(rows, 3);
  previous_image_.resize(rows, 3);
  // Sized in place, not copied from one prototype: a copy writes every page of every slot, while
  // a slot never written (a level that stops after two iterations uses one of five) then costs
  // address space only (peak memory per vertex: docs/results.md, "Scale and memory").
  residual_differences_.resize(history);
  image_differences_.resize(history);
  for (auto* slots : {&residual_differences_, &image_differences_}) {
    for (Eigen::MatrixXd& slot : *slots) slot.resize(rows, 3);
  }
  gram_.setZero(history, history);
  rhs_.resize(history);
  theta_.resize(history);
  small_matrix_.resize(history, history);
  Clear();
}

void AndersonAcceleration::Clear() {
  stored_ = 0;
  newest_ = -1;
  has_previous_ = false;
}

bool AndersonAcceleration::Step(const Eigen::MatrixXd& x, const Eigen::MatrixXd& g,
                                Eigen::MatrixXd& next, const Context& context) {
  const Eigen::Index size = x.size();
  // One pass: the residual f = g − x, the differences to the previous pair into the next ring
  // slot, and the previous pair replaced by this one.
  const bool record = has_previous_;
  if (record) {
    newest_ = (newest_ + 1) % history_;
    stored_ = std::min(stored_ + 1, history_);
  }
  Eigen::MatrixXd& residual_difference = residual_differences_[std::max(newest_, 0)];
  Eigen::MatrixXd& image_difference = image_differences_[std::max(newest_, 0)];
  ForBlockChunks(size, context, [&](Eigen::Index begin, Eigen::Index length) {
    const ConstChunk gc(g.data() + begin, length), xc(x.data() + begin, length);
    Chunk f(residual_.data() + begin, length), f_old(previous_residual_.data() + begin, length),
        g_old(previous_image_.data() + begin, length);
    f = gc - xc;
    if (record) {
      Chunk(residual_difference.data() + begin, length) = f - f_old;
      Chunk(image_difference.data() + begin, length) = gc - g_old;
    }
    f_old = f;
    g_old = gc;
  });
  has_previous_ = true;
  if (record) {
    for (int j = 0; j < stored_; ++j) {
      const int slot = (newest_ - j + history_) % history_;
      gram_(newest_, slot) = gram_(slot, newest_) =
          BlockDot(residual_differences_[newest_], residual_differences_[slot], context);
    }
  }
  if (stored_ == 0) {
    next = g;
    return false;
  }
  // Normal equations of the small least-squares problem in slot order 0..stored_−1 (newest
  // first), with a relative Tikhonov term against nearly dependent differences (stagnation).
  const auto block = small_matrix_.topLeftCorner(stored_, stored_);
  double trace = 0.0;
  for (int i = 0; i < stored_; ++i) {
    const int slot_i = (newest_ - i + history_) % history_;
    rhs_(i) = BlockDot(residual_differences_[slot_i], residual_, context);
    for (int j = 0; j < stored_; ++j) {
      small_matrix_(i, j) = gram_(slot_i, (newest_ - j + history_) % history_);
    }
    trace += small_matrix_(i, i);
  }
  bool extrapolated = trace > 0.0;  // else no change between iterates: nothing to extrapolate
  if (extrapolated) {
    small_matrix_.diagonal().head(stored_).array() += 1e-10 * trace / stored_;
    ldlt_.compute(block);  // reallocates only while the history fills up
    theta_.head(stored_) = ldlt_.solve(rhs_.head(stored_));
    extrapolated = theta_.head(stored_).allFinite();
  }
  // next = g − Σ_i θ_i ΔG_i, in one pass.
  ForBlockChunks(size, context, [&](Eigen::Index begin, Eigen::Index length) {
    Chunk out(next.data() + begin, length);
    out = ConstChunk(g.data() + begin, length);
    if (!extrapolated) return;
    for (int i = 0; i < stored_; ++i) {
      out -= theta_(i) *
             ConstChunk(image_differences_[(newest_ - i + history_) % history_].data() + begin,
                        length);
    }
  });
  return extrapolated;
}

}  // namespace harap
