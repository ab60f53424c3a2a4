// SPDX-License-Identifier: MIT
// One PLY reader; the binary seeds (corpus/ply_binary/, both byte orders) steer this harness
// to the binary body parser.
#include "tests/fuzz/fuzz_target.h"

HARAP_MESH_FUZZ_TARGET("input.ply")
