// SPDX-License-Identifier: MIT
// EnergyWithDataTerm: an energy of the coupled form plus Σ w ‖u − t‖² keeps the contract.
#include "framework/data_term.h"

#include <catch2/catch.hpp>
#include <random>

#include "tests/support/test_factory.h"
#include "tests/support/test_meshes.h"

using namespace harap;
using namespace harap::testing;

namespace {

SoftTargets SomeSoftTargets(const Mesh& mesh, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> uniform(-0.2, 0.2);
  SoftTargets soft;
  for (Index v = 0; v < mesh.num_vertices(); v += 5) {
    soft.vertices.push_back(v);
    soft.weights.push_back(0.5 + 0.1 * static_cast<double>(v % 7));
  }
  soft.targets.resize(static_cast<Index>(soft.vertices.size()), 3);
  for (Index k = 0; k < soft.targets.rows(); ++k) {
    soft.targets.row(k) = mesh.vertices.row(soft.vertices[k]) +
                          Eigen::RowVector3d(uniform(random), uniform(random), uniform(random));
  }
  return soft;
}

}  // namespace

TEST_CASE("data term: the full objective's gradient matches finite differences",
          "[framework][data_term]") {
  const Mesh mesh = Jittered(Grid(6, 5), 0, 0.0, 1);
  const Registries registries = MakeBuiltinRegistries();
  for (const char* name : {"spokes_and_rims", "spokes", "elements"}) {
    DYNAMIC_SECTION(name) {
      const Mesh used = std::string(name) == "elements" ? PlanarGrid(6, 5) : Icosphere(1);
      EnergyWithDataTerm energy(registries.energies.Create(name, ConfigNode()));
      const Context context;
      energy.Precompute(used, context);
      CHECK(energy.SetSoftTargets(SomeSoftTargets(used, 4)));
      std::mt19937 random(9);
      std::uniform_real_distribution<double> uniform(-0.05, 0.05);
      Positions u = used.vertices;
      for (Index v = 0; v < u.rows(); ++v) {
        for (int d = 0; d < (used.planar ? 2 : 3); ++d) u(v, d) += uniform(random);
      }
      // E(u) = min_R E(u, R) + D(u); its gradient is 2 (A' u − B'(R(u))).
      Rotations rotations(energy.num_rotations(), Rotation::Identity());
      energy.FitRotations(u, rotations, context);
      Positions rhs(u.rows(), 3);
      energy.AssembleRhs(rotations, rhs, context);
      const Positions gradient = 2.0 * (energy.system_matrix() * u - rhs);
      const auto fitted = [&](const Positions& x) {
        Rotations r(energy.num_rotations(), Rotation::Identity());
        return energy.FitRotations(x, r, context);
      };
      const double h = 1e-6;
      for (Index v = 0; v < u.rows(); v += 3) {
        for (int d = 0; d < (used.planar ? 2 : 3); ++d) {
          Positions plus = u, minus = u;
          plus(v, d) += h;
          minus(v, d) -= h;
          const double numeric = (fitted(plus) - fitted(minus)) / (2.0 * h);
          INFO("vertex " << v << ", axis " << d);
          CHECK(gradient(v, d) == Approx(numeric).margin(1e-6).epsilon(1e-5));
        }
      }
      // Evaluate and the local step agree; the data energy is reported.
      CHECK(energy.Evaluate(u, rotations, context) == Approx(fitted(u)).epsilon(1e-12));
      CHECK(energy.AuxiliaryMeasures(u, rotations, context).at("data_energy") ==
            Approx(energy.soft_targets().Evaluate(u)));
    }
  }
}

TEST_CASE("data term: without soft targets the energy is the wrapped one, bit for bit",
          "[framework][data_term]") {
  const Mesh mesh = Icosphere(1);
  const Registries registries = MakeBuiltinRegistries();
  const Context context;
  auto plain = registries.energies.Create("spokes_and_rims", ConfigNode());
  plain->Precompute(mesh, context);
  EnergyWithDataTerm wrapped(registries.energies.Create("spokes_and_rims", ConfigNode()));
  wrapped.Precompute(mesh, context);
  CHECK_FALSE(wrapped.SetSoftTargets(SoftTargets()));
  const Positions u = SmoothlyDeformed(mesh.vertices, 0.1);
  Rotations a(plain->num_rotations(), Rotation::Identity()), b = a;
  CHECK(plain->FitRotations(u, a, context) == wrapped.FitRotations(u, b, context));
  Positions rhs_a(u.rows(), 3), rhs_b(u.rows(), 3);
  plain->AssembleRhs(a, rhs_a, context);
  wrapped.AssembleRhs(b, rhs_b, context);
  CHECK(rhs_a == rhs_b);
  CHECK(&wrapped.system_matrix() == &wrapped.inner().system_matrix());
  // Moving the targets keeps the matrix; other weights change it.
  SoftTargets soft = SomeSoftTargets(mesh, 1);
  CHECK(wrapped.SetSoftTargets(soft));
  const SparseMatrix before = wrapped.system_matrix();
  wrapped.MoveSoftTargets(soft.targets.array() + 1.0);
  CHECK((wrapped.system_matrix() - before).norm() == 0.0);
  CHECK_FALSE(wrapped.SetSoftTargets(soft));
  soft.weights[0] *= 2.0;
  CHECK(wrapped.SetSoftTargets(soft));
}
