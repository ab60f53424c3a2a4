// SPDX-License-Identifier: MIT
#include "tests/fuzz/fuzz_target.h"

HARAP_MESH_FUZZ_TARGET("input.stl")
