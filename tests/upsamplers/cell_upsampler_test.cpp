// SPDX-License-Identifier: MIT
#include <Eigen/Geometry>
#include <catch2/catch.hpp>

#include "api/builtins.h"
#include "framework/error.h"
#include "framework/rotation.h"
#include "tests/support/test_meshes.h"

using namespace harap;
using namespace harap::testing;

namespace {

MeshHierarchy TwoLevels() {
  const Registries registries = MakeBuiltinRegistries();
  Mesh mesh = Icosphere(3);
  ConfigNode options = ConfigNode::Parse("min_vertices = 10\nmax_levels = 2\n", "test");
  MeshHierarchy hierarchy =
      registries.hierarchies.Create("octree", options)->Build(mesh, Context());
  REQUIRE(hierarchy.num_levels() == 2);
  return hierarchy;
}

}  // namespace

TEST_CASE("every upsampler carries a rigid coarse state to the rigid fine state", "[upsamplers]") {
  const Registries registries = MakeBuiltinRegistries();
  const MeshHierarchy hierarchy = TwoLevels();
  const HierarchyLevel& fine = hierarchy.levels[0];
  const HierarchyLevel& coarse = hierarchy.levels[1];
  const Eigen::Matrix3d r = RandomRotation(3);
  const Eigen::RowVector3d t(1.0, -2.0, 0.5);
  LevelState coarse_state;
  coarse_state.positions = (coarse.mesh.vertices * r.transpose()).rowwise() + t;
  coarse_state.rotations.assign(coarse.mesh.num_vertices(), r);
  for (const auto& name : registries.upsamplers.Names()) {
    DYNAMIC_SECTION(name) {
      auto upsampler = registries.upsamplers.Create(name, ConfigNode());
      LevelState fine_state;
      upsampler->Upsample(fine, coarse, RotationSite::kVertex, coarse_state, fine_state, Context());
      REQUIRE(fine_state.positions.rows() == fine.mesh.num_vertices());
      REQUIRE(static_cast<Index>(fine_state.rotations.size()) == fine.mesh.num_vertices());
      const Positions expected = (fine.mesh.vertices * r.transpose()).rowwise() + t;
      CHECK((fine_state.positions - expected).cwiseAbs().maxCoeff() < 1e-12);
      for (const auto& rotation : fine_state.rotations) CHECK((rotation - r).norm() < 1e-12);
    }
  }
}

TEST_CASE("rotations upsampler copies each cell rotation (Eq. 7) and smoothing averages",
          "[upsamplers]") {
  const Registries registries = MakeBuiltinRegistries();
  const MeshHierarchy hierarchy = TwoLevels();
  const HierarchyLevel& fine = hierarchy.levels[0];
  const HierarchyLevel& coarse = hierarchy.levels[1];
  LevelState coarse_state;
  coarse_state.positions = coarse.mesh.vertices;
  for (Index c = 0; c < coarse.mesh.num_vertices(); ++c) {
    coarse_state.rotations.push_back(RandomRotation(static_cast<unsigned>(c)));
  }
  LevelState copied, smoothed;
  registries.upsamplers.Create("rotations", ConfigNode())
      ->Upsample(fine, coarse, RotationSite::kVertex, coarse_state, copied, Context());
  registries.upsamplers.Create("smoothed_rotations", ConfigNode())
      ->Upsample(fine, coarse, RotationSite::kVertex, coarse_state, smoothed, Context());
  double copied_jump = 0.0, smoothed_jump = 0.0;
  for (Index j = 0; j < fine.mesh.num_vertices(); ++j) {
    CHECK(copied.rotations[j] == coarse_state.rotations[fine.coarse_vertex[j]]);
    CHECK((smoothed.rotations[j].transpose() * smoothed.rotations[j] - Eigen::Matrix3d::Identity())
              .norm() < 1e-12);
  }
  for (Index f = 0; f < fine.mesh.num_elements(); ++f) {
    for (int a = 0; a < 3; ++a) {
      const Index i = fine.mesh.elements(f, a), j = fine.mesh.elements(f, (a + 1) % 3);
      copied_jump += (copied.rotations[i] - copied.rotations[j]).norm();
      smoothed_jump += (smoothed.rotations[i] - smoothed.rotations[j]).norm();
    }
  }
  CHECK(smoothed_jump < copied_jump);
}

TEST_CASE("upsampler options are validated", "[upsamplers]") {
  const Registries registries = MakeBuiltinRegistries();
  CHECK_THROWS_AS(registries.upsamplers.Create("rotations", ConfigNode::Parse("passes = 2", "t")),
                  ConfigError);
  CHECK_THROWS_AS(
      registries.upsamplers.Create("smoothed_rotations", ConfigNode::Parse("passes = 0", "t")),
      ConfigError);
}

