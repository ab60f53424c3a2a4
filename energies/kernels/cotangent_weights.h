// SPDX-License-Identifier: MIT
#pragma once

#include "framework/mesh.h"
#include "framework/types.h"

namespace harap {

// kDegenerateTriangleRatio (framework/mesh.h): triangles below it get zero weights.

/// ½·cot of the interior angle at each corner of each triangle (#F×3): column a belongs to the
/// edge opposite corner a (the Pinkall–Polthier / Chao et al. weight w_{f,jk}). Degenerate
/// triangles get zeros and are counted in `num_degenerate` (if given).
Eigen::Matrix<double, Eigen::Dynamic, 3> HalfCotangents(const Positions& vertices,
                                                        const Elements& triangles,
                                                        Index* num_degenerate = nullptr);

}  // namespace harap
