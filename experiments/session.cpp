// SPDX-License-Identifier: MIT
#include "experiments/session.h"

#include <thread>

#include "framework/error.h"

namespace harap {

ConfiguredSession::ConfiguredSession(const Registries& registries, const Mesh& mesh,
                                     const ConfigNode& run_config, int threads,
                                     const SessionOptions::FrameStart* frame_start)
    : registries_(registries), config_(run_config) {
  ValidateRunConfig(config_);
  const MeshRepairOptions mesh_options = MeshRepairOptions::FromConfig(config_.Child("mesh"));
  // The defaults of `harap deform` (RunDeform).
  DefaultComponents defaults;
  if (!registries_.linear_solvers.Contains(defaults.solver)) defaults.solver = "eigen_ldlt";
  if (mesh.kind() == ElementKind::kTetrahedron || mesh.planar) defaults.energy = "elements";
  const ConfigNode optimizer_node = config_.Child("optimizer");
  optimizer_ = optimizer_node.Get("type", defaults.optimizer, "which optimizer");
  SessionOptions options = SessionOptions::FromConfig(optimizer_node);
  if (frame_start) options.frame_start = *frame_start;
  factory_ = std::make_unique<RegistryComponentFactory>(registries_, config_, defaults);
  threads_ = threads > 0 ? threads : static_cast<int>(std::thread::hardware_concurrency());

  const Context context = Context::WithThreads(threads);
  DeformationProblem problem;
  problem.mesh = &mesh;
  problem.constraints.targets.resize(0, 3);
  const auto prepared =
      context.Run([&] { return std::make_unique<const PreparedProblem>(problem, mesh_options); });
  mesh_checks_ = prepared->checks();
  mesh_summary_ = prepared->Summary();
  const Mesh& solved = *prepared->problem().mesh;
  if (solved.num_vertices() != mesh.num_vertices()) {
    // Handles and positions of a session are per input vertex; welding renumbers them.
    throw InputError(fmt::format(
        "the mesh repair welds {} vertices into {}; a session works on the input's vertices: "
        "set [mesh] weld_duplicates = false, or weld the mesh file first",
        mesh.num_vertices(), solved.num_vertices()));
  }
  mesh_ = solved;
  session_ = std::make_unique<DeformationSession>(mesh_, *factory_, options, context);
}

std::unique_ptr<ConfiguredSession> MakeSession(const Registries& registries, const Mesh& mesh,
                                               const ConfigNode& run_config, int threads,
                                               SessionOptions::FrameStart frame_start) {
  return std::make_unique<ConfiguredSession>(registries, mesh, run_config, threads, &frame_start);
}

}  // namespace harap
