// SPDX-License-Identifier: MIT
#pragma once

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "framework/config.h"
#include "framework/error.h"

namespace harap {

/// A component resolved from its options table: the parsed, validated options of one registry
/// entry and the way to build the implementation from them. Immutable once made, so Make() may be
/// called from several threads at once (the setup and solve threads of a run); it reads no
/// configuration.
template <class Interface>
class Recipe {
 public:
  using Maker = std::function<std::unique_ptr<Interface>()>;

  Recipe() = default;
  Recipe(std::string name, Maker maker) : name_(std::move(name)), maker_(std::move(maker)) {}

  /// A new instance configured with the resolved options.
  std::unique_ptr<Interface> Make() const {
    HARAP_CHECK(static_cast<bool>(maker_), "the recipe '{}' was never resolved", name_);
    return maker_();
  }
  /// The registry name the table resolved to.
  const std::string& name() const { return name_; }

 private:
  std::string name_;
  Maker maker_;
};

/// An open name → factory map for one interface (energy, linear solver, ...), filled by explicit
/// per-module registration functions (register_energies(...)) — no static initialization tricks.
///
/// An entry parses its options table once into a Recipe (Resolve): every option read with
/// OptionReader::Get, unknown keys rejected, values checked; the recipe then builds instances
/// without touching the configuration again.
///
///   Registry<Energy> energies("energy");
///   energies.Add<SpokesEnergy>("Spokes ARAP [Sorkine & Alexa 2007]");
///   Recipe<Energy> recipe = energies.Resolve(config.Child("energy"), "spokes_and_rims");
///   auto energy = recipe.Make();  // any thread, any number of times
template <class Interface>
class Registry {
 public:
  /// Parses and validates an implementation's options table (reads every option with
  /// OptionReader::Get and calls RejectUnknownKeys()) into a maker that builds it from the parsed
  /// options alone.
  using Resolver = std::function<typename Recipe<Interface>::Maker(OptionReader)>;

  struct Entry {
    std::string description;
    Resolver resolve;
  };

  explicit Registry(std::string kind) : kind_(std::move(kind)) {}

  /// Throws InternalError on a duplicate name.
  void Add(std::string name, std::string description, Resolver resolve) {
    HARAP_CHECK(!entries_.count(name), "{} '{}' registered twice", kind_, name);
    entries_.emplace(std::move(name), Entry{std::move(description), std::move(resolve)});
  }

  /// Registers an entry as its two halves: `parse(node)` reads and validates the options (once,
  /// when a run is resolved), `make(options)` builds an implementation from them (each time one
  /// is needed; the options are shared, read-only, by every instance made).
  template <class Parse, class Make>
  void Add(std::string name, std::string description, Parse parse, Make make) {
    Add(std::move(name), std::move(description),
        [parse = std::move(parse), make = std::move(make)](OptionReader node) ->
        typename Recipe<Interface>::Maker {
          auto options = std::make_shared<const std::decay_t<decltype(parse(node))>>(parse(node));
          return [options, make]() -> std::unique_ptr<Interface> { return make(*options); };
        });
  }

  /// Registers the implementation T, constructed from the options `parse(node)` returns, under
  /// `name` (for implementations registered under several names or parsed with extra arguments).
  template <class T, class Parse>
  void AddParsed(std::string name, std::string description, Parse parse) {
    static_assert(std::is_base_of_v<Interface, T>, "T must implement the registry's interface");
    Add(std::move(name), std::move(description), std::move(parse),
        [](const auto& options) -> std::unique_ptr<Interface> {
          return std::make_unique<T>(options);
        });
  }

  /// Registers the implementation T under T::kName: its options are read with
  /// T::Options::FromConfig(node) (which reads every option and rejects unknown keys) and T is
  /// constructed from them. The shape every implementation shares, written once.
  template <class T>
  void Add(std::string description) {
    static_assert(std::is_base_of_v<Interface, T>, "T must implement the registry's interface");
    AddParsed<T>(std::string(T::kName), std::move(description),
                 [](OptionReader node) { return T::Options::FromConfig(node); });
  }

  bool Contains(std::string_view name) const { return entries_.count(std::string(name)) > 0; }

  /// Resolves `name` with the options in `options` (a table without a `type` key, or whose
  /// `type` key is ignored). Unknown names throw ConfigError listing the valid ones; bad options
  /// throw the entry's ConfigError naming the key.
  Recipe<Interface> Resolve(std::string_view name, OptionReader options) const {
    return Recipe<Interface>(std::string(name), Find(name, options.table()).resolve(options));
  }

  /// Resolves the implementation named by the `type` key of `table` (`default_name` if absent).
  Recipe<Interface> Resolve(OptionReader table, std::string_view default_name) const {
    std::string name =
        table.Get("type", std::string(default_name), fmt::format("which {} to use", kind_));
    return Resolve(name, table);
  }

  /// Resolve(...).Make() in one call, for a component made once.
  std::unique_ptr<Interface> Create(std::string_view name, OptionReader options) const {
    return Resolve(name, std::move(options)).Make();
  }
  std::unique_ptr<Interface> Create(OptionReader table, std::string_view default_name) const {
    return Resolve(std::move(table), default_name).Make();
  }
  /// The same for a table read on its own, with a record of its own (an options table built in
  /// code, a test's).
  Recipe<Interface> Resolve(const ConfigNode& table, std::string_view default_name) const {
    return Resolve(OptionReader(table), default_name);
  }
  std::unique_ptr<Interface> Create(std::string_view name, const ConfigNode& options) const {
    return Create(name, OptionReader(options));
  }
  std::unique_ptr<Interface> Create(const ConfigNode& table, std::string_view default_name) const {
    return Create(OptionReader(table), default_name);
  }

  /// Sorted names: drives `harap list`, the docs and the conformance tests.
  std::vector<std::string> Names() const {
    std::vector<std::string> names;
    for (const auto& [name, entry] : entries_) names.push_back(name);
    return names;
  }

  const std::string& Description(std::string_view name) const {
    return Find(name, ConfigNode()).description;
  }

  /// The options `name` reads, with defaults and help (resolved on a describing reader).
  std::vector<OptionInfo> DescribeOptions(std::string_view name) const {
    OptionReader node = OptionReader::Describing();
    Find(name, node.table()).resolve(node);
    return node.Options();
  }

  const std::string& kind() const { return kind_; }

 private:
  const Entry& Find(std::string_view name, const ConfigNode& where) const {
    auto it = entries_.find(std::string(name));
    if (it == entries_.end()) {
      std::string location = where.Has("type") ? where.Where("type") + ": " : std::string();
      throw ConfigError(fmt::format("{}unknown {} '{}'; valid names: {}", location, kind_, name,
                                    fmt::join(Names(), ", ")));
    }
    return it->second;
  }

  std::string kind_;
  std::map<std::string, Entry, std::less<>> entries_;
};

}  // namespace harap
