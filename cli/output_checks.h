// SPDX-License-Identifier: MIT
// Checks on a command's file arguments that run before any long work, so a wrong name fails in
// a second instead of after the solve.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

namespace harap {

/// Throws InputError (naming `option` and the file) unless `file` can be written: its folder
/// exists and the file can be opened for writing without losing its contents. A file this
/// creates to find out is removed again, so a failed run leaves no empty files behind.
void CheckWritable(const std::filesystem::path& file, std::string_view option);

/// Whether `file`'s name is that of a mesh file (.obj .ply .off .stl .node .ele .mesh,
/// optionally .xz) rather than a scenario.
bool LooksLikeMeshFile(const std::filesystem::path& file);

/// Throws InputError when `file` is a mesh file given where a scenario is expected, with a
/// scenario for it to start from (instead of the TOML parser's syntax error), or an experiment
/// config (RefuseConfigAsScenario).
void RefuseMeshAsScenario(const std::filesystem::path& file);

/// Throws InputError when `file` is an experiment config (top-level [scenarios] or [[variant]],
/// no mesh) given where a scenario is expected, naming `harap run` (instead of "unknown key").
void RefuseConfigAsScenario(const std::filesystem::path& file);

/// Throws InputError when `file` is a scenario (top-level mesh or [[handle]], no [scenarios])
/// given to `harap run`, with a config that runs it and the `harap deform` command.
void RefuseScenarioAsConfig(const std::filesystem::path& file);

/// What `--config` takes, for RefuseMeshAsToml.
inline constexpr std::string_view kConfigFileKinds =
    "a TOML file of options ([optimizer], [energy], [solver], [hierarchy], [upsampler] tables, "
    "the keys `harap list` shows)";

/// Throws InputError when `file` is a mesh file given to `option` (e.g. "harap run",
/// "--config"), which takes a TOML file of the kind `expected` describes, naming what goes where
/// (instead of the TOML parser's syntax error).
void RefuseMeshAsToml(const std::filesystem::path& file, std::string_view option,
                      std::string_view expected);

/// The progress label for loading the scenario `file`: what LoadScenario will do, read from the
/// scenario's top-level keys (a built-in mesh is built, a surface tetrahedralized, `refine`
/// subdivides), e.g. "reading the scenario, tetrahedralizing its mesh (TetGen)". A file that
/// cannot be parsed gets the plain label (LoadScenario reports the error).
std::string ScenarioLoadingPhase(const std::filesystem::path& file);

}  // namespace harap
