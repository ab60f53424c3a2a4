// SPDX-License-Identifier: MIT
#pragma once

#include <cstddef>
#include <string>

namespace harap {

/// The colour of handle `h` (0-based) wherever handles are shown (`harap handles --out`,
/// `harap view`), and its name ("blue", ...). Colours repeat after nine handles.
void HandleColor(size_t h, unsigned char rgb[3], std::string* name = nullptr);

/// The grey of vertices no handle selects (all three channels).
inline constexpr unsigned char kFreeVertexGrey = 190;

}  // namespace harap
