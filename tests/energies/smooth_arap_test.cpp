// SPDX-License-Identifier: MIT
// smooth_arap beyond the conformance suite: its defining formula evaluated directly (own
// cotangents, own Voronoi cells from circumcentres), λ = 0 against spokes_and_rims, the published
// rotation fit, the mass matrix and the 2-ring system matrix.
#include <catch2/catch.hpp>
#include <map>

#include "energies/kernels/cotangent_weights.h"
#include "energies/smooth_arap_energy.h"
#include "energies/spokes_and_rims_energy.h"
#include "framework/error.h"
#include "tests/support/level_energies.h"
#include "tests/support/test_factory.h"
#include "tests/support/test_meshes.h"

using namespace harap;
using namespace harap::testing;

namespace {

Eigen::Vector3d Row(const Positions& p, Index i) { return p.row(i).transpose(); }

double Cot(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return a.dot(b) / a.cross(b).norm();
}

// The Voronoi cell of each corner from the triangle's circumcentre (quadrilateral corner, edge
// midpoint, circumcentre, edge midpoint); obtuse triangles: ½ area to the obtuse corner, ¼ to the
// others [Meyer et al. 2003].
Eigen::VectorXd ReferenceVoronoiAreas(const Mesh& mesh) {
  Eigen::VectorXd areas = Eigen::VectorXd::Zero(mesh.num_vertices());
  for (Index f = 0; f < mesh.num_elements(); ++f) {
    const Eigen::Vector3d p[3] = {Row(mesh.vertices, mesh.elements(f, 0)),
                                  Row(mesh.vertices, mesh.elements(f, 1)),
                                  Row(mesh.vertices, mesh.elements(f, 2))};
    const Eigen::Vector3d ab = p[1] - p[0], ac = p[2] - p[0];
    const Eigen::Vector3d normal = ab.cross(ac);
    const double area = 0.5 * normal.norm();
    int obtuse = -1;
    for (int a = 0; a < 3; ++a) {
      if ((p[(a + 1) % 3] - p[a]).dot(p[(a + 2) % 3] - p[a]) < 0.0) obtuse = a;
    }
    const Eigen::Vector3d centre =
        p[0] + (ac.squaredNorm() * normal.cross(ab) + ab.squaredNorm() * ac.cross(normal)) /
                   (2.0 * normal.squaredNorm());
    for (int a = 0; a < 3; ++a) {
      double cell;
      if (obtuse >= 0) {
        cell = a == obtuse ? 0.5 * area : 0.25 * area;
      } else {
        const Eigen::Vector3d m1 = 0.5 * (p[a] + p[(a + 1) % 3]);
        const Eigen::Vector3d m2 = 0.5 * (p[a] + p[(a + 2) % 3]);
        cell = 0.5 * (m1 - p[a]).cross(centre - p[a]).norm() +
               0.5 * (centre - p[a]).cross(m2 - p[a]).norm();
      }
      areas[mesh.elements(f, a)] += cell;
    }
  }
  return areas;
}

// E(U, R) = (1 − λ) Σ_i Σ_{f∋i} Σ_{(j,k)∈f} ½cot ‖(u_j − u_k) − R_i (v̄_j − v̄_k)‖²
//         + (3λ/2) Σ_i ‖(L U)_i − R_i (L V̄)_i‖² / M_ii,  M mean-1 Voronoi areas.
double ReferenceEnergy(const Mesh& mesh, double lambda, const Positions& u, const Rotations& r) {
  const Index n = mesh.num_vertices();
  std::map<std::pair<Index, Index>, double> weight;  // ½(cot α + cot β) per directed edge
  double spokes_and_rims = 0.0;
  for (Index f = 0; f < mesh.num_elements(); ++f) {
    for (int a = 0; a < 3; ++a) {
      const Index o = mesh.elements(f, a), j = mesh.elements(f, (a + 1) % 3),
                  k = mesh.elements(f, (a + 2) % 3);
      const double w = 0.5 * Cot(Row(mesh.vertices, j) - Row(mesh.vertices, o),
                                 Row(mesh.vertices, k) - Row(mesh.vertices, o));
      weight[{j, k}] += w;
      weight[{k, j}] += w;
      for (int s = 0; s < 3; ++s) {
        const Index site = mesh.elements(f, s);
        spokes_and_rims +=
            w * (Row(u, j) - Row(u, k) - r[site] * (Row(mesh.vertices, j) - Row(mesh.vertices, k)))
                    .squaredNorm();
      }
    }
  }
  Positions lu = Positions::Zero(n, 3), lv = Positions::Zero(n, 3);
  for (const auto& [edge, w] : weight) {
    lu.row(edge.first) += w * (u.row(edge.first) - u.row(edge.second));
    lv.row(edge.first) += w * (mesh.vertices.row(edge.first) - mesh.vertices.row(edge.second));
  }
  const Eigen::VectorXd areas = ReferenceVoronoiAreas(mesh);
  const double mean = areas.mean();
  double laplacian_term = 0.0;
  for (Index i = 0; i < n; ++i) {
    laplacian_term += (Row(lu, i) - r[i] * Row(lv, i)).squaredNorm() / (areas[i] / mean);
  }
  return (1.0 - lambda) * spokes_and_rims + 1.5 * lambda * laplacian_term;
}

SmoothArapEnergy::Options SmoothOptions(
    double lambda,
    SmoothArapEnergy::RotationFit fit = SmoothArapEnergy::RotationFit::kWholeEnergy) {
  SmoothArapEnergy::Options options;
  options.lambda = lambda;
  options.rotation_fit = fit;
  return options;
}

}  // namespace

