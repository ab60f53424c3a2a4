// SPDX-License-Identifier: MIT
#pragma once

#include <string_view>
#include <vector>

#include "framework/mesh.h"
#include "framework/types.h"

namespace harap {

/// Stiffness: one factor per element multiplying that element's terms of the energy
/// (docs/energies.md, "Stiffness"). An empty vector means 1 everywhere; a factor of 10 makes an
/// element ten times as costly to deform, so a stiff region stays closer to rigid.

/// Throws InputError naming `what` and the first offending element unless `stiffness` is empty
/// or has one finite factor > 0 per element of `mesh`.
void ValidateStiffness(const std::vector<double>& stiffness, const Mesh& mesh,
                       std::string_view what);

/// Per-vertex factors from per-element ones: the mean over the elements around each vertex (1 for
/// vertices no element references). Empty in, empty out.
std::vector<double> VertexStiffness(const Mesh& mesh, const std::vector<double>& element_stiffness);

/// Per-element factors from per-vertex ones: the mean over each element's vertices. Empty in,
/// empty out. A factor given per vertex reaches the elements around the vertex in part, so the
/// border of a stiff region is blended over one ring of elements.
std::vector<double> ElementStiffness(const Mesh& mesh, const std::vector<double>& vertex_stiffness);

}  // namespace harap
