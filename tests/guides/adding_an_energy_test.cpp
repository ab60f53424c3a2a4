// SPDX-License-Identifier: MIT
// The worked example of docs/adding-an-energy.md, built and run by the suite: an energy written
// as the guide says, registered by name and run through the normal machinery. The guide quotes
// the marked regions word for word (checked below), so a stale guide fails here.
#include <catch2/catch.hpp>
#include <cmath>
#include <memory>

#include "api/builtins.h"
#include "tests/guides/guide_support.h"
#include "tests/support/test_meshes.h"

// [guide:energy-header]
#include <string_view>

#include "energies/kernels/cotangent_arap_energy.h"

namespace harap {

/// Spokes ARAP with uniform weights: one rotation per vertex over its 1-ring edges,
///
///     E(U, R) = Σ_i Σ_{j ∈ N(i)} w_ij ‖(u_i − u_j) − R_i (v̄_i − v̄_j)‖²,  w_ij = ½ per face of ij
///
/// (1 for an interior edge, ½ on the boundary). Triangle meshes only.
class UniformSpokesEnergy final : public CotangentArapEnergy {
 public:
  static constexpr std::string_view kName = "uniform_spokes";

  /// Options: none (CoupledQuadraticEnergy's NoOptions).
  explicit UniformSpokesEnergy(const Options& /*options*/) : CotangentArapEnergy(kName) {}

 private:
  void AddFace(const Face& face, double* a_values, Eigen::Vector3d* coefficients,
               double& constant) const override;
};

}  // namespace harap
// [/guide:energy-header]

namespace harap {

// [guide:energy-source]
void UniformSpokesEnergy::AddFace(const Face& face, double* a_values, Eigen::Vector3d* coefficients,
                                  double& constant) const {
  // The face's edge bc (opposite corner a) with weight w enters the cells of b and c:
  // w‖(u_b − u_c) − R_b ē_bc‖² + w‖(u_c − u_b) − R_c ē_cb‖². Expanded: A gets w·(e_b − e_c)
  // (e_b − e_c)ᵀ twice, the constant 2w‖ē‖², the coupling of rotation b the coefficient +w ē
  // for u_b and −w ē for u_c (and of rotation c the opposite). positions[3x + s] is where the
  // entry (row x, column s) of the face's vertices lives.
  const auto& at = face.positions;
  for (int a = 0; a < 3; ++a) {
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    const double w = 0.5;  // uniform: ½ per face, so 1 per interior edge
    const Eigen::Vector3d edge = face.rest[b] - face.rest[c];
    a_values[at[3 * b + b]] += 2.0 * w;
    a_values[at[3 * c + c]] += 2.0 * w;
    a_values[at[3 * b + c]] -= 2.0 * w;
    a_values[at[3 * c + b]] -= 2.0 * w;
    constant += 2.0 * w * edge.squaredNorm();
    coefficients[at[3 * b + b]] += w * edge;
    coefficients[at[3 * c + b]] -= w * edge;
    coefficients[at[3 * c + c]] -= w * edge;
    coefficients[at[3 * b + c]] += w * edge;
  }
}
// [/guide:energy-source]

}  // namespace harap

using namespace harap;
using namespace harap::testing;

namespace {

// As energies/register_energies.cpp's RegisterEnergies, which lists the module's energies.
void RegisterExampleEnergy(Registry<Energy>& registry) {
  // [guide:energy-register]
  registry.Add<UniformSpokesEnergy>("spokes ARAP with uniform weights (the guide's example)");
  // [/guide:energy-register]
}

Registries RegistriesWithExample() {
  Registries registries = MakeBuiltinRegistries();
  RegisterExampleEnergy(registries.energies);
  return registries;
}

}  // namespace

TEST_CASE("guide adding-an-energy: the example is registered, listed and created by name",
          "[guides]") {
  const Registries registries = RegistriesWithExample();
  REQUIRE(registries.energies.Contains("uniform_spokes"));
  CHECK(registries.energies.DescribeOptions("uniform_spokes").empty());  // no options
  const ConfigNode typo =
      ConfigNode::Parse("[energy]\ntype = \"uniform_spokes\"\nweight = 2\n", "t");
  CHECK_THROWS_WITH(registries.energies.Create(typo.Child("energy"), "spokes"),
                    Catch::Contains("unknown option 'energy.weight'"));
}

