// SPDX-License-Identifier: MIT
// Point clouds drawn from a triangle surface, for registration targets with a known answer
// (docs/registration.md, "Known answers").
#pragma once

#include <cstdint>

#include "framework/mesh.h"
#include "framework/types.h"

namespace harap {

/// Points with one unit normal each (a zero normal where the triangle is degenerate).
struct SampledPoints {
  Positions points = Positions(0, 3);
  Positions normals = Positions(0, 3);
};

/// `count` points uniformly distributed over the area of `mesh`'s triangles (a triangle is
/// chosen with probability proportional to its area, then a uniform point inside it), each with
/// its triangle's unit normal. Deterministic for a seed, on every platform (the random numbers
/// come from std::mt19937_64, whose sequence the standard fixes, mapped to doubles here rather
/// than by the library's distributions, whose algorithms it does not fix). Throws InputError for
/// a mesh without triangles of positive area or a negative count.
SampledPoints SampleSurface(const Mesh& mesh, Index count, std::uint64_t seed);

/// How DamagePoints damages a sample.
struct PointDamage {
  /// Fraction of the points removed as one contiguous patch: the points nearest a randomly
  /// chosen one (a hole, as a scan's occlusion leaves).
  double removed = 0.10;
  /// Outliers added, as a fraction of the points kept: uniform in the kept points' bounding box
  /// grown by `outlier_margin` of its extent on every side, with random unit normals.
  double outliers = 0.01;
  double outlier_margin = 0.10;
};

/// `sample` with a patch removed and outliers appended (after the kept points, in their
/// order). Deterministic for a seed. Throws InputError for fractions outside [0, 1) or an empty
/// sample.
SampledPoints DamagePoints(const SampledPoints& sample, const PointDamage& damage,
                           std::uint64_t seed);

}  // namespace harap
