// SPDX-License-Identifier: MIT
#include "api/library.h"

#include <fmt/format.h>

#include "api/component_factory.h"
#include "framework/error.h"
#include "io/builtin_meshes.h"
#include "io/mesh_repair.h"
#include "solvers/optimizers/registration.h"
#ifdef HARAP_HAVE_CHOLMOD
#include "solvers/linear/cholmod_solver.h"
#endif

namespace harap {

namespace {

template <class Interface>
void Describe(const Registry<Interface>& registry, std::vector<ComponentDescription>& out) {
  for (const auto& name : registry.Names()) {
    ComponentDescription description{registry.kind(), name, registry.Description(name), {}};
    for (auto& option : registry.DescribeOptions(name)) {
      if (option.key != "type") description.options.push_back(std::move(option));
    }
    out.push_back(std::move(description));
  }
}

// Accepts only the tables named in `tables` at the top level of `config`.
void RejectOtherTables(const ConfigNode& config, std::initializer_list<const char*> tables) {
  OptionReader reader(config);
  for (const char* table : tables) reader.Child(table);
  reader.RejectUnknownKeys();
}

}  // namespace

ComponentCatalog DescribeComponents(const Registries& registries) {
  ComponentCatalog catalog;
  Describe(registries.optimizers, catalog.components);
  Describe(registries.level_solvers, catalog.components);
  Describe(registries.energies, catalog.components);
  Describe(registries.linear_solvers, catalog.components);
  Describe(registries.hierarchies, catalog.components);
  Describe(registries.upsamplers, catalog.components);
  catalog.small_systems_options = DescribeSmallSystemsOptions();
  const OptionReader mesh = OptionReader::Describing();
  MeshRepairOptions::FromConfig(mesh);
  catalog.mesh_options = mesh.Options();
  const OptionReader registration = OptionReader::Describing();
  RegistrationOptions::FromConfig(registration);
  catalog.registration_options = registration.Options();
  catalog.builtin_meshes = BuiltinMeshNames();
  return catalog;
}

MeshHierarchy BuildHierarchy(const Registries& registries, const Mesh& mesh,
                             const ConfigNode& config, int threads) {
  RejectOtherTables(config, {"hierarchy"});
  ValidateMesh(mesh, "hierarchy input");
  const auto hierarchy =
      registries.hierarchies.Create(OptionReader(config.Child("hierarchy")), "octree");
  const Context context = Context::WithThreads(threads);
  return context.Run([&] { return hierarchy->Build(mesh, context); });
}

EnergyEvaluation EvaluateEnergy(const Registries& registries, const Mesh& rest, const Positions& u,
                                const ConfigNode& config, int threads) {
  RejectOtherTables(config, {"energy"});
  const OptionReader table(config.Child("energy"));
  if (!table.Has("type")) throw ConfigError("energy: no energy named (its `type`)");
  auto energy = registries.energies.Create(table, "");
  ValidateMesh(rest, "energy rest mesh");
  if (u.rows() != rest.num_vertices()) {
    throw InputError(fmt::format("energy: the positions have {} rows, the rest mesh {} vertices",
                                 u.rows(), rest.num_vertices()));
  }
  for (Index v = 0; v < u.rows(); ++v) {
    if (!u.row(v).allFinite()) {
      throw InputError(fmt::format("energy: position of vertex {} is not finite ({}, {}, {})", v,
                                   u(v, 0), u(v, 1), u(v, 2)));
    }
  }
  const Context context = Context::WithThreads(threads);
  EnergyEvaluation result;
  context.Run([&] {
    energy->Precompute(rest, context);
    result.rotations.assign(energy->num_rotations(), Rotation::Identity());
    result.value = energy->FitRotations(u, result.rotations, context);
    Positions rhs(u.rows(), 3);
    energy->AssembleRhs(result.rotations, rhs, context);
    result.gradient = 2.0 * (energy->system_matrix() * u - rhs);
  });
  result.per_element = energy->rotation_site() == RotationSite::kElement;
  return result;
}

void StopIdleNativeThreads() {
#ifdef HARAP_HAVE_CHOLMOD
  CholmodSolver::StopIdleNativeThreads();
#endif
}

}  // namespace harap
