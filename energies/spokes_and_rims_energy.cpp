// SPDX-License-Identifier: MIT
#include "energies/spokes_and_rims_energy.h"

#include "energies/kernels/cotangent_weights.h"
#include "energies/kernels/mesh_adjacency.h"
#include "energies/kernels/triangle_stencil.h"

namespace harap {

SpokesAndRimsEnergy::Options SpokesAndRimsEnergy::Options::FromConfig(const ConfigNode& node) {
  node.RejectUnknownKeys();
  return Options{};
}

SpokesAndRimsEnergy::SpokesAndRimsEnergy(const Options& options)
    : CoupledQuadraticEnergy(RotationSite::kVertex), options_(options) {}

std::unique_ptr<Energy> SpokesAndRimsEnergy::Create(const ConfigNode& node) {
  return std::make_unique<SpokesAndRimsEnergy>(Options::FromConfig(node));
}

void SpokesAndRimsEnergy::Precompute(const Mesh& rest, const Context& context) {
  RequireTriangleMesh(rest, kName);
  context.Run([&] {
    const Elements& faces = rest.elements;
    const Positions& v = rest.vertices;
    const auto half_cot = HalfCotangents(v, faces, &num_degenerate_);
    a_ = AdjacencyPattern(rest.num_vertices(), faces);
    const auto entry = TriangleEntryPositions(a_, faces);
    std::vector<Eigen::Vector3d> coefficient(a_.nonZeros(), Eigen::Vector3d::Zero());
    double* value = a_.valuePtr();
    double constant = 0.0;
    for (Index f = 0; f < rest.num_elements(); ++f) {
      // g_x = Σ over the face's edges (x, y) of w·(v̄_x − v̄_y): the coefficient of u_x in the
      // cross term of every rotation of the face (Eq. 1 expanded).
      Eigen::Vector3d g[3] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                              Eigen::Vector3d::Zero()};
      for (int a = 0; a < 3; ++a) {
        const int b = (a + 1) % 3, c = (a + 2) % 3;
        const double w = half_cot(f, a);
        const Eigen::Vector3d edge = (v.row(faces(f, b)) - v.row(faces(f, c))).transpose();
        g[b] += w * edge;
        g[c] -= w * edge;
        // Each face edge is seen by the three rotations of the face: A = 3·L.
        value[entry[f][3 * b + b]] += 3.0 * w;
        value[entry[f][3 * c + c]] += 3.0 * w;
        value[entry[f][3 * b + c]] -= 3.0 * w;
        value[entry[f][3 * c + b]] -= 3.0 * w;
        constant += 3.0 * w * edge.squaredNorm();
      }
      for (int site = 0; site < 3; ++site) {
        for (int x = 0; x < 3; ++x) coefficient[entry[f][3 * x + site]] += g[x];
      }
    }
    coupling_ = MakeVertexSiteCoupling(a_, std::move(coefficient), constant);
  });
}

}  // namespace harap