TEST_CASE("mixed Voronoi areas match circumcentre cells and add up to the mesh area",
          "[energies]") {
  Mesh obtuse;  // an obtuse triangle (angle at corner 2 ≈ 127°) and an acute one sharing an edge
  obtuse.vertices.resize(4, 3);
  obtuse.vertices << 0, 0, 0, 2, 0, 0, 1, 0.5, 0, 2, 2, 0;
  obtuse.elements.resize(2, 3);
  obtuse.elements << 0, 1, 2, 1, 3, 2;
  for (const Mesh& mesh : {Icosphere(2), Tube(9, 12), obtuse}) {
    const Eigen::VectorXd areas = MixedVoronoiAreas(mesh.vertices, mesh.elements);
    const Eigen::VectorXd reference = ReferenceVoronoiAreas(mesh);
    CHECK((areas - reference).cwiseAbs().maxCoeff() < 1e-12 * reference.maxCoeff());
    double total = 0.0;
    for (Index f = 0; f < mesh.num_elements(); ++f) {
      total +=
          0.5 * (Row(mesh.vertices, mesh.elements(f, 1)) - Row(mesh.vertices, mesh.elements(f, 0)))
                    .cross(Row(mesh.vertices, mesh.elements(f, 2)) -
                           Row(mesh.vertices, mesh.elements(f, 0)))
                    .norm();
    }
    CHECK(areas.sum() == Approx(total).epsilon(1e-12));
  }
  const Eigen::VectorXd areas = MixedVoronoiAreas(obtuse.vertices, obtuse.elements);
  CHECK(areas[0] == Approx(0.25 * 0.5).margin(1e-15));  // ¼ of the obtuse triangle (area ½)
  // A degenerate triangle contributes nothing (its cotangent weights are zero too).
  Mesh flat = obtuse;
  flat.vertices.row(2) << 1, 0, 0;
  const Eigen::VectorXd flat_areas = MixedVoronoiAreas(flat.vertices, flat.elements);
  CHECK(flat_areas[0] == 0.0);
  CHECK(flat_areas.sum() == Approx(1.0).epsilon(1e-12));  // the other triangle (1, 3, 2) only
}

TEST_CASE("smooth_arap energy equals its defining formula evaluated directly", "[energies]") {
  const Context context;
  for (const auto& mesh : {Icosphere(2), Tube(10, 14)}) {
    for (double lambda : {0.0, 0.5, 0.99}) {
      SmoothArapEnergy energy(SmoothOptions(lambda));
      energy.Precompute(mesh, context);
      for (double amount : {0.3, 1.5}) {
        const Positions u = SmoothlyDeformed(mesh.vertices, amount);
        Rotations rotations(mesh.num_vertices(), Rotation::Identity());
        for (size_t s = 0; s < rotations.size(); ++s) {
          rotations[s] = RandomRotation(static_cast<unsigned>(s) + 5);
        }
        const double reference = ReferenceEnergy(mesh, lambda, u, rotations);
        CHECK(energy.Evaluate(u, rotations, context) == Approx(reference).epsilon(1e-10));
        // The local step returns the energy at the rotations it fitted.
        const double fitted = energy.FitRotations(u, rotations, context);
        CHECK(fitted == Approx(ReferenceEnergy(mesh, lambda, u, rotations)).epsilon(1e-10));
        CHECK(fitted < reference);
      }
    }
  }
}

