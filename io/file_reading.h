// SPDX-License-Identifier: MIT
// Whole-file reading with xz-compressed files (`name.xz`) decompressed in memory, for every
// reader of harap::io (meshes, scenarios and the files they name).
#pragma once

#include <fmt/format.h>

#include <filesystem>
#include <string>
#include <string_view>
#include <system_error>
#include <type_traits>

#include "framework/error.h"

namespace harap {

/// A file name's format: its extension in lower case without the dot ("obj", "ply"; "" if
/// none), looking through a trailing ".xz" (`xz` says whether there was one).
struct FileFormat {
  std::string extension;
  bool xz = false;
};
FileFormat DetectFormat(const std::filesystem::path& file);

/// Reads the whole file, decompressing it in memory when the name ends in `.xz`
/// (case-insensitive). Throws InputError naming the file when it is missing, a directory, a
/// device or socket, unreadable, or not valid xz data.
std::string ReadFileMaybeXz(const std::filesystem::path& file);

/// Decompresses xz data held in memory (several concatenated streams allowed, as `xz` writes
/// them). `what` names the data in the InputError for corrupt, truncated or non-xz data; a
/// header asking for more than 512 MiB of decoder memory is treated as corrupt.
std::string DecompressXz(std::string_view compressed, const std::string& what);

/// `read(path)` of a file that another file names, e.g. a scenario's `mesh = "x.obj"`: `where`
/// is where it is named ("scene.toml:3:8") and `what` the key ("mesh"). A missing file is an
/// InputError "<where>: <what> file <path> not found"; the InputErrors of `read` are prefixed by
/// "<where>: <what>: ", so the message leads back to the line that named the file.
template <class Read>
std::invoke_result_t<Read, const std::filesystem::path&> ReadNamedFile(
    const std::filesystem::path& path, const std::string& where, std::string_view what, Read read) {
  std::error_code error;
  if (!std::filesystem::exists(path, error)) {
    throw InputError(fmt::format("{}: {} file {} not found", where, what, path.string()));
  }
  try {
    return read(path);
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: {}: {}", where, what, e.what()));
  }
}

}  // namespace harap
