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
  AddSpokesAndRimsFace(face, 1.0, a_values, coefficients, constant);
}

}  // namespace harap