TEST_CASE("smooth_arap system matrix is the exactly symmetric 2-ring blend", "[energies]") {
  const Mesh mesh = Tube(10, 14);
  const Context context;
  SpokesAndRimsEnergy spokes_and_rims({});
  spokes_and_rims.Precompute(mesh, context);
  SmoothArapEnergy smooth(SmoothOptions(0.5));
  smooth.Precompute(mesh, context);
  const SparseMatrix& a = smooth.system_matrix();
  CHECK((SparseMatrix(a.transpose()) - a).norm() == 0.0);
  // Vertices two rings apart (same segment, rings 3 and 5) are coupled only by L M⁻¹ L.
  CHECK(spokes_and_rims.system_matrix().coeff(3 * 14, 5 * 14) == 0.0);
  CHECK(a.coeff(3 * 14, 5 * 14) > 0.0);
  // A = ½ A_SR + 0.75 L M⁻¹ L with L = A_SR / 3 and M the mean-1 Voronoi areas.
  const Eigen::MatrixXd l = Eigen::MatrixXd(spokes_and_rims.system_matrix()) / 3.0;
  const Eigen::VectorXd areas = MixedVoronoiAreas(mesh.vertices, mesh.elements);
  const Eigen::VectorXd inverse_mass = areas.mean() * areas.cwiseInverse();
  const Eigen::MatrixXd expected = 0.5 * 3.0 * l + 0.75 * l * inverse_mass.asDiagonal() * l;
  CHECK((Eigen::MatrixXd(a) - expected).norm() < 1e-12 * expected.norm());
}

TEST_CASE("smooth_arap at lambda 0 is spokes_and_rims exactly", "[energies]") {
  const BentTube tube(40, 24, 2.0, M_PI / 2, Eigen::Vector3d(0.0, 0.8, -0.8));
  for (const char* optimizer : {"classic", "hierarchical"}) {
    DYNAMIC_SECTION(optimizer) {
      const std::string common = fmt::format(
          "[optimizer]\ntype = \"{}\"\ntolerance = 1e-7\n[hierarchy]\nmin_vertices = 100\n",
          optimizer);
      TestSetup reference(common + "[energy]\ntype = \"spokes_and_rims\"\n");
      TestSetup smooth(common + "[energy]\ntype = \"smooth_arap\"\nlambda = 0.0\n");
      const OptimizeResult a =
          reference.MakeOptimizer()->Optimize(tube.problem, reference.factory, Context());
      const OptimizeResult b =
          smooth.MakeOptimizer()->Optimize(tube.problem, smooth.factory, Context());
      CHECK(a.total_iterations == b.total_iterations);
      CHECK(a.energy == b.energy);
      CHECK((a.positions - b.positions).cwiseAbs().maxCoeff() == 0.0);
    }
  }
  // The same matrix, pattern included (the solvers see the same system).
  const Context context;
  SpokesAndRimsEnergy spokes_and_rims({});
  spokes_and_rims.Precompute(tube.mesh, context);
  SmoothArapEnergy smooth(SmoothOptions(0.0));
  smooth.Precompute(tube.mesh, context);
  CHECK(smooth.system_matrix().nonZeros() == spokes_and_rims.system_matrix().nonZeros());
  CHECK((smooth.system_matrix() - spokes_and_rims.system_matrix()).norm() == 0.0);
}

TEST_CASE("smooth_arap rotation_fit = spokes_and_rims fits rotations as the published code",
          "[energies]") {
  const Mesh mesh = Tube(10, 14);
  const Context context;
  SmoothArapEnergy whole(SmoothOptions(0.9));
  SmoothArapEnergy published(SmoothOptions(0.9, SmoothArapEnergy::RotationFit::kSpokesAndRims));
  SpokesAndRimsEnergy spokes_and_rims({});
  for (Energy* energy : std::initializer_list<Energy*>{&whole, &published, &spokes_and_rims}) {
    energy->Precompute(mesh, context);
  }
  const Positions u = SmoothlyDeformed(mesh.vertices, 1.5);
  Rotations r_whole(mesh.num_vertices(), Rotation::Identity());
  Rotations r_published = r_whole, r_spokes_and_rims = r_whole;
  const double e_whole = whole.FitRotations(u, r_whole, context);
  const double e_published = published.FitRotations(u, r_published, context);
  spokes_and_rims.FitRotations(u, r_spokes_and_rims, context);
  double difference = 0.0, whole_difference = 0.0;
  for (Index i = 0; i < mesh.num_vertices(); ++i) {
    difference = std::max(difference, (r_published[i] - r_spokes_and_rims[i]).norm());
    whole_difference = std::max(whole_difference, (r_whole[i] - r_spokes_and_rims[i]).norm());
  }
  CHECK(difference < 1e-10);       // fitted to the spokes-and-rims part only
  CHECK(whole_difference > 1e-3);  // the λ-term changes the minimizing rotations
  // Both report the whole energy at their rotations; the whole fit is the lower one.
  CHECK(e_published == Approx(whole.Evaluate(u, r_published, context)).epsilon(1e-12));
  CHECK(e_whole < e_published);
  // The published fit of a finished run is visible in a classic run too: it converges.
  const BentTube tube(40, 24, 2.0, M_PI / 2, Eigen::Vector3d(0.0, 0.8, -0.8));
  TestSetup setup(
      "[optimizer]\ntype = \"classic\"\ntolerance = 1e-7\n"
      "[energy]\ntype = \"smooth_arap\"\nrotation_fit = \"spokes_and_rims\"\n");
  const OptimizeResult result =
      setup.MakeOptimizer()->Optimize(tube.problem, setup.factory, Context());
  CHECK(result.converged);
  CHECK(std::isfinite(result.energy));
}