TEST_CASE("guide adding-an-energy: the example is an ARAP energy", "[guides]") {
  const Registries registries = RegistriesWithExample();
  const Mesh mesh = Icosphere(2);
  const auto energy = registries.energies.Create("uniform_spokes", ConfigNode());
  const Context context;
  energy->Precompute(mesh, context);
  REQUIRE(energy->num_rotations() == mesh.num_vertices());
  const SparseMatrix& a = energy->system_matrix();
  CHECK((SparseMatrix(a.transpose()) - a).norm() == 0.0);
  // Zero at rest and under a rigid motion, with the rotation recovered by the local step.
  const Eigen::Matrix3d rotation = RandomRotation(3);
  Positions moved =
      (mesh.vertices * rotation.transpose()).rowwise() + Eigen::RowVector3d(0.3, -1.0, 2.0);
  Rotations rotations(mesh.num_vertices(), Rotation::Identity());
  CHECK(energy->FitRotations(mesh.vertices, rotations, context) == Approx(0.0).margin(1e-12));
  CHECK(energy->FitRotations(moved, rotations, context) == Approx(0.0).margin(1e-10));
  CHECK((rotations[7] - rotation).norm() < 1e-8);
  // The defining formula, summed edge by edge, at a non-rigid state with fitted rotations.
  const Positions u = SmoothlyDeformed(mesh.vertices, 0.2);
  const double e = energy->FitRotations(u, rotations, context);
  double direct = 0.0;
  for (Index f = 0; f < mesh.num_elements(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const Index i = mesh.elements(f, k), j = mesh.elements(f, (k + 1) % 3);
      const Eigen::Vector3d rest = (mesh.vertices.row(i) - mesh.vertices.row(j)).transpose();
      const Eigen::Vector3d now = (u.row(i) - u.row(j)).transpose();
      // ½ per face and cell: the edge ij of face f in the cells of i and of j.
      direct += 0.5 * ((now - rotations[i] * rest).squaredNorm() +
                       (-now + rotations[j] * rest).squaredNorm());
    }
  }
  CHECK(e == Approx(direct).epsilon(1e-10));
}

TEST_CASE("guide adding-an-energy: the example runs in classic and hierarchical optimizers",
          "[guides]") {
  const Registries registries = RegistriesWithExample();
  const BentTube tube(24, 16, 2.0, M_PI / 4, Eigen::Vector3d(0.0, 0.4, -0.2));
  for (const char* optimizer : {"classic", "hierarchical"}) {
    DYNAMIC_SECTION(optimizer) {
      std::map<int, std::vector<double>> energies;
      const OptimizeResult result = RunConfigured(
          registries, tube.problem,
          fmt::format("[optimizer]\ntype = \"{}\"\nmax_iterations = 200\n"
                      "[energy]\ntype = \"uniform_spokes\"\n[hierarchy]\nmin_vertices = 60\n",
                      optimizer),
          &energies);
      CHECK(std::isfinite(result.energy));
      CHECK(result.energy > 0.0);
      CHECK(energies.at(0).back() < energies.at(0).front());
      if (std::string(optimizer) == "classic") CHECK(MonotonePerLevel(energies));
      const Constraints& constraints = tube.problem.constraints;
      for (size_t k = 0; k < constraints.indices.size(); ++k) {
        CHECK(result.positions.row(constraints.indices[k]) == constraints.targets.row(k));
      }
    }
  }
}

TEST_CASE("guide adding-an-energy: the guide quotes the example as it is", "[guides]") {
  const std::string doc = "docs/adding-an-energy.md";
  const std::string example = "tests/guides/adding_an_energy_test.cpp";
  for (const char* region : {"energy-header", "energy-source", "energy-register"}) {
    DYNAMIC_SECTION(region) { CheckGuideQuotes(doc, example, region); }
  }
}
