// SPDX-License-Identifier: MIT
#include "energies/spokes_energy.h"

#include "energies/kernels/cotangent_weights.h"
#include "energies/kernels/mesh_adjacency.h"
#include "energies/kernels/triangle_stencil.h"

namespace harap {

SpokesEnergy::Options SpokesEnergy::Options::FromConfig(const ConfigNode& node) {
  node.RejectUnknownKeys();
  return Options{};
}

SpokesEnergy::SpokesEnergy(const Options& options)
    : CoupledQuadraticEnergy(RotationSite::kVertex), options_(options) {}

std::unique_ptr<Energy> SpokesEnergy::Create(const ConfigNode& node) {
  return std::make_unique<SpokesEnergy>(Options::FromConfig(node));
}

void SpokesEnergy::Precompute(const Mesh& rest, const Context& context) {
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
    // Each face contributes ½cot of each corner to the weight w_bc of the opposite edge; the
    // edge then appears in the cells of both its ends: A = 2·L.
    for (Index f = 0; f < rest.num_elements(); ++f) {
      for (int a = 0; a < 3; ++a) {
        const int b = (a + 1) % 3, c = (a + 2) % 3;
        const double w = half_cot(f, a);
        const Eigen::Vector3d edge = (v.row(faces(f, b)) - v.row(faces(f, c))).transpose();
        value[entry[f][3 * b + b]] += 2.0 * w;
        value[entry[f][3 * c + c]] += 2.0 * w;
        value[entry[f][3 * b + c]] -= 2.0 * w;
        value[entry[f][3 * c + b]] -= 2.0 * w;
        constant += 2.0 * w * edge.squaredNorm();
        // Cell of b: w‖(u_b − u_c) − R_b ē_bc‖²; cell of c: w‖(u_c − u_b) − R_c ē_cb‖².
        // Entry (row x, column s) holds c_sx.
        coefficient[entry[f][3 * b + b]] += w * edge;
        coefficient[entry[f][3 * c + b]] -= w * edge;
        coefficient[entry[f][3 * c + c]] -= w * edge;
        coefficient[entry[f][3 * b + c]] += w * edge;
      }
    }
    coupling_ = MakeVertexSiteCoupling(a_, std::move(coefficient), constant);
  });
}

}  // namespace harap
