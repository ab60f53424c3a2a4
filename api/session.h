// SPDX-License-Identifier: MIT
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "api/component_factory.h"
#include "api/deform.h"
#include "framework/config.h"
#include "framework/mesh.h"
#include "framework/registries.h"
#include "io/mesh_repair.h"
#include "solvers/optimizers/deformation_session.h"

namespace harap {

/// A DeformationSession together with everything it refers to: the registries, the run config,
/// the mesh (checked like `harap deform`'s) and the component factory. Neither copyable nor
/// movable (the session points into it); hold it by the unique_ptr MakeSession returns.
class ConfiguredSession {
 public:
  /// `stiffness`: per-element factors of `mesh` (framework/stiffness.h; empty: 1 everywhere).
  ConfiguredSession(const Registries& registries, const Mesh& mesh, const ConfigNode& run_config,
                    int threads, const SessionOptions::FrameStart* frame_start = nullptr,
                    const std::vector<double>& stiffness = {});
  ConfiguredSession(const ConfiguredSession&) = delete;
  ConfiguredSession& operator=(const ConfiguredSession&) = delete;

  DeformationSession& session() { return *session_; }
  const DeformationSession& session() const { return *session_; }
  /// The mesh the session solves (the input's vertices; duplicate elements dropped if the
  /// `[mesh]` table asks for it).
  const Mesh& mesh() const { return mesh_; }
  /// The mesh's checks at construction, made without handles (every component "without a
  /// handle"); MeshChecksFor() counts a handle set's.
  const MeshCheckReport& mesh_checks() const { return mesh_checks_; }
  /// One line per mesh finding (PreparedProblem::Summary).
  const std::vector<std::string>& mesh_summary() const { return mesh_summary_; }
  /// mesh_checks() with each component's `constrained_vertices` and
  /// `components_without_constraints` counted for `handles` (valid vertex indices), as
  /// CheckMesh would count them, without checking the mesh again.
  MeshCheckReport MeshChecksFor(const std::vector<Index>& handles) const;

  // The registry names the run config resolved to.
  const std::string& optimizer() const { return optimizer_; }
  std::string energy_name() const { return factory_->energy_name(); }
  std::string solver_name() const { return factory_->solver_name(); }
  std::string resolved_config() const { return config_.ToToml(); }
  int threads() const { return threads_; }
  /// The factory that made the session's pieces (which hierarchy, upsampler and per-level
  /// solvers the session uses).
  const RegistryComponentFactory& factory() const { return *factory_; }

 private:
  Registries registries_;
  ConfigNode config_;
  Mesh mesh_;
  MeshCheckReport mesh_checks_;
  std::vector<std::string> mesh_summary_;
  std::vector<Index> vertex_component_;  ///< index into mesh_checks_.components; -1: isolated
  std::unique_ptr<RegistryComponentFactory> factory_;
  std::string optimizer_;
  int threads_ = 0;
  std::unique_ptr<DeformationSession> session_;
};

/// Builds a session from the same run configuration as `harap deform` (tables `optimizer`
/// (classic or hierarchical), `energy`, `solver`, `hierarchy`, `upsampler`, `mesh`; the same
/// defaults, e.g. the per-element energy for tetrahedral and planar meshes). `threads` 0: all
/// hardware threads. The mesh is checked like `harap deform`'s; a mesh whose repair would weld
/// vertices (and so renumber them) is refused with InputError. The hierarchy and every level's
/// precomputation are done here; call SetHandles() next. `stiffness`: per-element factors of
/// `mesh` (framework/stiffness.h; empty: 1 everywhere), e.g. a scenario's ElementStiffness().
std::unique_ptr<ConfiguredSession> MakeSession(
    const Registries& registries, const Mesh& mesh, const ConfigNode& run_config, int threads,
    SessionOptions::FrameStart frame_start = SessionOptions::FrameStart::kCorrected,
    const std::vector<double>& stiffness = {});

/// "full", "numeric", "update" or "partial" (how a handle edit refactored a level).
std::string_view RefactorRouteName(LinearSolver::RefactorRoute route);

/// A session's Solve() or Preview() result as a DeformOutcome, so that DeformReportJson gives it
/// the keys of `harap deform --report` (docs/report.md) where they apply: the pieces the session
/// resolved, each level's solver, the mesh checks of its construction, the run warnings.
/// `scenario` holds the session's mesh and its current handles (one group); `trace` the solve's
/// iterations.
DeformOutcome SessionOutcome(const ConfiguredSession& session, const Scenario& scenario,
                             OptimizeResult result, std::vector<TraceEntry> trace);

/// A handle edit as JSON: {"seconds", "levels": [{"level", "constrained_vertices",
/// "changed_rows", "factored", "route", "seconds"}] (finest first), "constraints":
/// {"constrained_vertices", "isolated_vertices", "free_components",
/// "vertices_in_free_components"}, "notes"}. `route` is "none" on a level the edit left alone.
std::string HandleEditJson(const HandleEditResult& edit);

}  // namespace harap
