// SPDX-License-Identifier: MIT
//
// Decisions:
//   - Handles are geodesic balls (the k vertices nearest along edges to a seed), not slabs or
//     Euclidean balls: on shapes with limbs a slab or a ball at the end of an axis catches
//     several limbs or pieces of other components, a geodesic ball is one connected patch.
//   - Their size is a fraction of the component's vertices, so neither handle is ever empty
//     and the test case looks alike at every resolution and refinement.
//   - The seeds are the extreme vertices of the longest principal axis (PCA of the component's
//     vertices): that axis follows the shape's length whatever its orientation in the file,
//     where the bounding box's longest axis depends on how the file happens to be aligned.
//   - Axis signs are fixed (largest coordinate positive) so that the same shape gives the same
//     scenario; ties in distances go to the lower vertex index.
//   - Selections are written as vertex indices of the refined mesh and motions in mesh
//     coordinates (`units = "absolute"`), so the file says exactly which vertices go where.
#include "io/scenario_generator.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <utility>

#include "framework/disjoint_sets.h"
#include "framework/error.h"
#include "io/mesh_io.h"
#include "io/subdivision.h"

namespace harap {

namespace {

// Edges of the elements as a neighbour list per vertex (each edge once per endpoint).
std::vector<std::vector<Index>> Neighbours(const Mesh& mesh) {
  std::vector<std::vector<Index>> neighbours(static_cast<size_t>(mesh.num_vertices()));
  const int corners = mesh.simplex_size();
  for (Index e = 0; e < mesh.num_elements(); ++e) {
    for (int a = 0; a < corners; ++a) {
      for (int b = a + 1; b < corners; ++b) {
        neighbours[mesh.elements(e, a)].push_back(mesh.elements(e, b));
        neighbours[mesh.elements(e, b)].push_back(mesh.elements(e, a));
      }
    }
  }
  for (auto& list : neighbours) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  return neighbours;
}

// The `count` vertices nearest to `seed` along edges (Dijkstra; ties to the lower index).
std::vector<Index> GeodesicBall(const Mesh& mesh, const std::vector<std::vector<Index>>& neighbours,
                                Index seed, size_t count) {
  using Entry = std::pair<double, Index>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> queue;
  std::vector<double> distance(neighbours.size(), std::numeric_limits<double>::infinity());
  std::vector<bool> settled(neighbours.size(), false);
  std::vector<Index> ball;
  distance[seed] = 0.0;
  queue.emplace(0.0, seed);
  while (!queue.empty() && ball.size() < count) {
    const auto [d, v] = queue.top();
    queue.pop();
    if (settled[v]) continue;
    settled[v] = true;
    ball.push_back(v);
    for (const Index w : neighbours[v]) {
      const double through = d + (mesh.vertices.row(v) - mesh.vertices.row(w)).norm();
      if (through < distance[w]) {
        distance[w] = through;
        queue.emplace(through, w);
      }
    }
  }
  std::sort(ball.begin(), ball.end());
  return ball;
}

// `axis` with the sign that makes its largest-magnitude coordinate positive.
Eigen::Vector3d Oriented(Eigen::Vector3d axis) {
  Eigen::Index largest = 0;
  axis.cwiseAbs().maxCoeff(&largest);
  return axis(largest) < 0.0 ? Eigen::Vector3d(-axis) : axis;
}

std::string TomlString(const std::string& text) {
  std::string quoted = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') quoted += '\\';
    quoted += c;
  }
  return quoted + "\"";
}

std::string Vector(const Eigen::Vector3d& v) {
  return fmt::format("[{:.17g}, {:.17g}, {:.17g}]", v.x(), v.y(), v.z());
}

// `select.indices = [...]`, 16 indices per line.
std::string IndexList(const std::vector<Index>& indices) {
  std::string text = "select.indices = [";
  for (size_t i = 0; i < indices.size(); ++i) {
    text += fmt::format("{}{}{}", i == 0 ? "" : ",", i % 16 == 0 ? "\n  " : " ", indices[i]);
  }
  return text + "\n]\n";
}

}  // namespace

const std::vector<std::string>& ScenarioKindNames() {
  static const std::vector<std::string> names = {"bend", "twist", "lift", "stretch"};
  return names;
}

ScenarioKind ParseScenarioKind(std::string_view name) {
  const auto& names = ScenarioKindNames();
  const auto found = std::find(names.begin(), names.end(), name);
  if (found == names.end()) {
    throw ConfigError(
        fmt::format("unknown scenario kind '{}' (valid: {})", name, fmt::join(names, ", ")));
  }
  return static_cast<ScenarioKind>(found - names.begin());
}

