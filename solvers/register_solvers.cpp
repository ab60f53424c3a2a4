// SPDX-License-Identifier: MIT
#include "solvers/register_solvers.h"

#include <string>

#include "solvers/eigen_ldlt_solver.h"
#ifdef HARAP_HAVE_CHOLMOD
#include "solvers/cholmod_solver.h"
#endif

namespace harap {

void RegisterLinearSolvers(Registry<LinearSolver>& registry) {
#ifdef HARAP_HAVE_CHOLMOD
  registry.Add(std::string(CholmodSolver::kName),
               "sparse Cholesky with CHOLMOD (SuiteSparse), simplicial LDLᵀ or supernodal LLᵀ",
               &CholmodSolver::Create);
#endif
  registry.Add(std::string(EigenLdltSolver::kName),
               "sparse LDLᵀ with Eigen's SimplicialLDLT and AMD ordering (reference, always built)",
               &EigenLdltSolver::Create);
}

}  // namespace harap
