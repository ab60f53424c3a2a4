// SPDX-License-Identifier: MIT
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <Eigen/Dense>

#include "framework/context.h"

namespace harap {

/// Parallel vector operations on the optimizers' iterates (#free×3 matrices, a few MB each on
/// large meshes, so memory-bound and worth both cores), for the accelerated and Newton-type
/// iterations.

/// ⟨a, b⟩ (Frobenius), with a deterministic reduction: the same result for the same thread count.
inline double BlockDot(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, const Context& context) {
  const Eigen::Index size = a.size();
  return context.Run([&] {
    return tbb::parallel_deterministic_reduce(
        tbb::blocked_range<Eigen::Index>(0, size, 16384), 0.0,
        [&](const tbb::blocked_range<Eigen::Index>& range, double sum) {
          const Eigen::Index begin = range.begin(), length = range.end() - range.begin();
          return sum + Eigen::Map<const Eigen::VectorXd>(a.data() + begin, length)
                           .dot(Eigen::Map<const Eigen::VectorXd>(b.data() + begin, length));
        },
        [](double x, double y) { return x + y; });
  });
}

/// body(begin, length) over chunks of the flat coefficient range [0, size), in parallel: the
/// element-wise updates of the iterates.
template <class Body>
void ForBlockChunks(Eigen::Index size, const Context& context, Body&& body) {
  context.Run([&] {
    tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, size, 16384),
                      [&](const tbb::blocked_range<Eigen::Index>& range) {
                        body(range.begin(), range.end() - range.begin());
                      });
  });
}

using Chunk = Eigen::Map<Eigen::VectorXd>;
using ConstChunk = Eigen::Map<const Eigen::VectorXd>;

}  // namespace harap
