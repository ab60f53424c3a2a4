// SPDX-License-Identifier: MIT
#include <catch2/catch.hpp>

#include "experiments/builtins.h"
#include "framework/error.h"
#include "tests/support/test_meshes.h"

using namespace harap;
using namespace harap::testing;

namespace {

MeshHierarchy TwoLevels() {
  const Registries registries = MakeBuiltinRegistries();
  Mesh mesh = Icosphere(3);
  ConfigNode options = ConfigNode::Parse("min_vertices = 10\nmax_levels = 2\n", "test");
  MeshHierarchy hierarchy = registries.hierarchies.Create("octree", options)->Build(mesh, Context());
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
      upsampler->Upsample(fine, coarse, RotationSite::kVertex, coarse_state, fine_state,
                          Context());
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
    CHECK((smoothed.rotations[j].transpose() * smoothed.rotations[j] -
           Eigen::Matrix3d::Identity())
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
