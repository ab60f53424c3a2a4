// SPDX-License-Identifier: MIT
#include "energies/spokes_and_rims_energy.h"

namespace harap {

SpokesAndRimsEnergy::Options SpokesAndRimsEnergy::Options::FromConfig(const ConfigNode& node) {
  node.RejectUnknownKeys();
  return Options{};
}

std::unique_ptr<Energy> SpokesAndRimsEnergy::Create(const ConfigNode& node) {
  return std::make_unique<SpokesAndRimsEnergy>(Options::FromConfig(node));
}

void SpokesAndRimsEnergy::AddFace(const Face& face, double* a_values,
                                  Eigen::Vector3d* coefficients, double& constant) const {
  // g_x = Σ over the face's edges (x, y) of w·(v̄_x − v̄_y): the coefficient of u_x in the cross
  // term of every rotation of the face (Eq. 1 expanded).
  Eigen::Vector3d g[3] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                          Eigen::Vector3d::Zero()};
  const auto& at = face.positions;
  for (int a = 0; a < 3; ++a) {
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    const double w = face.half_cot[a];
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
