// SPDX-License-Identifier: MIT
// One PLY reader; the ASCII seeds (corpus/ply_ascii/) steer this harness to the ASCII body
// parser.
#include "tests/fuzz/fuzz_target.h"

HARAP_MESH_FUZZ_TARGET("input.ply")
