// SPDX-License-Identifier: MIT
#include "io/handle_colors.h"

#include <fmt/format.h>

#include <cstring>
#include <iterator>

namespace harap {

namespace {

struct NamedColor {
  unsigned char rgb[3];
  const char* name;
};

// Distinct colours, the first two as in the report's pictures (blue: first handle, red: second).
constexpr NamedColor kColors[] = {
    {{31, 119, 180}, "blue"},   {{214, 39, 40}, "red"},      {{44, 160, 44}, "green"},
    {{255, 127, 14}, "orange"}, {{148, 103, 189}, "purple"}, {{23, 190, 207}, "cyan"},
    {{227, 119, 194}, "pink"},  {{188, 189, 34}, "olive"},   {{140, 86, 75}, "brown"}};

}  // namespace

void HandleColor(size_t h, unsigned char rgb[3], std::string* name) {
  const NamedColor& color = kColors[h % std::size(kColors)];
  std::memcpy(rgb, color.rgb, 3);
  if (name) {
    *name = h < std::size(kColors) ? color.name
                                   : fmt::format("{} (colours repeat after {} handles)", color.name,
                                                 std::size(kColors));
  }
}

}  // namespace harap
