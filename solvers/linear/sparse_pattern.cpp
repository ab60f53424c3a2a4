// SPDX-License-Identifier: MIT
#include "solvers/linear/sparse_pattern.h"

#include <algorithm>

namespace harap {

bool SamePattern(const SparseMatrix& x, const SparseMatrix& y) {
  if (x.rows() != y.rows() || x.cols() != y.cols()) return false;
  for (Index j = 0; j < x.cols(); ++j) {
    const auto [xb, xe] = ColumnRange(x, j);
    const auto [yb, ye] = ColumnRange(y, j);
    if (xe - xb != ye - yb ||
        !std::equal(x.innerIndexPtr() + xb, x.innerIndexPtr() + xe, y.innerIndexPtr() + yb)) {
      return false;
    }
  }
  return true;
}

bool IsIdentityRow(const SparseMatrix& a, Index j) {
  const auto [begin, end] = ColumnRange(a, j);
  bool diagonal_one = false;
  for (Index e = begin; e < end; ++e) {
    const double value = a.valuePtr()[e];
    if (a.innerIndexPtr()[e] == j) {
      diagonal_one = value == 1.0;
    } else if (value != 0.0) {
      return false;
    }
  }
  return diagonal_one;
}

}  // namespace harap
