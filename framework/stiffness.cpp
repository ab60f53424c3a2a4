// SPDX-License-Identifier: MIT
#include "framework/stiffness.h"

#include <cmath>

#include "framework/error.h"

namespace harap {

void ValidateStiffness(const std::vector<double>& stiffness, const Mesh& mesh,
                       std::string_view what) {
  if (stiffness.empty()) return;
  if (static_cast<Index>(stiffness.size()) != mesh.num_elements()) {
    throw InputError(
        fmt::format("{}: {} stiffness factors for a mesh of {} elements (give one per "
                    "element)",
                    what, stiffness.size(), mesh.num_elements()));
  }
  for (size_t e = 0; e < stiffness.size(); ++e) {
    if (!std::isfinite(stiffness[e]) || stiffness[e] <= 0.0) {
      throw InputError(
          fmt::format("{}: the stiffness factor of element {} is {}; factors must be "
                      "finite and > 0",
                      what, e, stiffness[e]));
    }
  }
}

std::vector<double> VertexStiffness(const Mesh& mesh,
                                    const std::vector<double>& element_stiffness) {
  if (element_stiffness.empty()) return {};
  HARAP_CHECK(static_cast<Index>(element_stiffness.size()) == mesh.num_elements(),
              "{} stiffness factors for {} elements", element_stiffness.size(),
              mesh.num_elements());
  std::vector<double> sum(mesh.num_vertices(), 0.0);
  std::vector<int> count(mesh.num_vertices(), 0);
  for (Index e = 0; e < mesh.num_elements(); ++e) {
    for (int a = 0; a < mesh.simplex_size(); ++a) {
      sum[mesh.elements(e, a)] += element_stiffness[e];
      ++count[mesh.elements(e, a)];
    }
  }
  for (Index v = 0; v < mesh.num_vertices(); ++v) sum[v] = count[v] > 0 ? sum[v] / count[v] : 1.0;
  return sum;
}

std::vector<double> ElementStiffness(const Mesh& mesh,
                                     const std::vector<double>& vertex_stiffness) {
  if (vertex_stiffness.empty()) return {};
  HARAP_CHECK(static_cast<Index>(vertex_stiffness.size()) == mesh.num_vertices(),
              "{} stiffness factors for {} vertices", vertex_stiffness.size(), mesh.num_vertices());
  std::vector<double> result(mesh.num_elements());
  for (Index e = 0; e < mesh.num_elements(); ++e) {
    double sum = 0.0;
    for (int a = 0; a < mesh.simplex_size(); ++a) sum += vertex_stiffness[mesh.elements(e, a)];
    result[e] = sum / mesh.simplex_size();
  }
  return result;
}

}  // namespace harap
