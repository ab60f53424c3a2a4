// SPDX-License-Identifier: MIT
#pragma once

#include <memory>
#include <string_view>

#include "framework/config.h"
#include "framework/optimizer.h"
#include "solvers/optimizers/admm_elements.h"
#include "solvers/optimizers/local_global_solver.h"

namespace harap {

/// Hierarchical (cascadic) ARAP, the paper's Algorithm 2: build a mesh hierarchy (Section 4),
/// precompute and factor every level, solve the coarsest level with local/global iterations until
/// the convergence test holds, up-sample to the next finer level (Section 5.1) and solve again,
/// down to the input mesh.
///
/// Constraints on coarse levels (Section 4): a coarse vertex is constrained if any finest-level
/// vertex mapped to it is; its target is the average over those members of
/// (target_m − R_c (v̄_m − v̄_c)), i.e. mean target minus the rotated mean offset, with R_c the
/// coarse vertex's current rotation (identity at first). With `update_constraints` the targets
/// follow R_c before every global step (Fig. 16, right).
///
/// `inner` chooses the optimizer run on each level: `local_global` (the paper's), or the ADMM
/// optimizers `admm_pd` / `wrapd` (the paper's "hierarchical WRAPD", Section 7), energy
/// `elements` only. ADMM keeps no rotations, so a finished level hands the up-sampler the
/// rotations of the polar decompositions of its elements (averaged to vertices by Eq. 11 and
/// applied to the positions by Eq. 6 inside the up-sampler), the finer level starts from the
/// up-sampled positions, and coarse levels drop their inverted (misoriented) elements.
/// With an ADMM inner optimizer `tolerance`, `max_iterations` and `coarse_tolerance` take the
/// ADMM meanings (relative energy change, see admm_elements.h); update_constraints and
/// freeze_targets_after do not apply (targets are placed once per level).
///
/// The coarsest level starts like classic ARAP: coarse rest positions with constrained vertices at
/// their targets, then a local step. With a one-level hierarchy the result equals `classic`.
class HierarchicalOptimizer final : public Optimizer {
 public:
  static constexpr std::string_view kName = "hierarchical";

  enum class Inner { kLocalGlobal, kAdmmPd, kWrapd };

  struct Options {
    Inner inner = Inner::kLocalGlobal;  ///< the optimizer on each level
    AdmmOptions admm;                   ///< with inner = admm_pd or wrapd (admm_elements.h)
    LocalGlobalOptions iterations;  ///< tolerance (1e-6) and max_iterations (1000), per level
    /// Tolerance on the coarse levels (l > 0); negative: the same as `tolerance`.
    double coarse_tolerance = -1.0;
    /// Solve every k-th level below the coarsest (1: all levels; Fig. 14 "every second level":
    /// 2). The finest and coarsest levels are always solved; skipped levels are only up-sampled.
    int level_step = 1;
    /// Solve only the coarsest and the finest level (Fig. 14 "coarse level only").
    bool coarsest_only = false;
    /// Fig. 15's approximation: up-sample the coarsest solution straight to the finest level
    /// and do one global solve there (no iterations on the finest level).
    bool coarse_approximation = false;
    /// Re-evaluate coarse constraint targets with the current rotations during each level.
    bool update_constraints = true;
    /// Set up (precompute and factor) the finer levels on another thread while the coarser ones
    /// are solved. The finest level's setup is mostly sequential (ordering, symbolic analysis)
    /// and longer than all coarse solves together, so this hides the coarse solves. Results are
    /// identical; the report's phase times then overlap (total < H + P + C + S). Needs ≥ 2
    /// threads (else off).
    bool overlap_setup = true;

    static Options FromConfig(const ConfigNode& node);
  };

  explicit HierarchicalOptimizer(const Options& options) : options_(options) {}
  static std::unique_ptr<Optimizer> Create(const ConfigNode& node);

  OptimizeResult Optimize(const DeformationProblem& problem, const ComponentFactory& factory,
                          const Context& context) const override;

 private:
  Options options_;
};

}  // namespace harap