namespace {

MeshHierarchy TwoLevelsOf(const Mesh& mesh) {
  const Registries registries = MakeBuiltinRegistries();
  ConfigNode options = ConfigNode::Parse("min_vertices = 10\nmax_levels = 2\n", "test");
  MeshHierarchy hierarchy =
      registries.hierarchies.Create("octree", options)->Build(mesh, Context());
  REQUIRE(hierarchy.num_levels() == 2);
  return hierarchy;
}

std::vector<std::pair<std::string, Mesh>> SimplexMeshes() {
  return {{"tetrahedra", Jittered(TetBox(9, 8, 7, 5), 9, 0.2, 1)},
          {"planar triangles", Jittered(PlanarGrid(17, 13), 17, 0.2, 2)}};
}

/// A rotation of the plane for planar meshes, else of space.
Eigen::Matrix3d RandomSiteRotation(const Mesh& mesh, unsigned seed) {
  if (!mesh.planar) return RandomRotation(seed);
  return Eigen::AngleAxisd(0.1 * seed, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

}  // namespace

TEST_CASE("every upsampler carries rigid element rotations to the rigid fine state",
          "[upsamplers]") {
  const Registries registries = MakeBuiltinRegistries();
  for (const auto& [mesh_name, mesh] : SimplexMeshes()) {
    const MeshHierarchy hierarchy = TwoLevelsOf(mesh);
    const HierarchyLevel& fine = hierarchy.levels[0];
    const HierarchyLevel& coarse = hierarchy.levels[1];
    const Eigen::Matrix3d r = RandomSiteRotation(mesh, 5);
    const Eigen::RowVector3d t(1.0, -2.0, mesh.planar ? 0.0 : 0.5);
    LevelState coarse_state;
    coarse_state.positions = (coarse.mesh.vertices * r.transpose()).rowwise() + t;
    coarse_state.rotations.assign(coarse.mesh.num_elements(), r);
    for (const auto& name : registries.upsamplers.Names()) {
      DYNAMIC_SECTION(mesh_name << " " << name) {
        LevelState fine_state;
        registries.upsamplers.Create(name, ConfigNode())
            ->Upsample(fine, coarse, RotationSite::kElement, coarse_state, fine_state, Context());
        REQUIRE(fine_state.positions.rows() == fine.mesh.num_vertices());
        REQUIRE(static_cast<Index>(fine_state.rotations.size()) == fine.mesh.num_elements());
        const Positions expected = (fine.mesh.vertices * r.transpose()).rowwise() + t;
        CHECK((fine_state.positions - expected).cwiseAbs().maxCoeff() < 1e-12);
        for (const auto& rotation : fine_state.rotations) CHECK((rotation - r).norm() < 1e-12);
      }
    }
  }
}

TEST_CASE(
    "element rotations: vertex averages (Eq. 11), copied down (Eq. 7), element averages "
    "(Eq. 12)",
    "[upsamplers]") {
  const Registries registries = MakeBuiltinRegistries();
  for (const auto& [mesh_name, mesh] : SimplexMeshes()) {
    DYNAMIC_SECTION(mesh_name) {
      const MeshHierarchy hierarchy = TwoLevelsOf(mesh);
      const HierarchyLevel& fine = hierarchy.levels[0];
      const HierarchyLevel& coarse = hierarchy.levels[1];
      const int k = mesh.simplex_size();
      LevelState coarse_state;
      coarse_state.positions = coarse.mesh.vertices;
      for (Index e = 0; e < coarse.mesh.num_elements(); ++e) {
        coarse_state.rotations.push_back(RandomSiteRotation(mesh, static_cast<unsigned>(e)));
      }
      LevelState fine_state;
      registries.upsamplers.Create("rotations", ConfigNode())
          ->Upsample(fine, coarse, RotationSite::kElement, coarse_state, fine_state, Context());
      // Independently: mean of the incident coarse element rotations per coarse vertex, projected
      // (Eq. 11); each fine vertex takes its coarse vertex's (Eq. 7); each fine element the
      // projected mean of its vertices' (Eq. 12).
      std::vector<Eigen::Matrix3d> vertex_sum(coarse.mesh.num_vertices(), Eigen::Matrix3d::Zero());
      for (Index e = 0; e < coarse.mesh.num_elements(); ++e) {
        for (int a = 0; a < k; ++a)
          vertex_sum[coarse.mesh.elements(e, a)] += coarse_state.rotations[e];
      }
      for (Index e = 0; e < fine.mesh.num_elements(); ++e) {
        Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
        for (int a = 0; a < k; ++a) {
          const Index c = fine.coarse_vertex[fine.mesh.elements(e, a)];
          REQUIRE(c != kNoVertex);
          sum += NearestRotation(vertex_sum[c]);
        }
        const Eigen::Matrix3d expected = NearestRotation(sum);
        CHECK((fine_state.rotations[e] - expected).norm() < 1e-10);
        if (mesh.planar) {
          // Exactly a rotation of the plane: z row and column of the identity.
          CHECK(fine_state.rotations[e].row(2) == Eigen::RowVector3d::UnitZ());
          CHECK(fine_state.rotations[e].col(2) == Eigen::Vector3d::UnitZ());
        }
      }
    }
  }
}
