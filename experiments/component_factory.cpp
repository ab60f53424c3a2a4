// SPDX-License-Identifier: MIT
#include "experiments/component_factory.h"

namespace harap {

namespace {

std::string TypeOf(const ConfigNode& table, const std::string& default_name,
                   const std::string& kind) {
  return table.Get("type", default_name, fmt::format("which {} to use", kind));
}

}  // namespace

RegistryComponentFactory::RegistryComponentFactory(const Registries& registries,
                                                   const ConfigNode& root,
                                                   DefaultComponents defaults)
    : registries_(registries), root_(root), defaults_(std::move(defaults)) {
  MakeEnergy();
  registries_.linear_solvers.Create(root_.Child("solver"), defaults_.solver);
  if (root_.Has("hierarchy")) MakeHierarchy();
  if (root_.Has("upsampler")) MakeUpsampler();
}

std::unique_ptr<Energy> RegistryComponentFactory::MakeEnergy() const {
  return registries_.energies.Create(root_.Child("energy"), defaults_.energy);
}

std::unique_ptr<LinearSolver> RegistryComponentFactory::MakeLinearSolver(int, Index) const {
  return registries_.linear_solvers.Create(root_.Child("solver"), defaults_.solver);
}

std::unique_ptr<Hierarchy> RegistryComponentFactory::MakeHierarchy() const {
  return registries_.hierarchies.Create(root_.Child("hierarchy"), defaults_.hierarchy);
}

std::unique_ptr<Upsampler> RegistryComponentFactory::MakeUpsampler() const {
  return registries_.upsamplers.Create(root_.Child("upsampler"), defaults_.upsampler);
}

std::string RegistryComponentFactory::energy_name() const {
  return TypeOf(root_.Child("energy"), defaults_.energy, "energy");
}
std::string RegistryComponentFactory::solver_name() const {
  return TypeOf(root_.Child("solver"), defaults_.solver, "solver");
}
std::string RegistryComponentFactory::hierarchy_name() const {
  return TypeOf(root_.Child("hierarchy"), defaults_.hierarchy, "hierarchy");
}
std::string RegistryComponentFactory::upsampler_name() const {
  return TypeOf(root_.Child("upsampler"), defaults_.upsampler, "upsampler");
}

std::unique_ptr<Optimizer> MakeOptimizer(const Registries& registries, const ConfigNode& root,
                                         const DefaultComponents& defaults) {
  return registries.optimizers.Create(root.Child("optimizer"), defaults.optimizer);
}

void ValidateRunConfig(const ConfigNode& root) {
  for (const char* table : {"optimizer", "energy", "solver", "hierarchy", "upsampler", "mesh"}) {
    root.Child(table);
  }
  root.RejectUnknownKeys();
}

}  // namespace harap
