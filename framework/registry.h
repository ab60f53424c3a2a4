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

/// An open name → factory map for one interface (energy, linear solver, ...), filled by explicit
/// per-module registration functions (register_energies(...)) — no static initialization tricks.
///
///   Registry<Energy> energies("energy");
///   energies.Add<SpokesEnergy>("Spokes ARAP [Sorkine & Alexa 2007]");
///   auto energy = energies.Create(config.Child("energy"), "spokes_and_rims");
template <class Interface>
class Registry {
 public:
  /// Builds an implementation from its options table; reads every option with ConfigNode::Get
  /// and calls RejectUnknownKeys().
  using Factory = std::function<std::unique_ptr<Interface>(const ConfigNode&)>;

  struct Entry {
    std::string description;
    Factory factory;
  };

  explicit Registry(std::string kind) : kind_(std::move(kind)) {}

  /// Throws InternalError on a duplicate name.
  void Add(std::string name, std::string description, Factory factory) {
    HARAP_CHECK(!entries_.count(name), "{} '{}' registered twice", kind_, name);
    entries_.emplace(std::move(name), Entry{std::move(description), std::move(factory)});
  }

  /// Registers the implementation T under T::kName: its factory reads T::Options with
  /// T::Options::FromConfig(node) (which reads every option and rejects unknown keys) and
  /// constructs T from them. The shape every implementation shares, written once.
  template <class T>
  void Add(std::string description) {
    static_assert(std::is_base_of_v<Interface, T>, "T must implement the registry's interface");
    Add(std::string(T::kName), std::move(description),
        [](const ConfigNode& node) -> std::unique_ptr<Interface> {
          return std::make_unique<T>(T::Options::FromConfig(node));
        });
  }

  bool Contains(std::string_view name) const { return entries_.count(std::string(name)) > 0; }

  /// Creates `name` with the options in `options` (a table without a `type` key, or whose
  /// `type` key is ignored). Unknown names throw ConfigError listing the valid ones.
  std::unique_ptr<Interface> Create(std::string_view name, const ConfigNode& options) const {
    return Find(name, options).factory(options);
  }

  /// Creates the implementation named by the `type` key of `table` (`default_name` if absent).
  std::unique_ptr<Interface> Create(const ConfigNode& table, std::string_view default_name) const {
    std::string name =
        table.Get("type", std::string(default_name), fmt::format("which {} to use", kind_));
    return Create(name, table);
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

  /// The options `name` reads, with defaults and help (created on a describing node).
  std::vector<OptionInfo> DescribeOptions(std::string_view name) const {
    ConfigNode node = ConfigNode::Describing();
    Find(name, node).factory(node);
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
