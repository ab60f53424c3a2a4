// SPDX-License-Identifier: MIT
#pragma once

#include "framework/types.h"

namespace harap {

/// Whether `x` and `y` have the same size and the same entries stored in every column (explicit
/// zeros included; values are not compared). Compressed or not.
bool SamePattern(const SparseMatrix& x, const SparseMatrix& y);

/// Whether row (= column: `a` is symmetric) j of `a` is the identity's: 1 on the diagonal, every
/// other stored entry 0. What a handle's row becomes in the masked matrix of a session, and what a
/// deleted row of a factor becomes.
bool IsIdentityRow(const SparseMatrix& a, Index j);

}  // namespace harap
