// SPDX-License-Identifier: MIT
#include "energies/kernels/cotangent_arap_energy.h"

#include "energies/kernels/cotangent_weights.h"
#include "energies/kernels/mesh_adjacency.h"
#include "energies/kernels/triangle_stencil.h"
#include "framework/stiffness.h"

namespace harap {

namespace {

// Edges (vertex pairs) of A's pattern and those whose off-diagonal entry says the summed weight
// is negative (A = κ·L with κ > 0, L_ij = −w_ij).
std::pair<Index, Index> CountEdges(const SparseMatrix& a) {
  Index edges = 0, negative = 0;
  for (Index col = 0; col < a.outerSize(); ++col) {
    for (SparseMatrix::InnerIterator it(a, col); it; ++it) {
      if (it.row() >= col) continue;
      ++edges;
      if (it.value() > 0.0) ++negative;
    }
  }
  return {edges, negative};
}

}  // namespace

void CotangentArapEnergy::ApplyStiffness(const Mesh& rest, TriangleWeights& weights) const {
  if (stiffness_.empty()) return;
  // A triangle of the mesh takes its own factor. Triangles the weight scheme made (intrinsic
  // Delaunay flips) are not the mesh's: they take the mean of their corners' factors.
  std::vector<double> at_vertex;
  for (Index f = 0; f < weights.triangles.rows(); ++f) {
    double factor = stiffness_[f];
    if (weights.triangles.row(f) != rest.elements.row(f)) {
      if (at_vertex.empty()) at_vertex = VertexStiffness(rest, stiffness_);
      factor = (at_vertex[weights.triangles(f, 0)] + at_vertex[weights.triangles(f, 1)] +
                at_vertex[weights.triangles(f, 2)]) /
               3.0;
    }
    weights.half_cot.row(f) *= factor;
  }
}

WeightOptions WeightOptions::FromConfig(OptionReader node, const WeightOptions& defaults) {
  WeightOptions options = defaults;
  options.input_level = node.GetEnum(
      "weights", options.input_level, kWeightSchemeNames,
      "edge weights: cotan = ½cot of the mesh's angles (negative at obtuse angles; libigl's); "
      "intrinsic_delaunay = cotangents of the intrinsic Delaunay triangulation (never "
      "negative on closed meshes); clamped = cotangents raised to min_cotangent; uniform = 1 "
      "per edge");
  options.coarse_levels =
      node.GetEnum("coarse_weights", options.coarse_levels, kCoarseWeightSchemeNames,
                   "edge weights on a hierarchy's coarse levels (same = as `weights`)");
  options.min_cotangent =
      node.Get("min_cotangent", options.min_cotangent,
               "weights = clamped: the smallest cotangent of a corner (the weight of an edge is "
               "half the sum over its faces)",
               Range::Above(0.0));
  return options;
}

void CotangentArapEnergy::SetInputMesh(const Mesh& /*input*/, const Context& /*context*/) {
  coarse_level_ = true;
}

void CotangentArapEnergy::PrecomputeCoupledForm(const Mesh& rest, const Context& context) {
  RequireTriangleMesh(rest, name_);
  context.Run([&] {
    WeightScheme scheme = weight_options_.input_level;
    if (coarse_level_ && weight_options_.coarse_levels != WeightScheme::kAsInputLevel) {
      scheme = weight_options_.coarse_levels;
    }
    TriangleWeights weights =
        ComputeTriangleWeights(rest.vertices, rest.elements, scheme, weight_options_.min_cotangent);
    num_degenerate_ = weights.degenerate;
    ApplyStiffness(rest, weights);
    const Elements& faces = weights.triangles;
    const auto& half_cot = weights.half_cot;
    a_ = AdjacencyPattern(rest.num_vertices(), faces);
    const auto entry = TriangleEntryPositions(a_, faces);
    std::vector<Eigen::Vector3d> coefficient(a_.nonZeros(), Eigen::Vector3d::Zero());
    double constant = 0.0;
    for (Index f = 0; f < rest.num_elements(); ++f) {
      const Face face{
          {rest.vertices.row(faces(f, 0)).transpose(), rest.vertices.row(faces(f, 1)).transpose(),
           rest.vertices.row(faces(f, 2)).transpose()},
          {half_cot(f, 0), half_cot(f, 1), half_cot(f, 2)},
          entry[f]};
      AddFace(face, a_.valuePtr(), coefficient.data(), constant);
    }
    coupling_ = MakeVertexSiteCoupling(a_, std::move(coefficient), constant);
    const auto [edges, negative] = CountEdges(a_);
    weights_ = EnergyWeights{std::string(NameOf(kWeightSchemeNames, scheme)), edges, negative,
                             negative_weights_break_squares_ && negative > 0};
    AddNonFaceTerms(RestGeometry{rest, faces, half_cot, entry}, context);
  });
}

void CotangentArapEnergy::AddSpokesAndRimsFace(const Face& face, double scale, double* a_values,
                                               Eigen::Vector3d* coefficients, double& constant) {
  // g_x = Σ over the face's edges (x, y) of w·(v̄_x − v̄_y): the coefficient of u_x in the cross
  // term of every rotation of the face (Eq. 1 expanded).
  Eigen::Vector3d g[3] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                          Eigen::Vector3d::Zero()};
  const auto& at = face.positions;
  for (int a = 0; a < 3; ++a) {
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    const double w = scale * face.half_cot[a];
    const Eigen::Vector3d edge = face.rest[b] - face.rest[c];
    g[b] += w * edge;
    g[c] -= w * edge;
    // Each face edge is seen by the three rotations of the face: A = 3·L.
    a_values[at[3 * b + b]] += 3.0 * w;
    a_values[at[3 * c + c]] += 3.0 * w;
    a_values[at[3 * b + c]] -= 3.0 * w;
    a_values[at[3 * c + b]] -= 3.0 * w;
    constant += 3.0 * w * edge.squaredNorm();
  }
  for (int site = 0; site < 3; ++site) {
    for (int x = 0; x < 3; ++x) coefficients[at[3 * x + site]] += g[x];
  }
}

}  // namespace harap
