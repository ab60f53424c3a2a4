// SPDX-License-Identifier: MIT
#include "api/component_factory.h"

#include <limits>
#include <map>
#include <mutex>

namespace harap {

namespace {

constexpr std::string_view kSmallSystems = "small_systems";

// Reads the size limit of a `[solver.small_systems]` table (0 if the table is absent).
Index SmallSystemsLimit(OptionReader table) {
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

namespace {

// Resolves `key`'s table of `root`. Without such a table, a default the registry lacks (a
// registry built for a test or an embedding) is an error only if a run asks for the piece.
template <class Interface>
Recipe<Interface> ResolvePiece(const Registry<Interface>& registry, OptionReader& root,
                               std::string_view key, const std::string& default_name) {
  OptionReader table = root.Child(key);
  if (root.Has(key) || registry.Contains(default_name)) {
    return registry.Resolve(table, default_name);
  }
  const std::string problem = fmt::format("unknown {} '{}'; valid names: {}", registry.kind(),
                                          default_name, fmt::join(registry.Names(), ", "));
  return Recipe<Interface>(
      default_name, [problem]() -> std::unique_ptr<Interface> { throw ConfigError(problem); });
}

}  // namespace

RegistryComponentFactory::RegistryComponentFactory(const Registries& registries,
                                                   const ConfigNode& root,
                                                   DefaultComponents defaults)
    : defaults_(std::move(defaults)), choices_(std::make_shared<Choices>()) {
  // The pieces' tables only: the root's other keys are ValidateRunConfig's.
  OptionReader reader(root);
  energy_ = registries.energies.Resolve(reader.Child("energy"), defaults_.energy);
  OptionReader solver = reader.Child("solver");
  // The sub-tables first: reading them marks them as known to [solver]'s unknown-key check.
  OptionReader small = solver.Child(kSmallSystems);
  if (solver.Has(kSmallSystems)) {
    small_systems_limit_ = SmallSystemsLimit(small);
    if (small_systems_limit_ == 0) {
      throw ConfigError(fmt::format("{}: [solver.small_systems] needs max_unknowns > 0",
                                    small.Where("max_unknowns")));
    }
    small_systems_ = ResolveSolverTable(registries, small);
  }
  for (int level : LevelTables(solver.table())) {
    level_tables_[level] = ResolveSolverTable(registries, solver.Child(LevelTableKey(level)));
  }
  solver_ = ResolveSolverTable(registries, solver);
  hierarchy_ = ResolvePiece(registries.hierarchies, reader, "hierarchy", defaults_.hierarchy);
  upsampler_ = ResolvePiece(registries.upsamplers, reader, "upsampler", defaults_.upsampler);
}

RegistryComponentFactory::SolverTable RegistryComponentFactory::ResolveSolverTable(
    const Registries& registries, OptionReader table) const {
  SolverTable resolved;
  resolved.recipe = registries.linear_solvers.Resolve(table, defaults_.solver);
  // Creating a solver is cheap (no factorization); it knows whether it is direct.
  resolved.direct = resolved.recipe.Make()->is_direct();
  return resolved;
}

std::unique_ptr<Energy> RegistryComponentFactory::MakeEnergy() const { return energy_.Make(); }

const RegistryComponentFactory::SolverTable& RegistryComponentFactory::SolverTableFor(
    int level, Index num_unknowns) const {
  const auto own = level_tables_.find(level);
  if (own != level_tables_.end()) return own->second;
  if (small_systems_limit_ > 0 && num_unknowns <= small_systems_limit_) return small_systems_;
  return solver_;
}

std::unique_ptr<LinearSolver> RegistryComponentFactory::MakeLinearSolver(int level,
                                                                         Index num_unknowns) const {
  std::unique_ptr<LinearSolver> solver = SolverTableFor(level, num_unknowns).recipe.Make();
  solver->set_on_choice([choices = choices_, level](std::string_view used, bool direct) {
    const std::lock_guard lock(choices->mutex);
    choices->used[level] = std::string(used);
    choices->direct[level] = direct;
  });
  return solver;
}

std::unique_ptr<Hierarchy> RegistryComponentFactory::MakeHierarchy() const {
  made_hierarchy_ = true;
  return hierarchy_.Make();
}

std::unique_ptr<Upsampler> RegistryComponentFactory::MakeUpsampler() const {
  made_upsampler_ = true;
  return upsampler_.Make();
}

const std::string& RegistryComponentFactory::solver_name_for(Index num_unknowns) const {
  return SolverTableFor(-1, num_unknowns).recipe.name();
}
const std::string& RegistryComponentFactory::solver_name_for(int level, Index num_unknowns) const {
  return SolverTableFor(level, num_unknowns).recipe.name();
}
std::string RegistryComponentFactory::solver_used(int level, Index num_unknowns) const {
  const std::string& name = solver_name_for(level, num_unknowns);
  const std::lock_guard lock(choices_->mutex);
  const auto it = choices_->used.find(level);
  return it == choices_->used.end() ? name : fmt::format("{}:{}", name, it->second);
}
bool RegistryComponentFactory::solver_direct(int level, Index num_unknowns) const {
  const std::lock_guard lock(choices_->mutex);
  const auto it = choices_->direct.find(level);
  return it != choices_->direct.end() ? it->second : SolverTableFor(level, num_unknowns).direct;
}

std::unique_ptr<Optimizer> MakeOptimizer(const Registries& registries, const ConfigNode& root,
                                         const DefaultComponents& defaults) {
  return registries.optimizers.Create(OptionReader(root).Child("optimizer"), defaults.optimizer);
}

std::vector<OptionInfo> DescribeSmallSystemsOptions() {
  OptionReader node = OptionReader::Describing();
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
      optimizer_recipe(registries.optimizers.Resolve(OptionReader(config).Child("optimizer"),
                                                     defaults.optimizer)),
      optimizer_name(optimizer_recipe.name()),
      optimizer(optimizer_recipe.Make()),
      factory(registries, config, defaults) {
  optimizer->CheckComponents(factory);
}

void ValidateRunConfig(const ConfigNode& root, std::initializer_list<const char*> command_tables) {
  OptionReader reader(root);
  for (const char* table : {"optimizer", "energy", "solver", "hierarchy", "upsampler"}) {
    reader.Child(table);
  }
  for (const char* table : command_tables) reader.Child(table);
  reader.RejectUnknownKeys();
}

}  // namespace harap
