// SPDX-License-Identifier: MIT
// Properties every registered energy must have; a new energy is tested the moment it is
// registered.
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <catch2/catch.hpp>
#include <random>

#include "api/builtins.h"
#include "framework/data_term.h"
#include "framework/error.h"
#include "tests/support/level_energies.h"
#include "tests/support/test_meshes.h"

using namespace harap;
using namespace harap::testing;

namespace {

std::vector<std::pair<std::string, Mesh>> ConformanceMeshes() {
  Mesh grid = Grid(7, 6);
  // Lift the grid out of the plane so no rest neighbourhood is flat.
  for (Index i = 0; i < grid.num_vertices(); ++i) {
    grid.vertices(i, 2) = 0.2 * std::sin(3.0 * grid.vertices(i, 0)) * grid.vertices(i, 1);
  }
  // Surface meshes, tetrahedral meshes and a planar mesh: each energy runs on the kinds it
  // accepts (the others must be refused with an InputError).
  return {{"icosphere", Icosphere(2)},
          {"curved grid", grid},
          {"tube", Tube(9, 12)},
          {"tet box", TetBox(4, 4, 5, 6)},
          {"jittered 5-tet box", Jittered(TetBox(5, 4, 4, 5), 5, 0.2, 1)},
          {"jittered planar grid", Jittered(PlanarGrid(7, 6), 7, 0.25, 2)}};
}

Rotations Identities(const Energy& energy) {
  return Rotations(energy.num_rotations(), Rotation::Identity());
}

/// A random rotation, about z for planar meshes (they deform in their plane).
Eigen::Matrix3d RandomMotionRotation(const Mesh& mesh, unsigned seed) {
  if (!mesh.planar) return RandomRotation(seed);
  return Eigen::AngleAxisd(0.7 + 0.37 * seed, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

/// A smooth non-rigid deformation (in the plane for planar meshes).
Positions Deformed(const Mesh& mesh, double amount) {
  Positions u = SmoothlyDeformed(mesh.vertices, amount);
  if (mesh.planar) u.col(2).setZero();
  return u;
}

// Runs `check(energy, mesh)` in one section per registered energy × conformance mesh it accepts,
// with the energy precomputed on the mesh. Every energy must accept some of the meshes.
template <class Check>
void ForEachEnergyAndMesh(Check&& check) {
  const Registries registries = MakeBuiltinRegistries();
  for (const auto& name : registries.energies.Names()) {
    int accepted = 0;
    for (const auto& [mesh_name, mesh] : ConformanceMeshes()) {
      auto energy = registries.energies.Create(name, ConfigNode());
      try {
        energy->Precompute(mesh, Context());
      } catch (const InputError&) {
        continue;  // a mesh kind this energy does not support
      }
      ++accepted;
      DYNAMIC_SECTION(name << " on " << mesh_name) { check(*energy, mesh); }
    }
    INFO("energy " << name);
    CHECK(accepted >= 2);
  }
}

// ∂E/∂U = 2 (A U − B(R)) by the Energy contract, against central differences of Evaluate along
// `trials` random directions.
void CheckGradient(const Energy& energy, const Positions& u, const Rotations& rotations, int trials,
                   std::mt19937& rng, const Context& context) {
  std::normal_distribution<double> normal;
  Positions rhs(u.rows(), 3);
  energy.AssembleRhs(rotations, rhs, context);
  const Positions gradient = 2.0 * (energy.system_matrix() * u - rhs);
  for (int trial = 0; trial < trials; ++trial) {
    Positions direction(u.rows(), 3);
    for (Eigen::Index i = 0; i < direction.size(); ++i) direction.data()[i] = normal(rng);
    const double h = 1e-6;
    const double numeric = (energy.Evaluate(u + h * direction, rotations, context) -
                            energy.Evaluate(u - h * direction, rotations, context)) /
                           (2.0 * h);
    CHECK(numeric == Approx(gradient.cwiseProduct(direction).sum()).epsilon(1e-6).margin(1e-8));
  }
}

}  // namespace

TEST_CASE("every energy: rest pose and rigid motions have zero energy", "[energies]") {
  const Context context;
  ForEachEnergyAndMesh([&](Energy& energy, const Mesh& mesh) {
    Rotations rotations = Identities(energy);
    const double scale = energy.system_matrix().diagonal().sum();
    CHECK(std::abs(energy.FitRotations(mesh.vertices, rotations, context)) < 1e-12 * scale);

    const Eigen::Matrix3d r = RandomMotionRotation(mesh, 7);
    Positions moved = (mesh.vertices * r.transpose()).rowwise() +
                      Eigen::RowVector3d(0.3, -1.0, mesh.planar ? 0.0 : 2.0);
    const double e = energy.FitRotations(moved, rotations, context);
    CHECK(std::abs(e) < 1e-10 * scale);
    for (const auto& fitted : rotations) CHECK((fitted - r).norm() < 1e-8);
    CHECK(std::abs(energy.Evaluate(moved, rotations, context)) < 1e-10 * scale);
  });
}

TEST_CASE("every energy: system matrix is symmetric PSD and annihilates translations",
          "[energies]") {
  const Context context;
  ForEachEnergyAndMesh([&](Energy& energy, const Mesh& mesh) {
    const Eigen::MatrixXd a = Eigen::MatrixXd(energy.system_matrix());
    REQUIRE(a.rows() == mesh.num_vertices());
    CHECK((a - a.transpose()).norm() < 1e-12 * a.norm());
    CHECK((a * Eigen::VectorXd::Ones(a.rows())).norm() < 1e-10 * a.norm());
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(a);
    CHECK(eigen.eigenvalues().minCoeff() > -1e-10 * eigen.eigenvalues().maxCoeff());
  });
}

TEST_CASE("every energy: gradient matches finite differences", "[energies]") {
  const Context context;
  std::mt19937 rng(3);
  ForEachEnergyAndMesh([&](Energy& energy, const Mesh& mesh) {
    const Positions u = Deformed(mesh, 0.7);
    Rotations rotations = Identities(energy);
    energy.FitRotations(u, rotations, context);
    // Perturb the rotations away from the optimum so the gradient is not tiny.
    for (size_t s = 0; s < rotations.size(); ++s) {
      rotations[s] = rotations[s] * RandomMotionRotation(mesh, static_cast<unsigned>(s) + 11);
    }
    CheckGradient(energy, u, rotations, /*trials=*/5, rng, context);
  });
}

TEST_CASE("every energy with stiffness and a data term: gradient matches finite differences",
          "[energies][stiffness][soft]") {
  // The objective of soft handles and registration: E_ARAP with per-element stiffness plus
  // Σ w‖u − t‖² (EnergyWithDataTerm), still of the contract form, so ∂E/∂U = 2 (A' U − B'(R)).
  const Context context;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> factor(0.5, 3.0);
  const Registries registries = MakeBuiltinRegistries();
  for (const auto& name : registries.energies.Names()) {
    for (const auto& [mesh_name, mesh] : ConformanceMeshes()) {
      std::unique_ptr<Energy> inner = registries.energies.Create(name, ConfigNode());
      std::vector<double> stiffness(mesh.num_elements());
      for (double& f : stiffness) f = factor(rng);
      bool stiff = true;
      try {
        inner->SetStiffness(stiffness);
      } catch (const InputError&) {
        stiff = false;  // an energy without stiffness: the data term alone
      }
      EnergyWithDataTerm energy(std::move(inner));
      try {
        energy.Precompute(mesh, context);
      } catch (const InputError&) {
        continue;  // a mesh kind this energy does not support
      }
      DYNAMIC_SECTION(name << " on " << mesh_name << (stiff ? " with stiffness" : "")) {
        SoftTargets soft;
        for (Index v = 0; v < mesh.num_vertices(); v += 3) soft.vertices.push_back(v);
        soft.targets = Deformed(mesh, 0.3)(soft.vertices, Eigen::all);
        for (size_t k = 0; k < soft.vertices.size(); ++k) soft.weights.push_back(factor(rng));
        energy.SetSoftTargets(soft);
        const Positions u = Deformed(mesh, 0.7);
        Rotations rotations = Identities(energy);
        energy.FitRotations(u, rotations, context);
        CheckGradient(energy, u, rotations, /*trials=*/3, rng, context);
        // The data term is there: moving the targets changes the energy by D alone.
        const double with_targets = energy.Evaluate(u, rotations, context);
        energy.MoveSoftTargets(u(soft.vertices, Eigen::all));
        CHECK(energy.Evaluate(u, rotations, context) ==
              Approx(with_targets - soft.Evaluate(u)).epsilon(1e-9).margin(1e-12));
      }
    }
  }
}

TEST_CASE("every energy with a rotation derivative: Hessian products match finite differences",
          "[energies]") {
  // E(u) = E(u, R(u)) has gradient g(u) = 2 (A u − B(R(u))); its derivative in direction v is
  // H v = 2 (A v − B(R'(u)[v])). Compared with central differences of g, which refit R.
  const Context context;
  std::mt19937 rng(5);
  std::normal_distribution<double> normal;
  ForEachEnergyAndMesh([&](Energy& energy, const Mesh& mesh) {
    if (!energy.has_rotation_derivative()) return;
    const Positions u = Deformed(mesh, 0.7);
    const auto gradient = [&](const Positions& x, Rotations& rotations) {
      energy.FitRotations(x, rotations, context);
      Positions rhs(mesh.num_vertices(), 3);
      energy.AssembleRhs(rotations, rhs, context);
      return Positions(2.0 * (energy.system_matrix() * x - rhs));
    };
    Rotations rotations = Identities(energy);
    gradient(u, rotations);
    std::vector<Eigen::Matrix3d> curvature;
    energy.PrepareRotationDerivative(u, rotations, /*project=*/false, curvature, context);
    REQUIRE(static_cast<Index>(curvature.size()) == energy.num_rotations());
    for (int trial = 0; trial < 3; ++trial) {
      Positions direction(u.rows(), 3);
      for (Eigen::Index i = 0; i < direction.size(); ++i) direction.data()[i] = normal(rng);
      if (mesh.planar) direction.col(2).setZero();
      Rotations d_rotations;
      energy.RotationDerivative(direction, rotations, curvature, d_rotations, context);
      Positions rhs(mesh.num_vertices(), 3);
      energy.AssembleRhs(d_rotations, rhs, context);
      const Positions analytic = 2.0 * (energy.system_matrix() * direction - rhs);
      const double h = 1e-6;
      Rotations plus_rotations = rotations, minus_rotations = rotations;
      const Positions plus = gradient(u + h * direction, plus_rotations);
      const Positions minus = gradient(u - h * direction, minus_rotations);
      const Positions numeric = (plus - minus) / (2.0 * h);
      INFO("trial " << trial << ": |analytic| " << analytic.norm() << ", |numeric| "
                    << numeric.norm());
      CHECK((analytic - numeric).norm() < 1e-5 * numeric.norm());
      // Symmetric: ⟨w, H v⟩ = ⟨v, H w⟩.
      Positions other(u.rows(), 3);
      for (Eigen::Index i = 0; i < other.size(); ++i) other.data()[i] = normal(rng);
      if (mesh.planar) other.col(2).setZero();
      energy.RotationDerivative(other, rotations, curvature, d_rotations, context);
      energy.AssembleRhs(d_rotations, rhs, context);
      const Positions other_product = 2.0 * (energy.system_matrix() * other - rhs);
      CHECK(other.cwiseProduct(analytic).sum() ==
            Approx(direction.cwiseProduct(other_product).sum()).epsilon(1e-9));
    }
  });
}

TEST_CASE(
    "every energy with a rotation derivative: the projected Hessian is PSD, and exact "
    "where stretched",
    "[energies]") {
  const Context context;
  ForEachEnergyAndMesh([&](Energy& energy, const Mesh& mesh) {
    if (!energy.has_rotation_derivative()) return;
    const Index n = mesh.num_vertices();
    // The dense 3n×3n matrix of v ↦ H v = 2 (A v − B(R'(u)[v])) at u.
    const auto dense_hessian = [&](const Positions& u, bool project) {
      Rotations rotations = Identities(energy);
      energy.FitRotations(u, rotations, context);
      std::vector<Eigen::Matrix3d> curvature;
      energy.PrepareRotationDerivative(u, rotations, project, curvature, context);
      Eigen::MatrixXd h(3 * n, 3 * n);
      Positions unit = Positions::Zero(n, 3), rhs(n, 3);
      Rotations d_rotations;
      for (Index k = 0; k < 3 * n; ++k) {
        unit(k / 3, k % 3) = 1.0;
        energy.RotationDerivative(unit, rotations, curvature, d_rotations, context);
        energy.AssembleRhs(d_rotations, rhs, context);
        const Positions product = 2.0 * (energy.system_matrix() * unit - rhs);
        for (Index i = 0; i < 3 * n; ++i) h(i, k) = product(i / 3, i % 3);
        unit(k / 3, k % 3) = 0.0;
      }
      return h;
    };
    // Each site's Hessian is PSD after the projection when every weight is non-negative, i.e.
    // (conservatively) A has no positive off-diagonal entry: negative cotangent weights (jittered
    // meshes) make a site's rest energy itself indefinite.
    bool nonnegative_weights = true;
    const SparseMatrix& a = energy.system_matrix();
    for (Index col = 0; col < a.outerSize(); ++col) {
      for (SparseMatrix::InnerIterator it(a, col); it; ++it) {
        if (it.row() != col && it.value() > 0.0) nonnegative_weights = false;
      }
    }
    const Eigen::MatrixXd projected = dense_hessian(Deformed(mesh, 0.7), true);
    CHECK((projected - projected.transpose()).norm() < 1e-9 * projected.norm());
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(0.5 * (projected + projected.transpose()));
    INFO("smallest eigenvalue " << eigen.eigenvalues().minCoeff() << ", largest "
                                << eigen.eigenvalues().maxCoeff());
    if (nonnegative_weights) {
      CHECK(eigen.eigenvalues().minCoeff() > -1e-9 * eigen.eigenvalues().maxCoeff());
    }
    // Stretched by 1.3 everywhere (and rotated): no twist mode is compressed, so the projection
    // leaves the exact Hessian.
    const Eigen::Matrix3d r = RandomMotionRotation(mesh, 3);
    const Positions stretched = 1.3 * mesh.vertices * r.transpose();
    const Eigen::MatrixXd exact = dense_hessian(stretched, false);
    CHECK((dense_hessian(stretched, true) - exact).norm() < 1e-9 * exact.norm());
  });
}

TEST_CASE("every energy: the local step never increases the energy", "[energies]") {
  const Context context;
  ForEachEnergyAndMesh([&](Energy& energy, const Mesh& mesh) {
    const Positions u = Deformed(mesh, 1.5);
    Rotations rotations = Identities(energy);
    for (size_t s = 0; s < rotations.size(); ++s) {
      rotations[s] = RandomMotionRotation(mesh, static_cast<unsigned>(s));
    }
    const double before = energy.Evaluate(u, rotations, context);
    const double after = energy.FitRotations(u, rotations, context);
    CHECK(after <= before);
    CHECK(after == Approx(energy.Evaluate(u, rotations, context)).epsilon(1e-12));
    // Optimality: no random perturbation of a fitted rotation lowers the energy.
    Rotations perturbed = rotations;
    for (size_t s = 0; s < perturbed.size(); s += 3) {
      const Eigen::Vector3d axis =
          mesh.planar ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d(1, 2, 3).normalized();
      Eigen::Matrix3d small = Eigen::AngleAxisd(1e-3, axis).toRotationMatrix();
      perturbed[s] = perturbed[s] * small;
    }
    CHECK(energy.Evaluate(u, perturbed, context) >= after);
  });
}

TEST_CASE("every energy: a hierarchical run decreases the energy on every level", "[energies]") {
  // 1152 vertices, the top ring turned by 60° and shifted.
  const BentTube tube(48, 24, 2.0, M_PI / 3, Eigen::Vector3d(0.0, 0.6, -0.4));
  // A bar of 6×6×16 vertices (2400 tetrahedra), 3 high, its top layer turned by 60°.
  const TwistedTetBar bar(6, 6, 16, 3.0, M_PI / 3);
  for (const auto& name : MakeBuiltinRegistries().energies.Names()) {
    DYNAMIC_SECTION(name) {
      // Surface energies bend the tube; the per-element energy twists the tetrahedral bar.
      const bool volumetric = name == "elements";
      const DeformationProblem& problem = volumetric ? bar.problem : tube.problem;
      // Every level runs on that level's own energy (its own weights and matrices).
      LevelEnergies energies;
      const OptimizeResult result = energies.RunHierarchicalWithFixedTargets(
          problem, 80, fmt::format("[energy]\ntype = \"{}\"\n", name));
      REQUIRE(result.levels.size() >= 3);
      CHECK(energies.by_level.size() == result.levels.size());
      CHECK(energies.MonotonePerLevel());
      CHECK(result.converged);
      CHECK(std::isfinite(result.energy));
      CHECK(result.energy == result.levels[0].energy);
      const Constraints& constraints = problem.constraints;
      for (size_t k = 0; k < constraints.indices.size(); ++k) {
        CHECK(result.positions.row(constraints.indices[k]) == constraints.targets.row(k));
      }
    }
  }
}

TEST_CASE("surface energies reject tetrahedral meshes with a clear error", "[energies]") {
  const Registries registries = MakeBuiltinRegistries();
  Mesh tet;
  tet.vertices = Positions::Identity(4, 3);
  tet.vertices.row(3).setZero();
  tet.elements.resize(1, 4);
  tet.elements << 0, 1, 2, 3;
  for (const auto* name : {"spokes", "spokes_and_rims", "smooth_arap"}) {
    auto energy = registries.energies.Create(name, ConfigNode());
    CHECK_THROWS_WITH(energy->Precompute(tet, Context()),
                      Catch::Contains(name) && Catch::Contains("triangle"));
  }
}

TEST_CASE("energy options: unknown keys are rejected", "[energies]") {
  const Registries registries = MakeBuiltinRegistries();
  ConfigNode config = ConfigNode::Parse("[energy]\ntype = \"spokes\"\nlambda = 0.5\n", "test");
  CHECK_THROWS_AS(registries.energies.Create(config.Child("energy"), "spokes"), ConfigError);
  CHECK_THROWS_WITH(registries.energies.Create("nonexistent", ConfigNode()),
                    Catch::Contains("spokes_and_rims") && Catch::Contains("nonexistent"));
}

namespace {

// Meshes with many obtuse angles (negative raw cotangent weights) and near-degenerate triangles:
// a strongly jittered sphere, and a tube whose every other ring is pushed almost onto the next,
// so its triangles are needles a thousandth as wide as long.
std::vector<std::pair<std::string, Mesh>> ObtuseMeshes() {
  Mesh needles = Tube(12, 16);
  for (Index i = 0; i < needles.num_vertices(); ++i) {
    const double z = needles.vertices(i, 2);
    const long ring = std::lround(z * 11.0);
    if (ring % 2 == 1) needles.vertices(i, 2) = (static_cast<double>(ring) - 0.999) / 11.0;
  }
  return {{"jittered sphere", Jittered(Icosphere(3), 20, 0.45, 3)},
          {"needle tube", needles},
          {"jittered 5-tet box", Jittered(TetBox(5, 4, 4, 5), 5, 0.2, 1)},
          {"jittered planar grid", Jittered(PlanarGrid(7, 6), 7, 0.25, 2)}};
}

}  // namespace

TEST_CASE("every energy: E >= 0 on obtuse and needle meshes, or it declares negative weights",
          "[energies]") {
  // An ARAP energy with non-negative weights is a sum of squares; one that is not must say so
  // (Energy::weights().can_be_negative), which the report turns into a warning.
  const Context context;
  const Registries registries = MakeBuiltinRegistries();
  std::mt19937 rng(17);
  std::normal_distribution<double> normal;
  for (const auto& name : registries.energies.Names()) {
    for (const auto& [mesh_name, mesh] : ObtuseMeshes()) {
      auto energy = registries.energies.Create(name, ConfigNode());
      try {
        energy->Precompute(mesh, context);
      } catch (const InputError&) {
        continue;
      }
      INFO(name << " on " << mesh_name);
      const EnergyWeights weights = energy->weights();
      CHECK(weights.negative_edges <= weights.edges);
      if (weights.can_be_negative) {
        CHECK(weights.negative_edges > 0);
        continue;
      }
      const double scale = energy->system_matrix().diagonal().sum();
      for (int trial = 0; trial < 6; ++trial) {
        // Random deformations of growing size, in the plane for planar meshes.
        Positions u = Deformed(mesh, 0.3 * trial);
        for (Eigen::Index i = 0; i < u.size(); ++i) u.data()[i] += 0.05 * trial * normal(rng);
        if (mesh.planar) u.col(2).setZero();
        Rotations rotations = Identities(*energy);
        const double e = energy->FitRotations(u, rotations, context);
        CHECK(e >= -1e-10 * scale);
        // Any rotations, not only the fitted ones: a sum of squares is ≥ 0 for all.
        for (size_t s = 0; s < rotations.size(); ++s) {
          rotations[s] = RandomMotionRotation(mesh, static_cast<unsigned>(s + 31 * trial));
        }
        CHECK(energy->Evaluate(u, rotations, context) >= -1e-10 * scale);
      }
    }
  }
}

TEST_CASE("spokes with raw cotangent weights declares that it can be negative", "[energies]") {
  const Registries registries = MakeBuiltinRegistries();
  ConfigNode config;
  config.Set("weights", "cotan");
  auto energy = registries.energies.Create("spokes", config);
  energy->Precompute(Jittered(Icosphere(3), 20, 0.45, 3), Context());
  const EnergyWeights weights = energy->weights();
  CHECK(weights.scheme == "cotan");
  CHECK(weights.negative_edges > 0);
  CHECK(weights.can_be_negative);
}
