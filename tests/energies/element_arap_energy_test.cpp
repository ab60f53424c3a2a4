// SPDX-License-Identifier: MIT
// The per-element energy `elements` (Section 6 of the paper) against independent formulas:
// WRAPD's Σ ½ vol ‖F − R‖² from deformation gradients and an SVD, dihedral angles by
// trigonometry, and the surface energies on a flat mesh where they must agree.
#include "energies/element_arap_energy.h"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <catch2/catch.hpp>
#include <random>

#include "energies/kernels/cotangent_weights.h"
#include "energies/spokes_and_rims_energy.h"
#include "energies/spokes_energy.h"
#include "framework/error.h"
#include "tests/support/test_meshes.h"

using namespace harap;
using namespace harap::testing;

namespace {

/// The rotation closest to f with det = +1 (WRAPD: R = U Vᵀ with the sign of the smallest
/// singular direction flipped for a reflection), of the plane for 2×2 input.
template <int D>
Eigen::Matrix<double, D, D> WrapdRotation(const Eigen::Matrix<double, D, D>& f) {
  Eigen::JacobiSVD<Eigen::Matrix<double, D, D>> svd(f, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix<double, D, D> u = svd.matrixU();
  if ((u * svd.matrixV().transpose()).determinant() < 0) u.col(D - 1) *= -1.0;
  return u * svd.matrixV().transpose();
}

/// WRAPD's energy of one simplex: ½ |t| ‖F − R‖²_F (D = 3 tetrahedra, D = 2 planar triangles).
template <int D>
double WrapdEnergy(const Eigen::Matrix<double, D, D + 1>& rest,
                   const Eigen::Matrix<double, D, D + 1>& deformed) {
  Eigen::Matrix<double, D, D> dm, ds;
  for (int a = 0; a < D; ++a) {
    dm.col(a) = rest.col(a + 1) - rest.col(0);
    ds.col(a) = deformed.col(a + 1) - deformed.col(0);
  }
  const double volume = std::abs(dm.determinant()) / (D == 3 ? 6.0 : 2.0);
  const Eigen::Matrix<double, D, D> f = ds * dm.inverse();
  return 0.5 * volume * (f - WrapdRotation<D>(f)).squaredNorm();
}

Mesh SingleTet(const Eigen::Matrix<double, 3, 4>& corners) {
  Mesh mesh;
  mesh.vertices = corners.transpose();
  mesh.elements.resize(1, 4);
  mesh.elements << 0, 1, 2, 3;
  return mesh;
}

Eigen::Matrix3d RandomMatrix(std::mt19937& rng) {
  std::normal_distribution<double> normal;
  Eigen::Matrix3d m;
  for (int i = 0; i < 9; ++i) m.data()[i] = normal(rng);
  return m;
}

double DihedralCotangent(const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                         const Eigen::Vector3d& r, const Eigen::Vector3d& s) {
  // Angle at edge pq between the faces (p, q, r) and (p, q, s).
  const Eigen::Vector3d axis = (q - p).normalized();
  Eigen::Vector3d x = r - p, y = s - p;
  x -= x.dot(axis) * axis;
  y -= y.dot(axis) * axis;
  const double angle = std::acos(std::clamp(x.normalized().dot(y.normalized()), -1.0, 1.0));
  return std::cos(angle) / std::sin(angle);
}

}  // namespace

TEST_CASE("elements: tetrahedron weights are ℓ cot θ / 6 of the opposite edge (Eq. 9)",
          "[energies]") {
  std::mt19937 rng(1);
  for (int trial = 0; trial < 20; ++trial) {
    const Mesh mesh = SingleTet(RandomMatrix(rng) * Eigen::Matrix<double, 3, 4>::Random());
    const auto w = TetrahedronCotangentWeights(mesh.vertices, mesh.elements);
    for (int edge = 0; edge < 6; ++edge) {
      const auto [a, b] = kTetrahedronEdges[edge];
      const auto [c, d] = kTetrahedronEdges[5 - edge];  // the opposite edge
      const Eigen::Vector3d pc = mesh.vertices.row(c), pd = mesh.vertices.row(d),
                            pa = mesh.vertices.row(a), pb = mesh.vertices.row(b);
      const double reference = (pd - pc).norm() * DihedralCotangent(pc, pd, pa, pb) / 6.0;
      CHECK(w(0, edge) == Approx(reference).epsilon(1e-9).margin(1e-12));
    }
  }
}

TEST_CASE("elements: one tetrahedron under a random affine map has exactly twice WRAPD's energy",
          "[energies]") {
  std::mt19937 rng(7);
  const Context context;
  for (int trial = 0; trial < 40; ++trial) {
    Eigen::Matrix<double, 3, 4> rest = Eigen::Matrix<double, 3, 4>::Random();
    // Every fourth rest tetrahedron is negatively oriented: the weights must not care.
    if (trial % 4 == 1) rest.col(2).swap(rest.col(3));
    Eigen::Matrix3d f = RandomMatrix(rng);
    // Both signs of det F: half the deformed tetrahedra are inverted (σ₃ < 0 for WRAPD).
    if ((f.determinant() < 0) != (trial % 2 == 0)) f.col(0) *= -1.0;
    const Eigen::Vector3d shift = Eigen::Vector3d::Random();
    const Eigen::Matrix<double, 3, 4> deformed = (f * rest).colwise() + shift;
    const Mesh mesh = SingleTet(rest);
    ElementArapEnergy energy({});
    energy.Precompute(mesh, context);
    Rotations rotations(1, Rotation::Identity());
    const double e = energy.FitRotations(deformed.transpose(), rotations, context);
    const double wrapd = WrapdEnergy<3>(rest, deformed);
    REQUIRE(wrapd > 1e-6);
    CHECK(e == Approx(2.0 * wrapd).epsilon(1e-10));
    CHECK((rotations[0] - WrapdRotation<3>(f)).norm() < 1e-9);
    const auto measures = energy.AuxiliaryMeasures(deformed.transpose(), rotations, context);
    REQUIRE(measures.count("energy_wrapd") == 1);
    CHECK(measures.at("energy_wrapd") == Approx(wrapd).epsilon(1e-10));
  }
}

TEST_CASE(
    "elements: one planar triangle under a random in-plane affine map has twice WRAPD's "
    "energy",
    "[energies]") {
  std::mt19937 rng(8);
  const Context context;
  for (int trial = 0; trial < 40; ++trial) {
    const Eigen::Matrix<double, 2, 3> rest = Eigen::Matrix<double, 2, 3>::Random();
    Eigen::Matrix2d f = RandomMatrix(rng).topLeftCorner<2, 2>();
    if ((f.determinant() < 0) != (trial % 2 == 0)) f.col(0) *= -1.0;
    const Eigen::Matrix<double, 2, 3> deformed = (f * rest).colwise() + Eigen::Vector2d::Random();
    Mesh mesh;
    mesh.planar = true;
    mesh.vertices = Positions::Zero(3, 3);
    mesh.vertices.leftCols<2>() = rest.transpose();
    mesh.elements.resize(1, 3);
    mesh.elements << 0, 1, 2;
    Positions u = Positions::Zero(3, 3);
    u.leftCols<2>() = deformed.transpose();
    ElementArapEnergy energy({});
    energy.Precompute(mesh, context);
    Rotations rotations(1, Rotation::Identity());
    const double e = energy.FitRotations(u, rotations, context);
    const double wrapd = WrapdEnergy<2>(rest, deformed);
    REQUIRE(wrapd > 1e-6);
    // E is a difference of terms of size ~Σ|w|‖u‖² (thin random triangles have large weights):
    // round-off relative to that.
    const double scale = energy.system_matrix().cwiseAbs().sum() * u.squaredNorm();
    INFO("trial " << trial << " scale " << scale);
    CHECK(e == Approx(2.0 * wrapd).epsilon(1e-10).margin(1e-14 * scale));
    CHECK((rotations[0].topLeftCorner<2, 2>() - WrapdRotation<2>(f)).norm() < 1e-9);
    CHECK(rotations[0].col(2) == Eigen::Vector3d::UnitZ());
    CHECK(rotations[0].row(2) == Eigen::RowVector3d::UnitZ());
    CHECK(energy.AuxiliaryMeasures(u, rotations, context).at("energy_wrapd") ==
          Approx(wrapd).epsilon(1e-10).margin(1e-14 * scale));
  }
}

TEST_CASE("elements: whole meshes equal the sum of WRAPD's per-element energies, times two",
          "[energies]") {
  const Context context;
  const Mesh mesh = Jittered(TetBox(5, 4, 4, 5), 5, 0.2, 3);
  const Positions u = SmoothlyDeformed(mesh.vertices, 1.2);
  ElementArapEnergy energy({});
  energy.Precompute(mesh, context);
  Rotations rotations(mesh.num_elements(), Rotation::Identity());
  const double e = energy.FitRotations(u, rotations, context);
  double wrapd = 0.0;
  for (Index t = 0; t < mesh.num_elements(); ++t) {
    Eigen::Matrix<double, 3, 4> rest, deformed;
    for (int a = 0; a < 4; ++a) {
      rest.col(a) = mesh.vertices.row(mesh.elements(t, a)).transpose();
      deformed.col(a) = u.row(mesh.elements(t, a)).transpose();
    }
    wrapd += WrapdEnergy<3>(rest, deformed);
  }
  CHECK(e == Approx(2.0 * wrapd).epsilon(1e-10));
  CHECK(energy.AuxiliaryMeasures(u, rotations, context).at("energy_wrapd") ==
        Approx(wrapd).epsilon(1e-10));
  // Near zero energy the expanded E = tr(UᵀAU) − 2⟨R, M⟩ + c cancels to round-off of either
  // sign; energy_wrapd is a sum of squares and resolves it.
  const Eigen::Matrix3d r = RandomRotation(3);
  const Positions moved = (mesh.vertices * r.transpose()).rowwise() + Eigen::RowVector3d(5, 7, 9);
  energy.FitRotations(moved, rotations, context);
  const double rigid = energy.AuxiliaryMeasures(moved, rotations, context).at("energy_wrapd");
  CHECK(rigid >= 0.0);
  CHECK(rigid < 1e-25);
}

TEST_CASE("elements: negative weights, yet A is PSD with exactly the constants as null space",
          "[energies]") {
  const Context context;
  for (const Mesh& mesh :
       {Jittered(TetBox(5, 5, 4, 5), 5, 0.24, 11), Jittered(TetBox(4, 5, 5, 6), 5, 0.24, 12),
        Jittered(PlanarGrid(7, 6), 7, 0.3, 13)}) {
    Index negative = 0;
    if (mesh.planar) {
      negative = (HalfCotangents(mesh.vertices, mesh.elements).array() < 0.0).count();
    } else {
      negative = (TetrahedronCotangentWeights(mesh.vertices, mesh.elements).array() < 0.0).count();
    }
    CHECK(negative > 0);  // obtuse (dihedral) angles
    ElementArapEnergy energy({});
    energy.Precompute(mesh, context);
    CHECK(energy.num_degenerate_elements() == 0);
    const Eigen::MatrixXd a(energy.system_matrix());
    CHECK((a - a.transpose()).norm() < 1e-12 * a.norm());
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(a);
    const Eigen::VectorXd& lambda = eigen.eigenvalues();
    CHECK(std::abs(lambda(0)) < 1e-12 * lambda(lambda.size() - 1));
    CHECK(lambda(1) > 1e-6 * lambda(lambda.size() - 1));  // connected: one zero eigenvalue
    // Removing one vertex (a constraint) leaves the reduced matrix positive definite.
    Eigen::LLT<Eigen::MatrixXd> cholesky(a.bottomRightCorner(a.rows() - 1, a.cols() - 1));
    CHECK(cholesky.info() == Eigen::Success);
  }
}

TEST_CASE("elements: the orientation of rest tetrahedra does not matter", "[energies]") {
  const Context context;
  const Mesh mesh = Jittered(TetBox(4, 4, 4, 5), 4, 0.2, 4);
  Mesh flipped = mesh;
  for (Index t = 0; t < flipped.num_elements(); t += 2) {
    std::swap(flipped.elements(t, 0), flipped.elements(t, 1));
  }
  ElementArapEnergy a({}), b({});
  a.Precompute(mesh, context);
  b.Precompute(flipped, context);
  CHECK((Eigen::MatrixXd(a.system_matrix()) - Eigen::MatrixXd(b.system_matrix())).norm() <
        1e-13 * a.system_matrix().norm());
  const Positions u = SmoothlyDeformed(mesh.vertices, 1.0);
  Rotations ra(mesh.num_elements(), Rotation::Identity()), rb = ra;
  CHECK(a.FitRotations(u, ra, context) == Approx(b.FitRotations(u, rb, context)).epsilon(1e-12));
}

TEST_CASE("elements: degenerate rest tetrahedra get zero weight", "[energies]") {
  const Context context;
  Mesh mesh = TetBox(3, 3, 3, 6);
  // A flat tetrahedron (four coplanar points) hanging off the box at a new vertex, and a
  // collapsed one (two of its corners coincide).
  const Index n = mesh.num_vertices();
  Positions vertices(n + 2, 3);
  vertices << mesh.vertices, 1.5, 0.5, 1.0, 1.0, 1.0, 1.0;
  mesh.vertices = vertices;
  Elements elements(mesh.num_elements() + 2, 4);
  const Index a = 2 * 9 + 2 * 3 + 2, b = 2 * 9 + 0 * 3 + 2;  // (1,1,1) and (1,0,1): z = 1 face
  elements << mesh.elements, a, b, 2 * 9 + 1 * 3 + 2, n, a, b, n + 1, 0;
  mesh.elements = elements;
  ElementArapEnergy energy({});
  energy.Precompute(mesh, context);
  CHECK(energy.num_degenerate_elements() == 2);
  const SparseMatrix& m = energy.system_matrix();
  CHECK(Eigen::Map<const Eigen::VectorXd>(m.valuePtr(), m.nonZeros()).allFinite());
  // The new vertex is used only by the flat tetrahedron: its row of A is zero.
  CHECK(Eigen::MatrixXd(m).row(n).cwiseAbs().maxCoeff() == 0.0);
  Rotations rotations(mesh.num_elements(), Rotation::Identity());
  CHECK(
      std::isfinite(energy.FitRotations(SmoothlyDeformed(mesh.vertices, 1.0), rotations, context)));
  for (const auto& r : rotations) CHECK(r.allFinite());
}

TEST_CASE("elements: surface triangle meshes and planar tetrahedra are rejected", "[energies]") {
  ElementArapEnergy energy({});
  CHECK_THROWS_AS(energy.Precompute(Icosphere(1), Context()), InputError);
  CHECK_THROWS_WITH(energy.Precompute(Grid(4, 4), Context()),
                    Catch::Contains("elements") && Catch::Contains("planar") &&
                        Catch::Contains("spokes_and_rims"));
  Mesh tets = TetBox(3, 3, 3);
  tets.planar = true;
  CHECK_THROWS_WITH(energy.Precompute(tets, Context()), Catch::Contains("tetrahedra"));
  Mesh lifted = PlanarGrid(4, 4);
  lifted.vertices(5, 2) = 0.1;
  CHECK_THROWS_WITH(energy.Precompute(lifted, Context()),
                    Catch::Contains("planar") && Catch::Contains("vertex 5"));
}

// On a flat triangle mesh, the planar `elements` energy (2D rotation per triangle) and the
// surface energies (3D rotation per vertex) are different energies, but these must agree:
//   - the matrices: A_elements = L, A_spokes_and_rims = 3L, A_spokes = 2L (same cotangents);
//   - under any uniform in-plane affine map u = F v̄ + t with det F > 0 every cell's best
//     rotation is the polar factor of F (the cell covariances are F times an isotropic in-plane
//     matrix), so all rotations agree and E_spokes_and_rims = 3 E_elements. A spokes cell
//     (the edges at one vertex) is not isotropic, so its rotation may do better than the polar
//     factor: E_spokes ≤ 2 E_elements, the value at R = polar(F).
// With det F < 0 they must not agree: a space rotation can flip the plane over, a plane
// rotation cannot.
TEST_CASE("elements: flat mesh as 2D vs as a surface agree where they must", "[energies]") {
  const Context context;
  const Mesh planar = Jittered(PlanarGrid(8, 7), 8, 0.25, 21);
  Mesh surface = planar;
  surface.planar = false;
  ElementArapEnergy elements({});
  SpokesAndRimsEnergy spokes_and_rims({});
  SpokesEnergy::Options raw_cotangents;  // the elements' weights are the mesh's own cotangents
  raw_cotangents.weights.input_level = WeightScheme::kCotangent;
  SpokesEnergy spokes(raw_cotangents);
  elements.Precompute(planar, context);
  spokes_and_rims.Precompute(surface, context);
  spokes.Precompute(surface, context);
  const Eigen::MatrixXd l(elements.system_matrix());
  CHECK((Eigen::MatrixXd(spokes_and_rims.system_matrix()) - 3.0 * l).norm() < 1e-12 * l.norm());
  CHECK((Eigen::MatrixXd(spokes.system_matrix()) - 2.0 * l).norm() < 1e-12 * l.norm());

  std::mt19937 rng(5);
  for (int trial = 0; trial < 6; ++trial) {
    Eigen::Matrix3d f = Eigen::Matrix3d::Identity();
    f.topLeftCorner<2, 2>() = RandomMatrix(rng).topLeftCorner<2, 2>();
    const bool reflection = trial >= 4;
    if ((f.determinant() < 0) != reflection) f.col(0) *= -1.0;
    Positions u = (planar.vertices * f.transpose()).rowwise() + Eigen::RowVector3d(0.3, -0.2, 0.0);
    Rotations r_elements(elements.num_rotations(), Rotation::Identity());
    Rotations r_vertices(spokes.num_rotations(), Rotation::Identity());
    Rotations r_vertices2 = r_vertices;
    const double e = elements.FitRotations(u, r_elements, context);
    const double e_sr = spokes_and_rims.FitRotations(u, r_vertices, context);
    const double e_spokes = spokes.FitRotations(u, r_vertices2, context);
    REQUIRE(e > 1e-3);
    if (reflection) {
      CHECK(e_sr < 3.0 * e * (1.0 - 1e-3));
      continue;
    }
    CHECK(e_sr == Approx(3.0 * e).epsilon(1e-9));
    CHECK(e_spokes <= 2.0 * e * (1.0 + 1e-12));
    for (const auto& r : r_vertices) CHECK((r - r_elements[0]).norm() < 1e-9);
    for (const auto& r : r_elements) CHECK((r - r_elements[0]).norm() < 1e-9);
  }
}
