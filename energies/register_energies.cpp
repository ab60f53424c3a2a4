// SPDX-License-Identifier: MIT
#include "energies/register_energies.h"

#include "energies/element_arap_energy.h"
#include "energies/smooth_arap_energy.h"
#include "energies/spokes_and_rims_energy.h"
#include "energies/spokes_energy.h"

namespace harap {

void RegisterEnergies(Registry<Energy>& registry) {
  registry.Add<SpokesAndRimsEnergy>(
      "spokes-and-rims ARAP, one rotation per vertex over all edges of its incident "
      "faces [Chao et al. 2010] (the paper's Eq. 1)");
  registry.Add<SpokesEnergy>(
      "spokes ARAP, one rotation per vertex over its 1-ring edges, weights "
      "½(cot α + cot β) [Sorkine & Alexa 2007], of the intrinsic Delaunay triangulation by "
      "default (never negative)");
  registry.Add<ElementArapEnergy>(
      "per-element ARAP, one rotation per tetrahedron or per triangle of a planar mesh, "
      "cotangent weights (the paper's Eqs. 8, 9); reports energy_wrapd = E/2");
  registry.Add<SmoothArapEnergy>(
      "smooth ARAP: (1−λ)·spokes_and_rims + rigidly rotated Laplacian vectors (weight "
      "λ), a bi-Laplacian blend without spikes at handles [Oehri et al. 2025] (the "
      "paper's Fig. 10)");
}

}  // namespace harap
