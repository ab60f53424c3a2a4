// SPDX-License-Identifier: MIT
#pragma once

// The transfer operators of the multigrid solver (multigrid_solver.h): aggregates of unknowns,
// the prolongation P from them and the Galerkin coarse matrix PᵀAP. Not a component: a function
// library of the solvers module.

#include <vector>

#include "framework/types.h"

namespace harap::multigrid {

/// Greedy aggregation of the unknowns of the SPD matrix `a` along its strong couplings
/// [Vaněk, Mandel & Brezina, "Algebraic multigrid by smoothed aggregation for second and fourth
/// order elliptic problems", Computing 56 (1996), Section 3]: i and j are strongly coupled when
/// |a_ij| ≥ θ √(a_ii a_jj). (1) every unknown whose strong neighbours are all still free starts
/// an aggregate of itself and those neighbours; (2) the unknowns left join the aggregate of a
/// strong neighbour (the most strongly coupled one); (3) any still left (no strong neighbour in
/// an aggregate) form aggregates of themselves and their free strong neighbours. On a mesh
/// matrix an aggregate is about a vertex's one-ring, so each level has ~1/7 of the unknowns of
/// the one below. Returns the aggregate of each unknown (0..count−1) and sets `count`.
std::vector<Index> AggregateByStrength(const SparseMatrix& a, double strength_threshold,
                                       Index& count);

/// The piecewise constant prolongation of `aggregate` (n × count): P_ij = 1 iff unknown i lies
/// in aggregate j; PᵀAP is then the sum of A's entries between aggregates.
SparseMatrix ConstantProlongation(const std::vector<Index>& aggregate, Index count);

/// Smoothed aggregation: P = (I − ω D⁻¹A) P₀ with ω = 4 / (3 λ̂), λ̂ Gershgorin's upper bound
/// of λ_max(D⁻¹A) [Vaněk et al. 1996, Eq. 3.5]. The smoothing takes the high-frequency part out
/// of the coarse basis functions, so the coarse correction does not reintroduce what the
/// smoother removed; two-level convergence then no longer depends on the mesh size.
SparseMatrix SmoothedProlongation(const SparseMatrix& a, const SparseMatrix& constant);

/// The Galerkin coarse matrix PᵀAP in full symmetric compressed storage (exactly symmetric:
/// the upper triangle is mirrored).
SparseMatrix GalerkinProduct(const SparseMatrix& a, const SparseMatrix& p);

}  // namespace harap::multigrid
