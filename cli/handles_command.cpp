// SPDX-License-Identifier: MIT
#include "cli/handles_command.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <vector>

#include "cli/output_checks.h"
#include "framework/error.h"
#include "io/handle_colors.h"

namespace harap {

namespace {

// `scale` > 0: components below 1e-12 * scale are rounding noise of a computed point (a
// centred mesh's centroid at 1e-17) and print as 0.
std::string Vec(Eigen::RowVector3d v, double scale = 0.0) {
  for (int k = 0; k < 3; ++k) {
    if (std::abs(v[k]) <= 1e-12 * scale) v[k] = 0.0;
  }
  return fmt::format("({:.6g}, {:.6g}, {:.6g})", v[0], v[1], v[2]);
}

}  // namespace

std::string DescribeHandles(const Scenario& scenario) {
  const Mesh& mesh = scenario.mesh;
  std::string text;
  text += fmt::format("scenario    {}\n", scenario.file.string());
  text += fmt::format("mesh        {} ({} vertices, {} {})\n", scenario.mesh_source,
                      mesh.num_vertices(), mesh.num_elements(),
                      mesh.kind() == ElementKind::kTetrahedron ? "tetrahedra" : "faces");
  const Eigen::Vector3d extent = scenario.box_max - scenario.box_min;
  text += fmt::format(
      "bounding box x in [{:.6g}, {:.6g}], y in [{:.6g}, {:.6g}], z in [{:.6g}, "
      "{:.6g}] (extent {}, diagonal {:.6g})\n",
      scenario.box_min[0], scenario.box_max[0], scenario.box_min[1], scenario.box_max[1],
      scenario.box_min[2], scenario.box_max[2], Vec(extent.transpose()), extent.norm());
  std::vector<int> owner(static_cast<size_t>(mesh.num_vertices()), -1);
  Index shared = 0;
  for (size_t h = 0; h < scenario.handles.size(); ++h) {
    const ScenarioHandle& handle = scenario.handles[h];
    Eigen::RowVector3d rest = Eigen::RowVector3d::Zero(), target = Eigen::RowVector3d::Zero();
    double largest_move = 0.0;
    for (size_t i = 0; i < handle.vertices.size(); ++i) {
      const Index v = handle.vertices[i];
      rest += mesh.vertices.row(v);
      target += handle.targets.row(static_cast<Index>(i));
      largest_move = std::max(
          largest_move, (handle.targets.row(static_cast<Index>(i)) - mesh.vertices.row(v)).norm());
      if (owner[v] < 0) {
        owner[v] = static_cast<int>(h);
      } else {
        ++shared;
      }
    }
    const double count = static_cast<double>(std::max<size_t>(1, handle.vertices.size()));
    std::string color;
    unsigned char rgb[3];
    HandleColor(h, rgb, &color);
    text += fmt::format("handle {}   '{}' ({} in the PLY)\n", h + 1, handle.name, color);
    text += fmt::format("  vertices  {}\n", handle.vertices.size());
    text += fmt::format("  selected  {}\n", handle.selection.empty() ? "-" : handle.selection);
    text += fmt::format("  centroid  {} -> {}\n", Vec(rest / count, extent.norm()),
                        Vec(target / count, extent.norm()));
    text += fmt::format("  motion    {}\n", handle.motion.empty() ? "-" : handle.motion);
    text += fmt::format("  moves     at most {:.6g} ({:.3g} box diagonals)\n", largest_move,
                        extent.norm() > 0 ? largest_move / extent.norm() : 0.0);
  }
  Index constrained = 0;
  for (const int o : owner) constrained += o >= 0;
  text += fmt::format("free        {} of {} vertices ({} constrained)\n",
                      mesh.num_vertices() - constrained, mesh.num_vertices(), constrained);
  if (shared > 0) {
    text += fmt::format(
        "overlap     {} selections of vertices another handle selected before "
        "(each such vertex takes the first handle's target)\n",
        shared);
  }
  if (!scenario.handles.empty() && constrained == mesh.num_vertices()) {
    text += "warning     the handles select every vertex: nothing is left to solve for\n";
  }
  if (scenario.handles.empty()) text += "warning     no handles: nothing moves\n";
  for (const std::string& note : scenario.notes) text += fmt::format("note        {}\n", note);
  return text;
}

void WriteHandlesPly(const std::filesystem::path& file, const Scenario& scenario) {
  const Mesh& mesh = scenario.mesh;
  std::vector<std::array<unsigned char, 3>> colors(
      static_cast<size_t>(mesh.num_vertices()),
      {kFreeVertexGrey, kFreeVertexGrey, kFreeVertexGrey});
  std::vector<bool> colored(static_cast<size_t>(mesh.num_vertices()), false);
  for (size_t h = 0; h < scenario.handles.size(); ++h) {
    unsigned char rgb[3];
    HandleColor(h, rgb);
    for (const Index v : scenario.handles[h].vertices) {
      if (colored[v]) continue;
      colored[v] = true;
      colors[v] = {rgb[0], rgb[1], rgb[2]};
    }
  }
  std::ofstream out(file, std::ios::binary);
  if (!out) throw InputError(fmt::format("{}: cannot open for writing", file.string()));
  const bool triangles = mesh.kind() == ElementKind::kTriangle;
  // Tetrahedra are written as their four triangles so that viewers show something.
  const Index faces = triangles ? mesh.num_elements() : 4 * mesh.num_elements();
  out << "ply\nformat binary_little_endian 1.0\ncomment harap handles: handle vertices coloured, "
         "free vertices grey\n"
      << "element vertex " << mesh.num_vertices()
      << "\nproperty double x\nproperty double y\nproperty double z\n"
         "property uchar red\nproperty uchar green\nproperty uchar blue\n"
      << "element face " << faces << "\nproperty list uchar int vertex_indices\nend_header\n";
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    for (int d = 0; d < 3; ++d) {
      const double x = mesh.vertices(v, d);
      out.write(reinterpret_cast<const char*>(&x), sizeof x);
    }
    out.write(reinterpret_cast<const char*>(colors[v].data()), 3);
  }
  auto write_face = [&](Index a, Index b, Index c) {
    const unsigned char three = 3;
    out.write(reinterpret_cast<const char*>(&three), 1);
    for (const Index index : {a, b, c}) {
      const int32_t i = static_cast<int32_t>(index);
      out.write(reinterpret_cast<const char*>(&i), sizeof i);
    }
  };
  for (Index f = 0; f < mesh.num_elements(); ++f) {
    const auto e = mesh.elements.row(f);
    if (triangles) {
      write_face(e[0], e[1], e[2]);
    } else {
      write_face(e[0], e[2], e[1]);
      write_face(e[0], e[1], e[3]);
      write_face(e[0], e[3], e[2]);
      write_face(e[1], e[2], e[3]);
    }
  }
  if (!out) throw InputError(fmt::format("{}: cannot write", file.string()));
}

int HandlesCommand(const std::string& scenario_file, const std::string& out) {
  // Checked before the mesh is read: a typo in --out should not cost a mesh load.
  if (!out.empty()) {
    std::string extension = std::filesystem::path(out).extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (extension != ".ply") {
      throw InputError(
          fmt::format("--out {}: harap handles writes PLY with vertex colours; give "
                      "a file name ending in .ply",
                      out));
    }
    CheckWritable(out, "--out");
  }
  const Scenario scenario = LoadScenario(scenario_file);
  fmt::print("{}", DescribeHandles(scenario));
  if (!out.empty()) {
    WriteHandlesPly(out, scenario);
    fmt::print("wrote       {} (handle vertices coloured as above, free vertices grey)\n", out);
  }
  std::fflush(stdout);
  return 0;
}

}  // namespace harap