TEST_CASE("smooth_arap options are validated", "[energies]") {
  const Registries registries = MakeBuiltinRegistries();
  for (const char* bad : {"lambda = 1.0", "lambda = -0.1", "lambda = nan"}) {
    ConfigNode config =
        ConfigNode::Parse(fmt::format("[energy]\ntype = \"smooth_arap\"\n{}\n", bad), "test.toml");
    // NaN is already refused by ConfigNode ("must be a finite number").
    CHECK_THROWS_WITH(registries.energies.Create(config.Child("energy"), "spokes_and_rims"),
                      Catch::Contains("lambda") && Catch::Contains("test.toml:3") &&
                          (Catch::Contains("[0, 1)") || Catch::Contains("finite")));
  }
  ConfigNode config = ConfigNode::Parse(
      "[energy]\ntype = \"smooth_arap\"\nrotation_fit = \"edges\"\n", "test.toml");
  CHECK_THROWS_WITH(registries.energies.Create(config.Child("energy"), "spokes_and_rims"),
                    Catch::Contains("rotation_fit") && Catch::Contains("spokes_and_rims"));
  ConfigNode typo = ConfigNode::Parse("[energy]\ntype = \"smooth_arap\"\nlamda = 0.5\n", "t");
  CHECK_THROWS_AS(registries.energies.Create(typo.Child("energy"), "spokes_and_rims"), ConfigError);
}

TEST_CASE("smooth_arap normalizes coarse levels like the input mesh", "[energies]") {
  // The same sphere at two resolutions (162 and 2562 vertices) and the same smooth deformation:
  // the energy approximates one integral, so the coarse mesh given the fine input mesh must report
  // about the fine energy; normalized on its own, its Laplacian term is ~16× too strong.
  const Mesh fine = Icosphere(4), coarse = Icosphere(2);
  const Context context;
  auto fitted_energy = [&](const Mesh& mesh, const Mesh* input, const char* normalization) {
    SmoothArapEnergy::Options options;
    options.normalize_mass_on_input = std::string(normalization) == "input";
    SmoothArapEnergy energy(options);
    if (input) energy.SetInputMesh(*input, context);
    energy.Precompute(mesh, context);
    Rotations rotations(mesh.num_vertices(), Rotation::Identity());
    return energy.FitRotations(SmoothlyDeformed(mesh.vertices, 1.0), rotations, context);
  };
  const double reference = fitted_energy(fine, nullptr, "input");
  // On the input mesh itself the call changes nothing.
  CHECK(fitted_energy(fine, &fine, "input") == reference);
  const double consistent = fitted_energy(coarse, &fine, "input");
  const double per_level = fitted_energy(coarse, &fine, "level");
  INFO("fine " << reference << ", coarse with the input's mass scale " << consistent
               << ", coarse with its own " << per_level);
  CHECK(std::abs(consistent / reference - 1.0) < 0.15);
  CHECK(per_level / reference > 3.0);
}

TEST_CASE("smooth_arap takes the scale of the input mesh it is given", "[energies]") {
  // Coarse levels are normalized by the input mesh's mass scale: alternating inputs, and an
  // input edited in place, must each get their own scale.
  const Mesh coarse = Icosphere(1);
  Mesh a = Icosphere(3), b = Icosphere(3);
  b.vertices *= 2.0;  // same connectivity, 4× the area
  const Context context;
  auto coarse_energy = [&](const Mesh& input) {
    SmoothArapEnergy energy{SmoothArapEnergy::Options{}};
    energy.SetInputMesh(input, context);
    energy.Precompute(coarse, context);
    Rotations rotations(coarse.num_vertices(), Rotation::Identity());
    return energy.FitRotations(SmoothlyDeformed(coarse.vertices, 1.0), rotations, context);
  };
  const double with_a = coarse_energy(a);
  const double with_b = coarse_energy(b);
  CHECK(with_a != with_b);
  CHECK(coarse_energy(a) == with_a);
  CHECK(coarse_energy(b) == with_b);
  a.vertices *= 2.0;  // edited in place: now b's geometry
  CHECK(coarse_energy(a) == with_b);
  a.vertices(0, 0) += 1e-3;  // one coordinate: a different mesh again
  CHECK(coarse_energy(a) != with_b);
}