std::string GenerateScenarioToml(const Mesh& mesh, const std::string& mesh_reference,
                                 const ScenarioGeneratorOptions& options, const std::string& what) {
  auto unusable = [&](const std::string& problem) {
    return InputError(fmt::format("{}: cannot place handles: {}", what, problem));
  };
  if (mesh.num_elements() == 0) throw unusable("the mesh has no elements");
  if (!(options.handle_fraction > 0.0 && options.handle_fraction < 0.5)) {
    throw ConfigError(
        fmt::format("handle fraction {} is outside (0, 0.5)", options.handle_fraction));
  }
  // The largest component: the vertices of elements joined by shared vertices.
  DisjointSets<Index> components(mesh.num_vertices());
  for (Index e = 0; e < mesh.num_elements(); ++e) {
    for (int a = 1; a < mesh.simplex_size(); ++a) {
      components.Unite(mesh.elements(e, 0), mesh.elements(e, a));
    }
  }
  const std::vector<bool> referenced = ReferencedVertices(mesh);
  std::vector<Index> size(static_cast<size_t>(mesh.num_vertices()), 0);
  for (Index v = 0; v < mesh.num_vertices(); ++v) size[components.Find(v)] += referenced[v];
  const Index root = static_cast<Index>(std::max_element(size.begin(), size.end()) - size.begin());
  std::vector<Index> component;
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    if (referenced[v] && components.Find(v) == root) component.push_back(v);
  }
  const size_t count = std::max<size_t>(
      3, static_cast<size_t>(std::ceil(options.handle_fraction * component.size())));
  // At least as many free vertices as held and moved ones: else there is little left to solve.
  if (4 * count > component.size()) {
    throw unusable(
        fmt::format("its largest component has {} vertices, too few for two handles "
                    "of {} vertices and as many free ones",
                    component.size(), count));
  }

  // Principal axes of the component's vertices.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Index v : component) mean += mesh.vertices.row(v).transpose();
  mean /= static_cast<double>(component.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Index v : component) {
    const Eigen::Vector3d d = mesh.vertices.row(v).transpose() - mean;
    covariance += d * d.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
  const Eigen::Vector3d a1 = Oriented(eigen.eigenvectors().col(2));
  const Eigen::Vector3d a2 = Oriented(eigen.eigenvectors().col(1));
  const Eigen::Vector3d a3 = a1.cross(a2);
  // The extreme vertices along a1 (ties to the lower index: `component` is sorted).
  Index low = component.front(), high = component.front();
  double low_t = mesh.vertices.row(low).dot(a1), high_t = low_t;
  for (const Index v : component) {
    const double t = mesh.vertices.row(v).dot(a1);
    if (t < low_t) low = v, low_t = t;
    if (t > high_t) high = v, high_t = t;
  }
  const double length = high_t - low_t;
  if (!(length > 0.0) || !std::isfinite(length)) {
    throw unusable("its largest component has no extent along its principal axis");
  }

  const auto neighbours = Neighbours(mesh);
  const std::vector<Index> fixed = GeodesicBall(mesh, neighbours, low, count);
  std::vector<Index> moved = GeodesicBall(mesh, neighbours, high, count);
  moved.erase(
      std::remove_if(moved.begin(), moved.end(),
                     [&](Index v) { return std::binary_search(fixed.begin(), fixed.end(), v); }),
      moved.end());
  if (moved.empty()) throw unusable("the two ends of its longest axis are the same patch");

  const std::string& kind = ScenarioKindNames()[static_cast<size_t>(options.kind)];
  std::string motion;
  switch (options.kind) {
    case ScenarioKind::kBend:
      motion = fmt::format("rotate = {{ axis = {}, degrees = 60.0 }}\n", Vector(a3));
      break;
    case ScenarioKind::kTwist:
      motion = fmt::format("rotate = {{ axis = {}, degrees = 90.0 }}\n", Vector(a1));
      break;
    case ScenarioKind::kLift:
      motion = fmt::format("translate = {}\n", Vector(0.25 * length * a2));
      break;
    case ScenarioKind::kStretch:
      motion = fmt::format("translate = {}\n", Vector(0.2 * length * a1));
      break;
  }
  std::string text = fmt::format(
      "# Generated by harap scenario (kind {}, {} of the vertices per handle): the handles are\n"
      "# the vertices nearest along edges to the two ends of the longest principal axis\n"
      "# {} (length {:.6g}); docs/experiments.md.\n"
      "mesh = {}\n",
      kind, options.handle_fraction, Vector(a1), length, TomlString(mesh_reference));
  if (options.refine > 0) text += fmt::format("refine = {}\n", options.refine);
  text += "units = \"absolute\"\n\n[[handle]]\nname = \"held\"\n" + IndexList(fixed);
  text += fmt::format("\n[[handle]]\nname = \"{}\"\n{}{}", kind, motion, IndexList(moved));
  return text;
}

std::string GenerateScenarioForFile(const std::filesystem::path& mesh_file,
                                    const std::string& mesh_reference,
                                    const ScenarioGeneratorOptions& options) {
  Mesh mesh = ReadMesh(mesh_file);
  if (options.refine > 0) {
    if (mesh.kind() == ElementKind::kTetrahedron) {
      throw InputError(
          fmt::format("{}: refine applies to triangle meshes, this one has "
                      "tetrahedra",
                      mesh_file.string()));
    }
    mesh = LoopSubdivide(mesh, options.refine);
  }
  return GenerateScenarioToml(mesh, mesh_reference, options, mesh_file.string());
}

}  // namespace harap
