// SPDX-License-Identifier: MIT
// Compiled into harap_solvers only when CHOLMOD was found (see cholmod_solver.cpp).
#ifdef HARAP_HAVE_CHOLMOD

#include "solvers/linear/cholmod_refactor_routes.h"

#include <cholmod.h>
#include <cholmod_modify.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string_view>

#include "framework/error.h"
#include "solvers/linear/blas_work_buffer.h"
#include "solvers/linear/cholmod_native_threads.h"
#include "solvers/linear/cholmod_views.h"
#include "solvers/linear/sparse_pattern.h"

namespace harap::cholmod_refactor {
namespace {

using RefactorChoice = CholmodSolver::RefactorChoice;

// The simplicial factor's arrays, read by the update's estimate and modifications.
struct SimplicialArrays {
  explicit SimplicialArrays(const cholmod_factor& f)
      : lp(static_cast<const int*>(f.p)),
        lnz(static_cast<const int*>(f.nz)),
        li(static_cast<const int*>(f.i)) {}
  // Column j's parent in the elimination tree: its first row below the diagonal (-1: a root).
  int parent(int j) const { return lnz[j] > 1 ? li[lp[j] + 1] : -1; }
  const int* lp;   // column starts
  const int* lnz;  // column counts, the diagonal first
  const int* li;   // row indices
};

bool CanUpdate(const CholmodFactorization& f) { return !f.factor->is_super && !f.factor->is_ll; }

bool CanRefactorPartially(const CholmodFactorization& f) {
  return f.super != nullptr && f.super_current && f.keeps_super();
}

// The partial refactorization's share of the work (PartialSupernodalFactor::Mark, which also marks
// the supernodes RefactorPartial() recomputes) and time: its flops at the speed of the last partial
// refactorization (before any: the default).
void EstimatePartial(CholmodFactorization& f, const std::vector<Index>& changed_rows) {
  std::vector<int>& columns = f.row_index;
  columns.clear();
  for (Index r : changed_rows) columns.push_back(f.inverse_permutation[r]);
  f.info.partial_work_fraction = f.partial.Mark(f.SuperView(), columns);
  f.info.partial_supernodes = f.partial.marked_supernodes();
  f.info.estimated_partial_seconds = f.partial.marked_work() * f.partial_seconds_per_flop;
}

// The factor entries the deletions and the additions would touch (see CholmodSolver::Refactor()
// for the rule) into `plan`, and their estimated time into f.info.
void EstimateUpdate(CholmodFactorization& f, const SparseMatrix& a,
                    const std::vector<Index>& changed_rows, RefactorPlan& plan) {
  const Index n = f.rows;
  const SimplicialArrays l(*f.factor);
  // path_cost[j]: the factor entries in the columns from j up to the root (parents have larger
  // indices, so one descending sweep).
  f.path_cost.resize(n);
  for (Index j = n; j-- > 0;) {
    const int p = l.parent(static_cast<int>(j));
    f.path_cost[j] = l.lnz[j] + (p >= 0 ? f.path_cost[p] : 0.0);
  }
  // A deletion's column of the update starts at its first row that is not deleted too.
  std::vector<int>& deleted = f.mark;
  std::fill(deleted.begin(), deleted.end(), 0);
  for (Index r : changed_rows) {
    if (!IsIdentityRow(f.matrix, r)) deleted[f.inverse_permutation[r]] = 1;
  }
  for (Index r : changed_rows) {
    const int k = f.inverse_permutation[r];
    if (deleted[k]) {
      for (int e = l.lp[k] + 1; e < l.lp[k] + l.lnz[k]; ++e) {
        if (deleted[l.li[e]]) continue;
        plan.delete_entries += f.path_cost[l.li[e]];
        break;
      }
    }
    if (!IsIdentityRow(a, r)) {
      double forward = 0.0;
      const auto [begin, end] = ColumnRange(a, r);
      for (Index e = begin; e < end; ++e) {
        const int i = f.inverse_permutation[a.innerIndexPtr()[e]];
        if (i < k) forward = std::max(forward, f.path_cost[i] - f.path_cost[k]);
      }
      plan.add_entries += forward + f.path_cost[k];
    }
  }
  // Additions move columns of a packed factor, so the parallel solve's plan is set up again.
  const double plan_setup = plan.add_entries > 0.0 && f.use_tree_solve ? f.plan_seconds : 0.0;
  f.info.estimated_update_seconds = plan.delete_entries * f.delete_seconds_per_entry +
                                    plan.add_entries * f.add_seconds_per_entry + plan_setup;
}

[[noreturn]] void ThrowModificationFailure(const CholmodFactorization& f, std::string_view stage,
                                           const SparseMatrix& a) {
  f.ThrowOnFailure(stage, a);
  throw InternalError(fmt::format("cholmod: {} failed with status {}", stage, f.common.status));
}

// The update's first part: every changed row k that is not already the identity's becomes it,
// all at once. With F the other rows, the old P A Pᵀ restricted to F is
//   Σ_j d_j L(F,j) L(F,j)ᵀ = L̃ D̃ L̃ᵀ (F,F) + Σ_k d_k L(F,k) L(F,k)ᵀ,
// where L̃, D̃ are L, D with the deleted rows and columns replaced by the identity's. So setting
// those rows and columns to the identity's and updating with the columns sqrt(d_k) L(F,k)
// (cholmod_updown, up to 8 columns per sweep along the elimination tree) gives the factor of `a`
// with all changed rows and columns replaced by the identity's, since `a` and the old matrix
// differ only there.
void DeleteChangedRows(CholmodFactorization& f, const SparseMatrix& a,
                       const std::vector<Index>& changed_rows) {
  const Index n = f.rows;
  const SimplicialArrays l(*f.factor);
  std::vector<int>& deleted = f.mark;
  std::fill(deleted.begin(), deleted.end(), 0);
  std::vector<int>& deletions = f.row_index;
  deletions.clear();
  for (Index r : changed_rows) {
    if (IsIdentityRow(f.matrix, r)) continue;
    deletions.push_back(f.inverse_permutation[r]);
    deleted[f.inverse_permutation[r]] = 1;
  }
  if (deletions.empty()) return;
  auto* lx = static_cast<double*>(f.factor->x);
  std::vector<int>& cp = f.update_start;
  std::vector<int>& ci = f.update_row;
  std::vector<double>& cx = f.update_value;
  cp.assign(1, 0);
  ci.clear();
  cx.clear();
  for (int k : deletions) {
    const double scale = std::sqrt(lx[l.lp[k]]);  // d_k > 0: the old factor passed the checks
    for (int e = l.lp[k] + 1; e < l.lp[k] + l.lnz[k]; ++e) {
      if (deleted[l.li[e]]) continue;
      ci.push_back(l.li[e]);
      cx.push_back(lx[e] * scale);
    }
    if (static_cast<int>(ci.size()) > cp.back()) cp.push_back(static_cast<int>(ci.size()));
  }
  // L̃, D̃: one pass over the factor (cheaper than searching each deleted row's columns).
  for (Index j = 0; j < n; ++j) {
    if (deleted[j]) {
      lx[l.lp[j]] = 1.0;
      std::fill(lx + l.lp[j] + 1, lx + l.lp[j] + l.lnz[j], 0.0);
      continue;
    }
    for (int e = l.lp[j] + 1; e < l.lp[j] + l.lnz[j]; ++e) {
      if (deleted[l.li[e]]) lx[e] = 0.0;
    }
  }
  if (cp.size() > 1) {
    // The factor's columns are sorted.
    cholmod_sparse c = cholmod_views::ColumnsView(n, cp.size() - 1, cp.data(), ci.data(), cx.data(),
                                                  ci.size(), /*sorted=*/true);
    if (!cholmod_updown(1, &c, f.factor, &f.common)) {
      ThrowModificationFailure(f, "update (cholmod_updown)", a);
    }
  }
}

// The update's second part: each changed row that is not the identity's in `a` is added
// (cholmod_rowadd) with its entries in the rows already added, which keeps the invariant of
// DeleteChangedRows(): the factor is that of `a` with the rows not yet added replaced by the
// identity's.
void AddChangedRows(CholmodFactorization& f, const SparseMatrix& a,
                    const std::vector<Index>& changed_rows) {
  std::vector<int>& pending = f.mark;
  std::fill(pending.begin(), pending.end(), 0);
  for (Index r : changed_rows) pending[r] = 1;
  std::vector<int>& rows = f.row_index;
  std::vector<double>& values = f.row_value;
  int column_start[2] = {0, 0};
  for (Index r : changed_rows) {
    pending[r] = 0;
    if (IsIdentityRow(a, r)) continue;
    rows.clear();
    values.clear();
    const auto [begin, end] = ColumnRange(a, r);
    for (Index e = begin; e < end; ++e) {
      const Index i = a.innerIndexPtr()[e];
      if (pending[i]) continue;
      rows.push_back(f.inverse_permutation[i]);
      values.push_back(a.valuePtr()[e]);
    }
    column_start[1] = static_cast<int>(rows.size());
    cholmod_sparse column = cholmod_views::ColumnsView(
        f.rows, 1, column_start, rows.data(), values.data(), std::max<size_t>(rows.size(), 1),
        /*sorted=*/false);
    if (!cholmod_rowadd(static_cast<size_t>(f.inverse_permutation[r]), &column, f.factor,
                        &f.common)) {
      ThrowModificationFailure(f, "row addition (cholmod_rowadd)", a);
    }
  }
}

// The pattern holds every entry a row can need, but cholmod_rowadd makes room for one more in
// every column of its forward solve that has no slack (all of them in a packed factor), moving it
// to the end of the factor's arrays: its solve plan must then be set up anew. Moved columns stay
// below the tail L->p[n], which is all EliminationTreeSolve reads; if a CHOLMOD version did
// otherwise, the factor is packed first. Returns whether columns moved.
bool PackIfColumnsMoved(CholmodFactorization& f, const SparseMatrix& a,
                        double reallocations_before) {
  const bool moved = f.common.nrealloc_col != reallocations_before || !f.factor->is_monotonic;
  if (!moved) return false;
  const auto* start = static_cast<const int*>(f.factor->p);
  const auto* count = static_cast<const int*>(f.factor->nz);
  const Index n = f.rows;
  bool below_tail = true;
  for (Index j = 0; j < n && below_tail; ++j) below_tail = start[j] + count[j] <= start[n];
  if (!below_tail &&
      !cholmod_change_factor(CHOLMOD_REAL, f.factor->is_ll, 0, 1, 1, f.factor, &f.common)) {
    ThrowModificationFailure(f, "packing of the modified factor", a);
  }
  return true;
}

}  // namespace

bool CanReuse(const CholmodFactorization& f, const SparseMatrix& a) {
  return f.factorized && f.symbolic != nullptr && f.rows != 0 &&
         f.options.refactor != RefactorChoice::kFull && SamePattern(f.matrix, a);
}

void CheckChangedRows(CholmodFactorization& f, const SparseMatrix& a,
                      const std::vector<Index>& changed_rows) {
  const Index n = f.rows;
  for (size_t k = 0; k < changed_rows.size(); ++k) {
    HARAP_CHECK(changed_rows[k] >= 0 && changed_rows[k] < n &&
                    (k == 0 || changed_rows[k] > changed_rows[k - 1]),
                "Refactor: changed_rows must be sorted, unique and in [0, {}); entry {} is {}", n,
                k, changed_rows[k]);
  }
  std::vector<int>& changed = f.mark;
  changed.assign(n, 0);
  for (Index r : changed_rows) changed[r] = 1;
  for (Index j = 0; j < n; ++j) {
    if (changed[j]) continue;
    const auto [begin, end] = ColumnRange(a, j);
    const auto [old_begin, old_end] = ColumnRange(f.matrix, j);
    for (Index e = begin, o = old_begin; e < end; ++e, ++o) {
      const Index i = a.innerIndexPtr()[e];
      HARAP_CHECK(changed[i] || a.valuePtr()[e] == f.matrix.valuePtr()[o],
                  "Refactor: entry ({}, {}) changed from {} to {}, but neither row {} nor row {} "
                  "is in changed_rows",
                  i, j, f.matrix.valuePtr()[o], a.valuePtr()[e], i, j);
    }
  }
}

RefactorPlan PlanRefactor(CholmodFactorization& f, const SparseMatrix& a,
                          const std::vector<Index>& changed_rows) {
  const bool can_update = CanUpdate(f);
  const bool can_partial = CanRefactorPartially(f);
  RefactorPlan plan;
  plan.route = f.options.refactor;
  if (plan.route == RefactorChoice::kUpdate && !can_update) plan.route = RefactorChoice::kNumeric;
  if (plan.route == RefactorChoice::kPartial && !can_partial) plan.route = RefactorChoice::kNumeric;
  f.info.estimated_update_seconds = 0.0;
  f.info.estimated_partial_seconds = 0.0;
  f.info.estimated_numeric_seconds = f.info.numeric_seconds;
  const Index n = f.rows;
  const auto* perm = static_cast<const int*>(f.factor->Perm);
  f.inverse_permutation.resize(n);
  for (Index j = 0; j < n; ++j) f.inverse_permutation[perm ? perm[j] : j] = static_cast<int>(j);
  if (can_partial &&
      (plan.route == RefactorChoice::kPartial || plan.route == RefactorChoice::kAuto)) {
    EstimatePartial(f, changed_rows);
  }
  if (can_update) EstimateUpdate(f, a, changed_rows, plan);
  if (plan.route == RefactorChoice::kAuto) {
    // The lowest estimate of the routes this factor allows.
    plan.route = RefactorChoice::kNumeric;
    double best = f.info.estimated_numeric_seconds;
    if (can_partial && f.info.estimated_partial_seconds < best) {
      plan.route = RefactorChoice::kPartial;
      best = f.info.estimated_partial_seconds;
    }
    if (can_update && f.info.estimated_update_seconds < best) plan.route = RefactorChoice::kUpdate;
  }
  return plan;
}

bool RefactorPartial(CholmodFactorization& f, const SparseMatrix& a,
                     const Eigen::VectorXd& diagonal, const Context& context) {
  if (!EnsureBlasWorkBuffer()) return false;
  const ScopedNativeThreads native_threads(f.options.native_threads);
  const Stopwatch clock;
  const int bad_column = f.partial.Refactor(f.SuperView(), a, f.inverse_permutation);
  // A non-positive pivot (`a` is not positive definite): Factorize() says so in detail.
  if (bad_column >= 0 || !f.CopySuperToSimplicial(/*all=*/false)) {
    f.FreeSuper();
    return false;
  }
  // Calibrate on refactorizations large enough to time.
  constexpr double kCalibrationFlops = 1e7;
  if (f.partial.marked_work() >= kCalibrationFlops) {
    f.partial_seconds_per_flop = clock.Seconds() / f.partial.marked_work();
  }
  f.FinishFactor(a, diagonal, context, /*same_arrays=*/true);
  return true;
}

bool RefactorNumeric(CholmodFactorization& f, const SparseMatrix& a,
                     const Eigen::VectorXd& diagonal, const Context& context) {
  if (f.options.mode != CholmodSolver::Mode::kSimplicial && !EnsureBlasWorkBuffer()) return false;
  const ScopedNativeThreads native_threads(f.options.native_threads);
  cholmod_sparse view = cholmod_views::LowerTriangleView(a);
  if (f.FactorNumericInPlace(view, a, context)) {
    f.FinishFactor(a, diagonal, context, /*same_arrays=*/true);
    return true;
  }
  // E.g. a factor whose pattern updates changed: factored from a copy of the analysis (keeping
  // the supernodal factor again if kept at all).
  f.FreeFactor();
  f.factor = cholmod_copy_factor(f.symbolic, &f.common);
  f.ThrowOnFailure("copy of the analysis", a);
  if (f.keeps_super()) {
    f.FactorNumericKeepingSuper(view, a, context);
  } else {
    f.FreeSuper();
    f.FactorNumeric(view, a, context);
  }
  f.FinishFactor(a, diagonal, context, /*same_arrays=*/false, /*same_pattern=*/true);
  return true;
}

void RefactorByUpdate(CholmodFactorization& f, const SparseMatrix& a,
                      const std::vector<Index>& changed_rows, const RefactorPlan& plan,
                      const Eigen::VectorXd& diagonal, const Context& context) {
  f.super_current = false;  // the kept supernodal factor no longer matches
  const double reallocations_before = f.common.nrealloc_col;
  Stopwatch clock;
  DeleteChangedRows(f, a, changed_rows);
  const double delete_seconds = clock.Seconds();
  clock.Restart();
  AddChangedRows(f, a, changed_rows);
  const double add_seconds = clock.Seconds();
  // Calibrate on modifications large enough to time (a few milliseconds at least).
  constexpr double kCalibrationEntries = 1e6;
  if (plan.delete_entries >= kCalibrationEntries) {
    f.delete_seconds_per_entry = delete_seconds / plan.delete_entries;
  }
  if (plan.add_entries >= kCalibrationEntries) {
    f.add_seconds_per_entry = add_seconds / plan.add_entries;
  }
  const bool moved = PackIfColumnsMoved(f, a, reallocations_before);
  f.FinishFactor(a, diagonal, context, /*same_arrays=*/!moved);
}

}  // namespace harap::cholmod_refactor

#endif  // HARAP_HAVE_CHOLMOD
