// SPDX-License-Identifier: MIT
// Weight schemes of the edge-based energies: the intrinsic Delaunay triangulation on hand-checked
// quadrilaterals, non-negative weights on irregular and shared meshes, and the options.
#include "energies/kernels/weight_schemes.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <random>
#include <utility>

#include "api/builtins.h"
#include "energies/kernels/cotangent_weights.h"
#include "energies/kernels/intrinsic_delaunay.h"
#include "io/mesh_io.h"
#include "tests/support/shared_data.h"
#include "tests/support/test_meshes.h"

using namespace harap;
using namespace harap::testing;

namespace {

// Summed weight of every edge (unordered vertex pair) of a triangulation.
std::map<std::pair<Index, Index>, double> EdgeWeights(
    const Elements& triangles, const Eigen::Matrix<double, -1, 3>& half_cot) {
  std::map<std::pair<Index, Index>, double> weights;
  for (Index f = 0; f < triangles.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const Index b = triangles(f, (k + 1) % 3), c = triangles(f, (k + 2) % 3);
      weights[{std::min(b, c), std::max(b, c)}] += half_cot(f, k);
    }
  }
  return weights;
}

// Two triangles (a, b, c) and (d, c, b) on the edge bc = [0, 2] of the x-axis, with a = (1, 0.5)
// and d = (1, −0.5) (d folded out of the plane by `fold` about bc, which keeps its distance 0.5 to
// bc): the angles at a and d are 126.87°, cot = −0.75 each, so bc is not Delaunay.
Mesh ObtuseQuad(double fold) {
  Mesh mesh;
  mesh.vertices.resize(4, 3);
  mesh.vertices << 1.0, 0.5, 0.0,                        // a
      0.0, 0.0, 0.0,                                     // b
      2.0, 0.0, 0.0,                                     // c
      1.0, -0.5 * std::cos(fold), 0.5 * std::sin(fold);  // d
  mesh.elements.resize(2, 3);
  mesh.elements << 0, 1, 2,  // (a, b, c)
      3, 2, 1;               // (d, c, b)
  return mesh;
}

}  // namespace

TEST_CASE("intrinsic Delaunay flips the diagonal of an obtuse quad (hand-checked)", "[weights]") {
  for (const double fold : {0.0, 0.9}) {
    INFO("fold " << fold);
    const Mesh quad = ObtuseQuad(fold);
    // The raw cotangent weight of bc is ½(−0.75 − 0.75) = −0.75.
    const auto raw = EdgeWeights(quad.elements, HalfCotangents(quad.vertices, quad.elements));
    CHECK(raw.at({1, 2}) == Approx(-0.75).margin(1e-12));

    const IntrinsicTriangulation intrinsic =
        IntrinsicDelaunayTriangulation(quad.vertices, quad.elements);
    CHECK(intrinsic.flips == 1);
    CHECK(intrinsic.zeroed_edges == 0);
    const auto weights = EdgeWeights(intrinsic.triangles, intrinsic.half_cot);
    // The new edge ad: its intrinsic length is the distance in the unfolded quad, 1, whatever
    // the fold (the chord |a − d| is shorter when folded).
    REQUIRE(weights.count({0, 3}) == 1);
    CHECK(weights.count({1, 2}) == 0);
    for (Index f = 0; f < 2; ++f) {
      for (int k = 0; k < 3; ++k) {
        const Index b = intrinsic.triangles(f, (k + 1) % 3),
                    c = intrinsic.triangles(f, (k + 2) % 3);
        if (std::min(b, c) == 0 && std::max(b, c) == 3)
          CHECK(intrinsic.lengths(f, k) == Approx(1.0));
      }
    }
    // Triangles (a, b, d) and (d, c, a): sides √1.25, √1.25, 1. At b (and c) cos = 0.6,
    // sin = 0.8, cot = 0.75; at a and d cot = 0.5. So w_ad = ½(0.75 + 0.75) = 0.75 and each
    // boundary edge gets ½·0.5 = 0.25.
    CHECK(weights.at({0, 3}) == Approx(0.75));
    for (const auto& edge : {std::pair<Index, Index>{0, 1}, {0, 2}, {1, 3}, {2, 3}}) {
      CHECK(weights.at(edge) == Approx(0.25));
    }
  }
}

TEST_CASE("intrinsic Delaunay keeps a Delaunay mesh as it is", "[weights]") {
  const Mesh sphere = Icosphere(2);
  const IntrinsicTriangulation intrinsic =
      IntrinsicDelaunayTriangulation(sphere.vertices, sphere.elements);
  CHECK(intrinsic.flips == 0);
  CHECK(intrinsic.triangles == sphere.elements);
  const Eigen::Matrix<double, -1, 3> raw = HalfCotangents(sphere.vertices, sphere.elements);
  CHECK((intrinsic.half_cot - raw).cwiseAbs().maxCoeff() < 1e-12);
}

TEST_CASE("every weight scheme but cotan gives non-negative edge weights", "[weights]") {
  // Jittered meshes: obtuse angles and negative raw cotangent weights, closed and open.
  const std::vector<std::pair<std::string, Mesh>> meshes = {
      {"jittered sphere", Jittered(Icosphere(3), 20, 0.45, 3)},
      {"jittered tube (open)", Jittered(Tube(12, 16), 8, 0.3, 4)},
      {"jittered planar grid (open)", Jittered(PlanarGrid(9, 8), 9, 0.25, 5)}};
  for (const auto& [name, mesh] : meshes) {
    INFO(name);
    const auto raw = EdgeWeights(mesh.elements, HalfCotangents(mesh.vertices, mesh.elements));
    Index raw_negative = 0;
    for (const auto& [edge, w] : raw) raw_negative += w < 0.0;
    CHECK(raw_negative > 0);  // the mesh does test something
    for (const auto scheme :
         {WeightScheme::kIntrinsicDelaunay, WeightScheme::kClamped, WeightScheme::kUniform}) {
      INFO("scheme " << NameOf(kWeightSchemeNames, scheme));
      const TriangleWeights weights =
          ComputeTriangleWeights(mesh.vertices, mesh.elements, scheme, 0.01);
      CHECK(weights.triangles.rows() == mesh.elements.rows());
      for (const auto& [edge, w] : EdgeWeights(weights.triangles, weights.half_cot)) {
        CHECK(w >= 0.0);
      }
      if (scheme == WeightScheme::kIntrinsicDelaunay) CHECK(weights.flips > 0);
    }
  }
}

TEST_CASE("intrinsic Delaunay weights are non-negative on every shared mesh", "[weights][shared]") {
  HARAP_REQUIRE_SHARED(folder, "meshes");
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    const std::string file = entry.path().filename().string();
    if (file.find(".tet") != std::string::npos || file.find("-tet.") != std::string::npos) continue;
    if (entry.path().extension() != ".xz") continue;
    INFO(file);
    const Mesh mesh = ReadMesh(entry.path());
    if (mesh.kind() != ElementKind::kTriangle) continue;
    const TriangleWeights weights = ComputeTriangleWeights(mesh.vertices, mesh.elements,
                                                           WeightScheme::kIntrinsicDelaunay, 0.01);
    Index negative = 0;
    for (const auto& [edge, w] : EdgeWeights(weights.triangles, weights.half_cot)) {
      negative += w < 0.0;
    }
    CHECK(negative == 0);
  }
}
