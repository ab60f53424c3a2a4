// SPDX-License-Identifier: MIT
// libFuzzer entry points for harap's readers.
//
// A harness is one file tests/fuzz/fuzz_<target>.cpp that defines LLVMFuzzerTestOneInput, usually
// with HARAP_MESH_FUZZ_TARGET below, plus seed inputs in tests/fuzz/corpus/<target>/. CMake finds
// it by name: with -DHARAP_FUZZ=ON (clang) it becomes the fuzzer harap_fuzz_<target>; in every
// other build it is linked with replay_main.cpp into a ctest test that runs the seed corpus and
// the saved crash inputs (tests/fuzz/regressions/<target>/) once, so they stay fixed.
//
// What counts as a failure: anything but returning normally or throwing the documented error
// types (InputError for data, ConfigError for scenario text), i.e. crashes, sanitizer reports,
// InternalError (a failed HARAP_CHECK), std::bad_alloc and other exceptions, and timeouts.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "framework/error.h"
#include "io/mesh_io.h"
#include "io/mesh_repair.h"

namespace harap::fuzzing {

inline std::string_view AsText(const uint8_t* data, size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

/// Runs what `harap deform` runs on a mesh before solving: read, check, weld and drop duplicates.
inline void CheckAndRepair(const Mesh& mesh, const Constraints& constraints) {
  DeformationProblem problem;
  problem.mesh = &mesh;
  problem.constraints = constraints;
  MeshRepairOptions options;
  options.weld_duplicates = true;
  const PreparedProblem prepared(problem, options);
  (void)prepared.Summary();
}

/// Parses `data` as a mesh file called `file_name` (the extension selects the reader).
inline int FuzzMeshReader(const uint8_t* data, size_t size, std::string_view file_name) {
  try {
    const Mesh mesh = ParseMesh(AsText(data, size), file_name);
    CheckAndRepair(mesh, {});
  } catch (const InputError&) {
    // A clear error is the expected outcome for malformed data.
  }
  return 0;
}

}  // namespace harap::fuzzing

/// Defines the fuzz entry point for the mesh reader that `file_name`'s extension selects.
#define HARAP_MESH_FUZZ_TARGET(file_name)                                   \
  extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) { \
    return ::harap::fuzzing::FuzzMeshReader(data, size, file_name);         \
  }
