// SPDX-License-Identifier: MIT
#pragma once

#include "framework/types.h"

namespace harap {

/// The symmetric sparsity pattern of "vertices i and j share an element", diagonal included for
/// every vertex (also unreferenced ones), values zero, row indices sorted in each column. The
/// global-step matrices of all per-vertex and per-element ARAP energies live on this pattern.
SparseMatrix AdjacencyPattern(Index num_vertices, const Elements& elements);

/// Index into a.valuePtr() of the stored entry (row, col); throws InternalError if absent.
Index EntryPosition(const SparseMatrix& a, Index row, Index col);

/// For each stored entry p of the symmetric pattern `a`, the index of its mirror entry (col, row).
std::vector<Index> TransposePositions(const SparseMatrix& a);

}  // namespace harap
