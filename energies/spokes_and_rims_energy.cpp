// SPDX-License-Identifier: MIT
#include "energies/spokes_and_rims_energy.h"

namespace harap {

void SpokesAndRimsEnergy::AddFace(const Face& face, double* a_values, Eigen::Vector3d* coefficients,
                                  double& constant) const {
  AddSpokesAndRimsFace(face, 1.0, a_values, coefficients, constant);
}

}  // namespace harap
