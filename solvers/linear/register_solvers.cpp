// SPDX-License-Identifier: MIT
#include "solvers/linear/register_solvers.h"

#include <string>

#include "solvers/linear/chebyshev_solver.h"
#include "solvers/linear/conjugate_gradient_solver.h"
#include "solvers/linear/eigen_ldlt_solver.h"
#include "solvers/linear/gauss_seidel_solver.h"
#include "solvers/linear/multigrid_solver.h"
#ifdef HARAP_HAVE_CHOLMOD
#include "solvers/linear/adaptive_solver.h"
#include "solvers/linear/cholmod_solver.h"
#endif

namespace harap {

void RegisterLinearSolvers(Registry<LinearSolver>& registry) {
#ifdef HARAP_HAVE_CHOLMOD
  registry.Add<CholmodSolver>(
      "sparse Cholesky with CHOLMOD (SuiteSparse), simplicial LDLᵀ or supernodal LLᵀ");
  registry.Add<AdaptiveSolver>(
      "cholmod or cg per matrix, chosen from CHOLMOD's analysis (memory and arithmetic of the "
      "factor vs. CG iterations) before factoring (paper Section 5.2)");
#endif
  registry.Add<EigenLdltSolver>(
      "sparse LDLᵀ with Eigen's SimplicialLDLT and AMD ordering (reference, always built)");
  registry.Add<GaussSeidelSolver>(
      "Gauss–Seidel/SOR sweeps (forward or symmetric), parallel by graph colouring, "
      "warm-started");
  registry.Add<ConjugateGradientSolver>(
      "preconditioned conjugate gradients (Jacobi or incomplete Cholesky), three "
      "right-hand sides per pass, warm-started");
  registry.Add<ChebyshevSolver>(
      "Chebyshev semi-iterative acceleration of Jacobi [Wang 2015], bounds from Spectra, "
      "warm-started");
  registry.Add<MultigridSolver>(
      "CG preconditioned by a multigrid V-cycle (smoothed aggregation of the matrix graph, "
      "Galerkin coarse matrices, Gauss–Seidel or Chebyshev smoothing, coarsest level factored), "
      "warm-started");
}

}  // namespace harap
