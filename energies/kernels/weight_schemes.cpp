// SPDX-License-Identifier: MIT
#include "energies/kernels/weight_schemes.h"

#include <algorithm>

#include "energies/kernels/cotangent_weights.h"
#include "energies/kernels/intrinsic_delaunay.h"
#include "framework/error.h"

namespace harap {

TriangleWeights ComputeTriangleWeights(const Positions& vertices, const Elements& triangles,
                                       WeightScheme scheme, double min_cotangent) {
  TriangleWeights weights;
  switch (scheme) {
    case WeightScheme::kCotangent:
      weights.triangles = triangles;
      weights.half_cot = HalfCotangents(vertices, triangles, &weights.degenerate);
      return weights;
    case WeightScheme::kIntrinsicDelaunay: {
      IntrinsicTriangulation intrinsic = IntrinsicDelaunayTriangulation(vertices, triangles);
      weights.triangles = std::move(intrinsic.triangles);
      weights.half_cot = std::move(intrinsic.half_cot);
      weights.degenerate = intrinsic.degenerate;
      weights.flips = intrinsic.flips;
      weights.zeroed_edges = intrinsic.zeroed_edges;
      return weights;
    }
    case WeightScheme::kClamped:
    case WeightScheme::kUniform: {
      weights.triangles = triangles;
      weights.half_cot = HalfCotangents(vertices, triangles, &weights.degenerate);
      for (Index f = 0; f < weights.half_cot.rows(); ++f) {
        // Degenerate triangles keep their zeros (HalfCotangents zeroes all three).
        if ((weights.half_cot.row(f).array() == 0.0).all()) continue;
        for (int k = 0; k < 3; ++k) {
          double& w = weights.half_cot(f, k);
          w = scheme == WeightScheme::kUniform ? 0.5 : std::max(w, 0.5 * min_cotangent);
        }
      }
      return weights;
    }
    case WeightScheme::kAsInputLevel:
      break;
  }
  throw InternalError("ComputeTriangleWeights: no weights for the scheme 'same'");
}

}  // namespace harap
