// SPDX-License-Identifier: MIT
#include "energies/kernels/cotangent_arap_energy.h"

#include "energies/kernels/cotangent_weights.h"
#include "energies/kernels/mesh_adjacency.h"
#include "energies/kernels/triangle_stencil.h"

namespace harap {

void CotangentArapEnergy::Precompute(const Mesh& rest, const Context& context) {
  RequireTriangleMesh(rest, name_);
  context.Run([&] {
    const Elements& faces = rest.elements;
    const auto half_cot = HalfCotangents(rest.vertices, faces, &num_degenerate_);
    a_ = AdjacencyPattern(rest.num_vertices(), faces);
    const auto entry = TriangleEntryPositions(a_, faces);
    std::vector<Eigen::Vector3d> coefficient(a_.nonZeros(), Eigen::Vector3d::Zero());
    double constant = 0.0;
    for (Index f = 0; f < rest.num_elements(); ++f) {
      const Face face{{rest.vertices.row(faces(f, 0)).transpose(),
                       rest.vertices.row(faces(f, 1)).transpose(),
                       rest.vertices.row(faces(f, 2)).transpose()},
                      {half_cot(f, 0), half_cot(f, 1), half_cot(f, 2)},
                      entry[f]};
      AddFace(face, a_.valuePtr(), coefficient.data(), constant);
    }
    coupling_ = MakeVertexSiteCoupling(a_, std::move(coefficient), constant);
  });
}

}  // namespace harap
