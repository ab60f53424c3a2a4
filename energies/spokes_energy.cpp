// SPDX-License-Identifier: MIT
#include "energies/spokes_energy.h"

namespace harap {

void SpokesEnergy::AddFace(const Face& face, double* a_values, Eigen::Vector3d* coefficients,
                           double& constant) const {
  // Each face contributes ½cot of each corner to the weight w_bc of the opposite edge; the edge
  // then appears in the cells of both its ends: A = 2·L.
  const auto& at = face.positions;
  for (int a = 0; a < 3; ++a) {
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    const double w = face.half_cot[a];
    const Eigen::Vector3d edge = face.rest[b] - face.rest[c];
    a_values[at[3 * b + b]] += 2.0 * w;
    a_values[at[3 * c + c]] += 2.0 * w;
    a_values[at[3 * b + c]] -= 2.0 * w;
    a_values[at[3 * c + b]] -= 2.0 * w;
    constant += 2.0 * w * edge.squaredNorm();
    // Cell of b: w‖(u_b − u_c) − R_b ē_bc‖²; cell of c: w‖(u_c − u_b) − R_c ē_cb‖².
    // Entry (row x, column s) holds c_sx.
    coefficients[at[3 * b + b]] += w * edge;
    coefficients[at[3 * c + b]] -= w * edge;
    coefficients[at[3 * c + c]] -= w * edge;
    coefficients[at[3 * b + c]] += w * edge;
  }
}

}  // namespace harap
