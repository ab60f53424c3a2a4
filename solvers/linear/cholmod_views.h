// SPDX-License-Identifier: MIT
#pragma once
// Part of the CHOLMOD solver (cholmod_solver.h): included only by sources compiled with CHOLMOD
// (HARAP_HAVE_CHOLMOD).

#include <cholmod.h>

#include <Eigen/Dense>
#include <cstddef>
#include <string_view>

#include "framework/types.h"
#include "solvers/linear/elimination_tree_solve.h"
#include "solvers/linear/partial_supernodal_factor.h"

namespace harap::cholmod_views {

// Views without ownership between harap's arrays and CHOLMOD's structs: no copies, the viewed
// memory must outlive the view. CHOLMOD's inputs are not const-qualified, but the calls these
// views are handed to only read them.

/// `a` (n×n, full symmetric storage) as CHOLMOD's symmetric lower-triangle matrix: with stype = -1
/// CHOLMOD reads only the entries on and below the diagonal, so full storage needs no copy.
cholmod_sparse LowerTriangleView(const SparseMatrix& a);

/// The same view without values, for CHOLMOD's analysis: the ordering and the symbolic
/// factorization read only the pattern, and the transposes they make of A then copy no values.
cholmod_sparse PatternView(const SparseMatrix& a);

/// `columns` packed, unsymmetric columns of `rows` rows in compressed column form (column_start,
/// row_index, value; room for `capacity` entries), as cholmod_updown and cholmod_rowadd take their
/// modifications.
cholmod_sparse ColumnsView(Index rows, size_t columns, int* column_start, int* row_index,
                           double* value, size_t capacity, bool sorted);

/// `b` as a dense right-hand side of cholmod_solve2 (which only reads it).
cholmod_dense DenseView(const Eigen::Ref<const Eigen::MatrixXd>& b);

/// A numeric supernodal factor as PartialSupernodalFactor reads it.
SupernodalFactorView SupernodalView(const cholmod_factor& f);

/// A simplicial factor's arrays as EliminationTreeSolve reads them.
LdltFactorView SimplicialView(const cholmod_factor& f);

/// CHOLMOD's name of a factor's ordering (cholmod_factor::ordering): "amd", "metis", ...
std::string_view OrderingName(int cholmod_ordering);

/// Calls visit(j, pivot) for column j's pivot d_j (LDLᵀ) or L_jj² (LLᵀ) of a numeric factor, in
/// the factor's order.
template <class Visit>
void ForEachPivot(const cholmod_factor& factor, Visit&& visit) {
  const auto* x = static_cast<const double*>(factor.x);
  if (factor.is_super) {
    const auto* super = static_cast<const int*>(factor.super);
    const auto* pi = static_cast<const int*>(factor.pi);
    const auto* px = static_cast<const int*>(factor.px);
    for (size_t s = 0; s < factor.nsuper; ++s) {
      const int first = super[s];
      const int rows = pi[s + 1] - pi[s];  // Leading dimension of the supernode's dense block.
      for (int j = first; j < super[s + 1]; ++j) {
        const double l = x[px[s] + static_cast<size_t>(j - first) * (rows + 1)];
        visit(j, l * l);
      }
    }
  } else {
    const auto* p = static_cast<const int*>(factor.p);
    for (size_t j = 0; j < factor.n; ++j) {
      const double d = x[p[j]];  // The diagonal is the first entry of each column.
      visit(static_cast<int>(j), factor.is_ll ? d * d : d);
    }
  }
}

}  // namespace harap::cholmod_views
