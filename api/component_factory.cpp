// SPDX-License-Identifier: MIT
#include "api/component_factory.h"

#include <limits>
#include <map>
#include <mutex>

#ifdef HARAP_HAVE_CHOLMOD
#include "solvers/linear/adaptive_solver.h"
#endif

namespace harap {

namespace {

std::string TypeOf(const ConfigNode& table, const std::string& default_name,
                   const std::string& kind) {
  return table.Get("type", default_name, fmt::format("which {} to use", kind));
}

constexpr std::string_view kSmallSystems = "small_systems";

// Reads the size limit of a `[solver.small_systems]` table (0 if the table is absent).
Index SmallSystemsLimit(const ConfigNode& table) {
  const int limit = table.Get("max_unknowns", 0,
                              "reduced systems with at most this many unknowns (free vertices) "
                              "use this table's solver, larger ones [solver]'s; 0: none",
                              Range::AtLeast(0));
  return limit;
}

// `[solver.level_<l>]`: the level's own solver table.
std::string LevelTableKey(int level) { return fmt::format("level_{}", level); }

// The levels `[solver]` has tables for (keys level_<digits>); other keys are left to the solver.
std::vector<int> LevelTables(const ConfigNode& solver) {
  std::vector<int> levels;
  for (const std::string& key : solver.Keys()) {
    if (key.rfind("level_", 0) != 0 || key.size() == 6) continue;
    const std::string digits = key.substr(6);
    if (digits.find_first_not_of("0123456789") != std::string::npos || digits.size() > 6) {
      throw ConfigError(
          fmt::format("{}: a level table is named level_<l> with l = 0, 1, ... "
                      "(0 = the input mesh)",
                      solver.Where(key)));
    }
    levels.push_back(std::stoi(digits));
  }
  return levels;
}

}  // namespace

struct RegistryComponentFactory::Choices {
  std::mutex mutex;
  std::map<int, std::string> used;  // level → "cholmod" / "cg"
  std::map<int, bool> direct;
};

RegistryComponentFactory::RegistryComponentFactory(const Registries& registries,
                                                   const ConfigNode& root,
                                                   DefaultComponents defaults)
    : registries_(registries),
      root_(root),
      defaults_(std::move(defaults)),
      choices_(std::make_shared<Choices>()) {
  MakeEnergy();
  // Both solver tables are validated now (the small-system one only if present).
  const ConfigNode solver = root_.Child("solver");
  if (solver.Has(kSmallSystems)) {
    const ConfigNode small = solver.Child(kSmallSystems);
    if (SmallSystemsLimit(small) == 0) {
      throw ConfigError(fmt::format("{}: [solver.small_systems] needs max_unknowns > 0",
                                    small.Where("max_unknowns")));
    }
    registries_.linear_solvers.Create(small, defaults_.solver);
  }
  for (int level : LevelTables(solver)) {
    registries_.linear_solvers.Create(solver.Child(LevelTableKey(level)), defaults_.solver);
  }
  registries_.linear_solvers.Create(SolverTableFor(-1, std::numeric_limits<Index>::max()),
                                    defaults_.solver);
  if (root_.Has("hierarchy")) MakeHierarchy();
  if (root_.Has("upsampler")) MakeUpsampler();
  made_hierarchy_ = made_upsampler_ = false;
}

std::unique_ptr<Energy> RegistryComponentFactory::MakeEnergy() const {
  return registries_.energies.Create(root_.Child("energy"), defaults_.energy);
}

ConfigNode RegistryComponentFactory::SolverTableFor(int level, Index num_unknowns) const {
  const ConfigNode solver = root_.Child("solver");
  // Reading the sub-tables also marks them as known to [solver]'s unknown-key check.
  for (int table_level : LevelTables(solver)) {
    const ConfigNode table = solver.Child(LevelTableKey(table_level));
    if (table_level == level) return table;
  }
  const ConfigNode small = solver.Child(kSmallSystems);
  if (solver.Has(kSmallSystems) && num_unknowns <= SmallSystemsLimit(small)) return small;
  return solver;
}

std::unique_ptr<LinearSolver> RegistryComponentFactory::MakeLinearSolver(int level,
                                                                         Index num_unknowns) const {
  std::unique_ptr<LinearSolver> solver =
      registries_.linear_solvers.Create(SolverTableFor(level, num_unknowns), defaults_.solver);
#ifdef HARAP_HAVE_CHOLMOD
  if (auto* adaptive = dynamic_cast<AdaptiveSolver*>(solver.get())) {
    adaptive->set_on_choice([choices = choices_, level](std::string_view used, bool direct) {
      const std::lock_guard lock(choices->mutex);
      choices->used[level] = std::string(used);
      choices->direct[level] = direct;
    });
  }
#endif
  return solver;
}

std::unique_ptr<Hierarchy> RegistryComponentFactory::MakeHierarchy() const {
  made_hierarchy_ = true;
  return registries_.hierarchies.Create(root_.Child("hierarchy"), defaults_.hierarchy);
}

std::unique_ptr<Upsampler> RegistryComponentFactory::MakeUpsampler() const {
  made_upsampler_ = true;
  return registries_.upsamplers.Create(root_.Child("upsampler"), defaults_.upsampler);
}

std::string RegistryComponentFactory::energy_name() const {
  return TypeOf(root_.Child("energy"), defaults_.energy, "energy");
}
std::string RegistryComponentFactory::solver_name() const {
  return TypeOf(root_.Child("solver"), defaults_.solver, "solver");
}
std::string RegistryComponentFactory::solver_name_for(Index num_unknowns) const {
  return TypeOf(SolverTableFor(-1, num_unknowns), defaults_.solver, "solver");
}
std::string RegistryComponentFactory::solver_name_for(int level, Index num_unknowns) const {
  return TypeOf(SolverTableFor(level, num_unknowns), defaults_.solver, "solver");
}
std::string RegistryComponentFactory::solver_used(int level, Index num_unknowns) const {
  const std::string name = solver_name_for(level, num_unknowns);
  const std::lock_guard lock(choices_->mutex);
  const auto it = choices_->used.find(level);
  return it == choices_->used.end() ? name : fmt::format("{}:{}", name, it->second);
}
bool RegistryComponentFactory::solver_direct(int level, Index num_unknowns) const {
  {
    const std::lock_guard lock(choices_->mutex);
    const auto it = choices_->direct.find(level);
    if (it != choices_->direct.end()) return it->second;
  }
  // Creating a solver is cheap (no factorization); it knows whether it is direct.
  return registries_.linear_solvers.Create(SolverTableFor(level, num_unknowns), defaults_.solver)
      ->is_direct();
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

std::vector<OptionInfo> DescribeSmallSystemsOptions() {
  const ConfigNode node = ConfigNode::Describing();
  SmallSystemsLimit(node);
  node.Get("type", DefaultComponents{}.solver,
           "the solver for the small systems (its own options go in the same table)");
  return node.Options();
}

DefaultComponents DefaultComponentsFor(const Registries& registries, const Mesh& mesh) {
  DefaultComponents defaults;
  if (!registries.linear_solvers.Contains(defaults.solver)) defaults.solver = "eigen_ldlt";
  if (mesh.kind() == ElementKind::kTetrahedron || mesh.planar) defaults.energy = "elements";
  return defaults;
}

namespace {

// Validates `config` before anything reads it (the first member initializer).
DefaultComponents ValidatedDefaults(const Registries& registries, const ConfigNode& config,
                                    const Mesh& mesh) {
  ValidateRunConfig(config);
  return DefaultComponentsFor(registries, mesh);
}

}  // namespace

ResolvedRunConfig::ResolvedRunConfig(const Registries& registries, const ConfigNode& config,
                                     const Mesh& mesh)
    : defaults(ValidatedDefaults(registries, config, mesh)),
      optimizer_name(TypeOf(config.Child("optimizer"), defaults.optimizer, "optimizer")),
      optimizer(registries.optimizers.Create(optimizer_name, config.Child("optimizer"))),
      factory(registries, config, defaults) {}

void ValidateRunConfig(const ConfigNode& root) {
  for (const char* table : {"optimizer", "energy", "solver", "hierarchy", "upsampler", "mesh"}) {
    root.Child(table);
  }
  root.RejectUnknownKeys();
}

}  // namespace harap
