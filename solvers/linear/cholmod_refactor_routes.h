// SPDX-License-Identifier: MIT
#pragma once
// Part of the CHOLMOD solver (cholmod_solver.h): included only by sources compiled with CHOLMOD
// (HARAP_HAVE_CHOLMOD).

#include <Eigen/Dense>
#include <vector>

#include "framework/context.h"
#include "framework/types.h"
#include "solvers/linear/cholmod_factorization.h"
#include "solvers/linear/cholmod_solver.h"

// The routes of CholmodSolver::Refactor() (the rule that picks one, and what each computes, is
// documented at CholmodSolver::Refactor() and in docs/solvers.md, "Refactoring after handle
// edits"). CholmodSolver::RefactorImpl() checks, plans, then runs one route; a route that cannot
// go on returns false before changing the factor's values, and the caller factors from scratch.
namespace harap::cholmod_refactor {

/// Whether `factorization` holds what a route reuses for `a`: a factorization of a matrix with the
/// same pattern, the copies Refactor() needs (keeps_copies()), and a route other than full.
bool CanReuse(const CholmodFactorization& factorization, const SparseMatrix& a);

/// Refactor()'s contract: `changed_rows` sorted, unique and in range, and the values of `a` equal
/// to those of the last factored matrix outside those rows and columns. The update route relies
/// on it, so a caller's mistake is an InternalError naming the entry, not a wrong factor.
void CheckChangedRows(CholmodFactorization& factorization, const SparseMatrix& a,
                      const std::vector<Index>& changed_rows);

/// The route a refactorization takes and what the update route would touch.
struct RefactorPlan {
  CholmodSolver::RefactorChoice route = CholmodSolver::RefactorChoice::kNumeric;
  double delete_entries = 0.0;  ///< Factor entries the deletions' update touches.
  double add_entries = 0.0;     ///< Factor entries the row additions touch.
};

/// The route Options::refactor names if this factor allows it (else numeric), or for auto the
/// one with the lowest estimated time; records the estimates in factorization.info and sets up
/// factorization.inverse_permutation, which the routes read.
RefactorPlan PlanRefactor(CholmodFactorization& factorization, const SparseMatrix& a,
                          const std::vector<Index>& changed_rows);

/// The partial route: refactors the supernodes of the kept supernodal factor that the changed
/// rows reach (marked by PlanRefactor()) and copies them into the simplicial factor. False (the
/// kept supernodal factor dropped) if there is no BLAS buffer or a pivot fails.
bool RefactorPartial(CholmodFactorization& factorization, const SparseMatrix& a,
                     const Eigen::VectorXd& diagonal, const Context& context);

/// The numeric route: the values factored anew with the kept analysis. False if there is no BLAS
/// buffer for a supernodal factorization.
bool RefactorNumeric(CholmodFactorization& factorization, const SparseMatrix& a,
                     const Eigen::VectorXd& diagonal, const Context& context);

/// The update route (simplicial LDLᵀ): the changed rows deleted from the factor at once
/// (cholmod_updown), then added row by row (cholmod_rowadd); calibrates the seconds per touched
/// entry on modifications large enough to time.
void RefactorByUpdate(CholmodFactorization& factorization, const SparseMatrix& a,
                      const std::vector<Index>& changed_rows, const RefactorPlan& plan,
                      const Eigen::VectorXd& diagonal, const Context& context);

}  // namespace harap::cholmod_refactor
