// SPDX-License-Identifier: MIT
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "framework/config.h"
#include "framework/level_solver.h"
#include "framework/optimizer.h"
#include "framework/registry.h"

namespace harap {

/// The one optimizer loop: a level solver (framework/level_solver.h, `inner`) on every solved
/// level of a mesh hierarchy, from the coarsest level down, each finer level starting from the
/// up-sampled solution of the coarser one. Registered four times:
///
/// - `hierarchical`, the paper's Algorithm 2: build a mesh hierarchy (Section 4), precompute and
///   factor every solved level, solve the coarsest level until the convergence test holds,
///   up-sample to the next finer level (Section 5.1) and solve again, down to the input mesh.
///   `inner` chooses the level solver: `local_global` (the paper's), or the ADMM solvers
///   `admm_pd` / `wrapd` (the paper's "hierarchical WRAPD", Section 7), energy `elements` only.
///   With an ADMM level solver `tolerance`, `max_iterations`, `coarse_tolerance` and
///   `coarse_tolerance_factor` (a multiple of that tolerance) take the ADMM
///   meanings (relative energy change, see admm_elements.h); targets_follow_rotations and
///   freeze_targets_after do not apply (targets are placed once per level).
/// - `classic` [Sorkine & Alexa 2007], `admm_pd` [Overby et al. 2017] and `wrapd` [Brown &
///   Narain 2021]: one-level runs of the same loop on the input mesh with that level solver
///   (`classic` = `local_global`), their options being the level solver's.
///
/// Constraints on coarse levels (Section 4): a coarse vertex is constrained if any finest-level
/// vertex mapped to it is; its target is the average over those members of
/// (target_m − R_c (v̄_m − v̄_c)), with R_c the coarse vertex's current rotation (identity at
/// first). The level solver places its constrained vertices itself; with `targets_follow_rotations`
/// the targets follow R_c before every global step (Fig. 16, right).
///
/// The coarsest level starts like classic ARAP: coarse rest positions with constrained vertices
/// at their targets, then a local step. With a one-level hierarchy the result equals `classic`.
class HierarchicalOptimizer final : public Optimizer {
 public:
  static constexpr std::string_view kName = "hierarchical";

  struct Options {
    /// The level solver's registry name, and one configured from the optimizer's table: every
    /// level gets a fresh one like it (LevelSolver::CreateAnother).
    std::string inner = "local_global";
    std::shared_ptr<const LevelSolver> level_solver;
    /// false: a one-level run on the input mesh (`classic`, `admm_pd`, `wrapd`); no hierarchy,
    /// the options below do not apply (their defaults hold).
    bool hierarchical = true;
    /// Tolerance on the coarse levels (l > 0); negative: `tolerance` × coarse_tolerance_factor.
    double coarse_tolerance = -1.0;
    /// The coarse levels stop at this multiple of the finest level's tolerance (of a session's
    /// per-solve one too), unless coarse_tolerance is set (it wins, also over a preset's factor).
    /// Below 1 the coarse levels, which are cheap, hand down a better converged start, and the
    /// finest level stops nearer a minimum (docs/solvers.md, "Presets").
    double coarse_tolerance_factor = 1.0;
    /// The level solver's energy_tolerance on the coarse levels (l > 0; local_global only); -1:
    /// the same as on the finest level. 0 stops the coarse levels by the displacement test alone.
    double coarse_energy_tolerance = -1.0;
    /// Solve every k-th level below the coarsest (1: all levels; Fig. 14 "every second level":
    /// 2). The finest and coarsest levels are always solved; skipped levels are only up-sampled.
    int level_step = 1;
    /// Solve only the coarsest and the finest level (Fig. 14 "coarse level only").
    bool coarsest_only = false;
    /// Fig. 15's approximation: up-sample the coarsest solution straight to the finest level
    /// and do one global solve there (no iterations on the finest level).
    bool coarse_approximation = false;
    /// Re-evaluate coarse constraint targets with the current rotations during each level.
    bool targets_follow_rotations = true;
    /// With targets_follow_rotations: keep a level's coarse targets fixed after this many
    /// iterations raised its energy (LevelSolveRequest::freeze_targets_after).
    int freeze_targets_after = 3;
    /// Set up (precompute and factor) the finer levels on another thread while the coarser ones
    /// are solved. The finest level's setup is mostly sequential (ordering, symbolic analysis)
    /// and longer than all coarse solves together, so this hides the coarse solves. Results are
    /// identical; the report's phase times then overlap (total < H + P + C + S). Needs ≥ 2
    /// threads (else off).
    bool overlap_setup = true;

    /// The `hierarchical` table: `inner` (a name in `level_solvers`), that level solver's
    /// options, then the hierarchy's.
    static Options FromConfig(OptionReader node, const Registry<LevelSolver>& level_solvers);
    /// A one-level run of level solver `inner` with its options from `node`.
    static Options OneLevel(OptionReader node, const Registry<LevelSolver>& level_solvers,
                            std::string_view inner);

    /// The levels a run solves, coarsest first, of a hierarchy of `num_levels` levels.
    std::vector<int> SolvedLevels(int num_levels) const;
    /// The request for level `level` of `num_levels` (limits and target handling).
    LevelSolveRequest Request(int level, int num_levels, bool start_from_rotations,
                              double diagonal) const;
  };

  explicit HierarchicalOptimizer(Options options) : options_(std::move(options)) {}

  OptimizeResult Optimize(const DeformationProblem& problem, const ComponentFactory& factory,
                          const Context& context) const override;
  /// The level solver's requirements on the energy (LevelSolver::CheckCompatible).
  void CheckComponents(const ComponentFactory& factory) const override;

  const Options& options() const { return options_; }

 private:
  Options options_;
};

/// Notes for the report about what constraint handling did (pinned components, isolated
/// vertices); shared by the optimizers and the session.
std::vector<std::string> DescribeConstraintHandling(const ConstraintReport& report);

}  // namespace harap
