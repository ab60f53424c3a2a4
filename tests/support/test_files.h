// SPDX-License-Identifier: MIT
// Texts of small input files that several tests write: scenarios and meshes.
#pragma once

#include <fmt/format.h>

#include <string>

namespace harap::testing {

/// A cylinder bend scenario: `mesh` (the value of the `mesh` key, e.g. CylinderMesh(3000)), its
/// bottom (z in [0, slab] of the box) held as 'bottom', its top (z in [1 − slab, 1]) as 'top'
/// turned `degrees` about x (no rotation for 0) and shifted by `translate`, with `top_extra`
/// (TOML lines, e.g. "weight = 2.0\n") added to the top handle.
inline std::string CylinderScenario(const std::string& mesh, double slab, double degrees,
                                    const std::string& translate = "[0.0, 0.0, 0.0]",
                                    const std::string& top_extra = "") {
  std::string text = fmt::format(
      "mesh = {}\n[[handle]]\nname = \"bottom\"\nselect.slab = {{ axis = \"z\", from = 0.0, to "
      "= {} }}\n[[handle]]\nname = \"top\"\nselect.slab = {{ axis = \"z\", from = {}, to = 1.0 "
      "}}\n",
      mesh, slab, 1.0 - slab);
  if (degrees != 0.0) {
    text += fmt::format("rotate = {{ axis = [1.0, 0.0, 0.0], degrees = {:.1f} }}\n", degrees);
  }
  return text + fmt::format("translate = {}\n", translate) + top_extra;
}

/// The `mesh` value of a built-in cylinder with about `vertices` vertices.
inline std::string CylinderMesh(int vertices) {
  return fmt::format("{{ builtin = \"cylinder\", vertices = {} }}", vertices);
}

/// A 600-vertex built-in cylinder, its bottom held ('bottom') and its top turned 60° about x
/// ('top'): a scenario that solves in a fraction of a second.
inline constexpr const char* kCylinderBendScenario = R"(
mesh = { builtin = "cylinder", vertices = 600 }
[[handle]]
name = "bottom"
select.slab = { axis = "z", from = 0.0, to = 0.05 }
[[handle]]
name = "top"
select.slab = { axis = "z", from = 0.95, to = 1.0 }
rotate = { axis = [1.0, 0.0, 0.0], degrees = 60.0 }
)";

/// A 2000-vertex built-in cylinder, its bottom held and its top turned 60° about x, without
/// names: with a tolerance of 1e-30 and a fixed iteration count a run takes most of a second, long
/// enough to interrupt a sweep in the middle of a run.
inline constexpr const char* kSlowCylinderScenario = R"(
mesh = { builtin = "cylinder", vertices = 2000 }
[[handle]]
select.slab = { axis = "z", from = 0.0, to = 0.05 }
[[handle]]
select.slab = { axis = "z", from = 0.95, to = 1.0 }
rotate = { axis = [1.0, 0.0, 0.0], degrees = 60.0 }
)";

/// The tables of a sweep comparing classic and hierarchical ARAP on small meshes (tolerance 1e-5,
/// a hierarchy down to 100 vertices), for experiment configs after their [scenarios].
inline constexpr const char* kClassicAndHierarchicalVariants = R"(
[optimizer]
tolerance = 1e-5
[[variant]]
name = "classic"
optimizer.type = "classic"
[[variant]]
name = "hierarchical"
optimizer.type = "hierarchical"
hierarchy.min_vertices = 100
)";

/// A bar along x in [0, 3] with a 1 x 1 cross-section as OFF: rings of 4 vertices at x = 0, 1,
/// 2, 3 (vertex 4 * ring + k), the sides triangulated (24 faces), with `caps` the two ends too
/// (28 faces, closed).
inline std::string BarOff(bool caps) {
  std::string off = fmt::format("OFF\n16 {} 0\n", caps ? 28 : 24);
  for (int ring = 0; ring < 4; ++ring) {
    off += fmt::format("{} 0 0\n{} 1 0\n{} 1 1\n{} 0 1\n", ring, ring, ring, ring);
  }
  for (int ring = 0; ring < 3; ++ring) {
    for (int k = 0; k < 4; ++k) {
      const int a = 4 * ring + k, b = 4 * ring + (k + 1) % 4, c = a + 4, d = b + 4;
      off += fmt::format("3 {} {} {}\n3 {} {} {}\n", a, b, d, a, d, c);
    }
  }
  if (caps) off += "3 0 2 1\n3 0 3 2\n3 12 13 14\n3 12 14 15\n";
  return off;
}

}  // namespace harap::testing
