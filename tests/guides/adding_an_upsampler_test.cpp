// SPDX-License-Identifier: MIT
// The example of docs/adding-an-upsampler.md, built and run by the suite: an up-sampler written
// as the guide says, registered by name and used by the hierarchical optimizer through the normal
// machinery. The guide quotes the marked regions word for word (checked below).
#include <catch2/catch.hpp>
#include <cmath>

#include "api/builtins.h"
#include "tests/guides/guide_support.h"
#include "tests/support/test_meshes.h"

// [guide:upsampler-header]
#include <string_view>

#include "framework/config.h"
#include "framework/upsampler.h"

namespace harap {

/// Moves every fine vertex with the translation of its coarse vertex (Eq. 6 without the
/// rotation): u_j = u_c + (v̄_j − v̄_c) for c = coarse_vertex[j]; vertices without a coarse vertex
/// stay at rest. The fine rotations are the identity, so the finer level starts with a local
/// step (the rotations are fitted to the positions first).
class TranslationUpsampler final : public Upsampler {
 public:
  static constexpr std::string_view kName = "translations";

  struct Options {
    static Options FromConfig(OptionReader node);
  };

  explicit TranslationUpsampler(const Options& /*options*/) {}

  UpsampleOutput output() const override { return UpsampleOutput::kPositions; }
  void Upsample(const HierarchyLevel& fine, const HierarchyLevel& coarse, RotationSite site,
                const LevelState& coarse_state, LevelState& fine_state,
                const Context& context) const override;
};

}  // namespace harap
// [/guide:upsampler-header]

namespace harap {

// [guide:upsampler-source]
TranslationUpsampler::Options TranslationUpsampler::Options::FromConfig(OptionReader node) {
  node.RejectUnknownKeys();
  return Options{};
}

void TranslationUpsampler::Upsample(const HierarchyLevel& fine, const HierarchyLevel& coarse,
                                    RotationSite site, const LevelState& coarse_state,
                                    LevelState& fine_state, const Context& /*context*/) const {
  const Mesh& mesh = fine.mesh;
  fine_state.positions = mesh.vertices;
  for (Index j = 0; j < mesh.num_vertices(); ++j) {
    const Index c = fine.coarse_vertex[j];
    if (c == kNoVertex) continue;
    fine_state.positions.row(j) =
        coarse_state.positions.row(c) + (mesh.vertices.row(j) - coarse.mesh.vertices.row(c));
  }
  const Index sites = site == RotationSite::kVertex ? mesh.num_vertices() : mesh.num_elements();
  fine_state.rotations.assign(sites, Rotation::Identity());
}
// [/guide:upsampler-source]

}  // namespace harap

using namespace harap;
using namespace harap::testing;

namespace {

// As hierarchies/upsamplers/register_upsamplers.cpp's RegisterUpsamplers.
void RegisterExampleUpsampler(Registry<Upsampler>& registry) {
  // [guide:upsampler-register]
  registry.Add<TranslationUpsampler>("coarse translations to the fine vertices (guide example)");
  // [/guide:upsampler-register]
}

Registries RegistriesWithExample() {
  Registries registries = MakeBuiltinRegistries();
  RegisterExampleUpsampler(registries.upsamplers);
  return registries;
}

}  // namespace

TEST_CASE("guide adding-an-upsampler: a rigidly moved coarse level moves the fine one",
          "[guides]") {
  const Registries registries = RegistriesWithExample();
  REQUIRE(registries.upsamplers.Contains("translations"));
  const Mesh mesh = Tube(12, 10);
  const ConfigNode octree = ConfigNode::Parse("[hierarchy]\nmin_vertices = 20\n", "t");
  const MeshHierarchy hierarchy =
      registries.hierarchies.Create("octree", octree.Child("hierarchy"))->Build(mesh, Context());
  REQUIRE(hierarchy.num_levels() >= 2);
  const HierarchyLevel& fine = hierarchy.levels[0];
  const HierarchyLevel& coarse = hierarchy.levels[1];
  LevelState coarse_state;
  const Eigen::RowVector3d shift(0.5, -1.0, 2.0);
  coarse_state.positions = coarse.mesh.vertices.rowwise() + shift;
  LevelState fine_state;
  registries.upsamplers.Create("translations", ConfigNode())
      ->Upsample(fine, coarse, RotationSite::kVertex, coarse_state, fine_state, Context());
  REQUIRE(fine_state.rotations.size() == std::size_t(mesh.num_vertices()));
  for (Index j = 0; j < mesh.num_vertices(); ++j) {
    if (fine.coarse_vertex[j] == kNoVertex) continue;
    CHECK((fine_state.positions.row(j) - (mesh.vertices.row(j) + shift)).norm() < 1e-12);
  }
}

TEST_CASE("guide adding-an-upsampler: the hierarchical optimizer runs with the example",
          "[guides]") {
  const Registries registries = RegistriesWithExample();
  const BentTube tube(24, 16, 2.0, M_PI / 4, Eigen::Vector3d(0.0, 0.4, -0.2));
  std::map<int, std::vector<double>> energies;
  const OptimizeResult result =
      RunConfigured(registries, tube.problem,
                    "[optimizer]\ntype = \"hierarchical\"\ntargets_follow_rotations = "
                    "false\nmax_iterations = 300\n"
                    "[hierarchy]\nmin_vertices = 60\n[upsampler]\ntype = \"translations\"\n",
                    &energies);
  CHECK(result.levels.size() >= 3);
  CHECK(MonotonePerLevel(energies));
  CHECK(std::isfinite(result.energy));
  const Constraints& constraints = tube.problem.constraints;
  for (size_t k = 0; k < constraints.indices.size(); ++k) {
    CHECK(result.positions.row(constraints.indices[k]) == constraints.targets.row(k));
  }
}

TEST_CASE("guide adding-an-upsampler: the guide quotes the example as it is", "[guides]") {
  const std::string doc = "docs/adding-an-upsampler.md";
  const std::string example = "tests/guides/adding_an_upsampler_test.cpp";
  for (const char* region : {"upsampler-header", "upsampler-source", "upsampler-register"}) {
    DYNAMIC_SECTION(region) { CheckGuideQuotes(doc, example, region); }
  }
}
