// SPDX-License-Identifier: MIT
// Hierarchy construction, octree vs edge_collapse, default options (both hierarchies get the
// same level vertex counts: edge_collapse targets the octree's and builds it for that):
//
//   ./build/harap_benchmarks --benchmark_filter=HierarchyBuildFileOrder
//
// The intrinsic Delaunay weights of the same meshes (the default weights of `spokes`, computed on
// every level):
//
//   ./build/harap_benchmarks --benchmark_filter=IntrinsicDelaunay
#include "benchmarks/hierarchy_benchmark.h"

#include <benchmark/benchmark.h>

#include <functional>
#include <map>
#include <string>
#include <utility>

#include "api/builtins.h"
#include "energies/kernels/intrinsic_delaunay.h"
#include "io/scenario.h"

namespace harap::benchmarks {
namespace {

using MeshLoader = std::function<Mesh()>;

const Mesh& CachedMesh(const std::string& key, const MeshLoader& load) {
  static std::map<std::string, Mesh> meshes;
  auto it = meshes.find(key);
  if (it == meshes.end()) it = meshes.emplace(key, load()).first;
  return it->second;
}

void HierarchyBuild(benchmark::State& state, const std::string& hierarchy_name,
                    const std::string& key, const MeshLoader& load) {
  const Mesh& mesh = CachedMesh(key, load);  // outside the timed loop
  const Registries registries = MakeBuiltinRegistries();
  const auto hierarchy = registries.hierarchies.Create(hierarchy_name, ConfigNode());
  const Context context;
  int levels = 0;
  Index coarsest = 0;
  for (auto _ : state) {
    const MeshHierarchy result = hierarchy->Build(mesh, context);
    levels = result.num_levels();
    coarsest = result.levels.back().mesh.num_vertices();
    benchmark::DoNotOptimize(result.levels.data());
  }
  state.counters["vertices"] = double(mesh.num_vertices());
  state.counters["levels"] = levels;
  state.counters["coarsest"] = double(coarsest);
}

void IntrinsicDelaunay(benchmark::State& state, const std::string& key, const MeshLoader& load) {
  const Mesh& mesh = CachedMesh(key, load);  // outside the timed loop
  Index flips = 0;
  for (auto _ : state) {
    const IntrinsicTriangulation result =
        IntrinsicDelaunayTriangulation(mesh.vertices, mesh.elements);
    flips = result.flips;
    benchmark::DoNotOptimize(result.half_cot.data());
  }
  state.counters["faces"] = double(mesh.num_elements());
  state.counters["flips"] = double(flips);
}

}  // namespace

void RegisterHierarchyBenchmarks(const std::filesystem::path& shared_dir) {
  std::vector<std::pair<std::string, MeshLoader>> meshes = {
      {"cylinder-170k", [] {
         return ParseScenario("mesh = { builtin = \"cylinder\", vertices = 170000 }\n",
                              "cylinder-170k", ".")
             .mesh;
       }}};
  for (const char* name : {"armadillo-bend", "dragon-lift"}) {
    const std::filesystem::path file = shared_dir / "scenarios" / (std::string(name) + ".toml");
    if (std::filesystem::exists(file)) {
      meshes.emplace_back(name, [file] { return LoadScenario(file).mesh; });
    }
  }
  for (const auto& [key, load] : meshes) {
    for (const char* hierarchy : {"octree", "edge_collapse"}) {
      benchmark::RegisterBenchmark(
          (std::string("HierarchyBuildFileOrder_") + hierarchy + "/" + key).c_str(),
          [hierarchy = std::string(hierarchy), key = key, load = load](benchmark::State& state) {
            HierarchyBuild(state, hierarchy, key, load);
          })
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime();
    }
    benchmark::RegisterBenchmark(
        ("IntrinsicDelaunay/" + key).c_str(),
        [key = key, load = load](benchmark::State& state) { IntrinsicDelaunay(state, key, load); })
        ->Unit(benchmark::kMillisecond);
  }
}

}  // namespace harap::benchmarks
