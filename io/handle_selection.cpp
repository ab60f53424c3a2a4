// SPDX-License-Identifier: MIT
//
// Handle selection. Decisions the format leaves open:
//   - "The bounding box of the rest mesh" is the box of the vertices referenced by some element
//     (the same set BoundingBoxDiagonal uses), after `refine`. Unreferenced vertices (the
//     Stanford bunny has 1,113) are stray points, not surface: they neither stretch the box nor
//     get picked by `slab`/`ball` selections. `indices`/`index_file` may name any vertex.
//   - An axis along which the box is flat (extent 0) gives every vertex the fraction 0 there.
//   - `units = "absolute"` reads slab bounds, ball centre and radius, rotate.center and translate
//     in mesh coordinates instead of box fractions and diagonals.
#include "io/handle_selection.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>

#include "framework/error.h"
#include "io/file_reading.h"
#include "io/ply_reader.h"
#include "io/text_scanning.h"

namespace harap::io_internal {

std::string Vec(const Eigen::Vector3d& v) {
  return fmt::format("({:.6g}, {:.6g}, {:.6g})", v[0], v[1], v[2]);
}

namespace {

// A computed point (a centroid) of a mesh of size `scale`: rounding noise far below the mesh's
// size (a centred mesh's centroid at 1e-17) prints as 0, not as a number that looks meaningful.
std::string Point(Eigen::Vector3d v, double scale) {
  for (int k = 0; k < 3; ++k) {
    if (std::abs(v[k]) <= 1e-12 * scale) v[k] = 0.0;
  }
  return Vec(v);
}

// The box, for every message about a selection: the numbers only mean something against it.
std::string DescribeBox(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  return fmt::format("x in [{:.6g}, {:.6g}], y in [{:.6g}, {:.6g}], z in [{:.6g}, {:.6g}]", lo[0],
                     hi[0], lo[1], hi[1], lo[2], hi[2]);
}

// What a handle selects, with its kind and units; `lo`/`hi` the mesh's bounding box.
std::string DescribeSelection(const HandleSpec& spec, const Eigen::Vector3d& lo,
                              const Eigen::Vector3d& hi) {
  const bool absolute = spec.units == Units::kAbsolute;
  const std::string units =
      absolute ? fmt::format(
                     "absolute coordinates (units = \"absolute\"); the mesh's bounding box "
                     "is {}",
                     DescribeBox(lo, hi))
               : fmt::format("fractions of the bounding box {}{}", DescribeBox(lo, hi),
                             spec.kind == SelectionKind::kBall ? ", radius in box diagonals" : "");
  switch (spec.kind) {
    case SelectionKind::kSlab:
      return fmt::format("select.slab {} in [{}, {}] ({})", "xyz"[spec.axis], spec.from, spec.to,
                         units);
    case SelectionKind::kBall:
      return fmt::format("select.ball at {} of radius {} ({})", Vec(spec.ball_center), spec.radius,
                         units);
    case SelectionKind::kIndices:
      return fmt::format("select.indices ({} 0-based vertex indices)", spec.indices.size());
    case SelectionKind::kIndexFile:
      return fmt::format("select.index_file {} (0-based vertex indices)", spec.index_file.string());
  }
  return "";
}
// A problem with what the scenario text selects: a ConfigError at `where`, naming the handle.
[[noreturn]] void Fail(const std::string& where, const std::string& label,
                       std::string_view problem) {
  throw ConfigError(fmt::format("{}: {}: {}", where, label, problem));
}

// The text of a file the scenario names; read errors name `where` and `what`.
std::string ReadNamedText(const std::filesystem::path& path, const std::string& where,
                          std::string_view what) {
  return ReadNamedFile(path, where, what, [](const auto& file) { return ReadFileMaybeXz(file); });
}

// select.index_file: whitespace-separated 0-based vertex indices.
std::vector<Index> ReadIndexFile(const HandleSpec& spec, Index num_vertices) {
  const std::string file = spec.index_file.string();
  auto fail = [&](const std::string& problem) {
    throw InputError(
        fmt::format("{}: {}: index file {}: {}", spec.index_file_where, spec.label, file, problem));
  };
  std::string text;
  try {
    text = ReadFileMaybeXz(spec.index_file);
  } catch (const InputError& error) {
    fail(error.what());
  }
  std::vector<Index> indices;
  size_t line = 1;
  size_t position = 0;
  while (position < text.size()) {
    const char c = text[position];
    if (c == '\n') ++line;
    if (std::isspace(static_cast<unsigned char>(c))) {
      ++position;
      continue;
    }
    size_t end = position;
    while (end < text.size() && !std::isspace(static_cast<unsigned char>(text[end]))) ++end;
    const std::string_view token(text.data() + position, end - position);
    int64_t index = 0;
    const auto [stop, error] = std::from_chars(token.data(), token.data() + token.size(), index);
    if (error != std::errc() || stop != token.data() + token.size()) {
      fail(fmt::format("line {}: '{}' is not a vertex index", line,
                       token.substr(0, std::min<size_t>(token.size(), 40))));
    }
    if (index < 0 || index >= num_vertices) {
      fail(fmt::format("line {}: index {} out of range (the mesh has {} vertices, valid 0..{})",
                       line, index, num_vertices, num_vertices - 1));
    }
    indices.push_back(static_cast<Index>(index));
    position = end;
  }
  return indices;
}

// Vertices `spec` selects, ascending.
std::vector<Index> Select(const HandleSpec& spec, const Mesh& mesh,
                          const std::vector<bool>& referenced, const Eigen::Vector3d& lo,
                          const Eigen::Vector3d& extent, double diagonal) {
  std::vector<Index> selected;
  const Index n = mesh.num_vertices();
  const bool absolute = spec.units == Units::kAbsolute;
  // Slab bounds are compared as written: fractions to fractions, coordinates to coordinates.
  auto coordinate = [&](Index v, int d) {
    if (absolute) return mesh.vertices(v, d);
    return extent[d] > 0.0 ? (mesh.vertices(v, d) - lo[d]) / extent[d] : 0.0;
  };
  switch (spec.kind) {
    case SelectionKind::kSlab:
      for (Index v = 0; v < n; ++v) {
        if (!referenced[v]) continue;
        const double f = coordinate(v, spec.axis);
        if (f >= spec.from && f <= spec.to) selected.push_back(v);
      }
      break;
    case SelectionKind::kBall: {
      const Eigen::Vector3d center =
          absolute ? spec.ball_center : Eigen::Vector3d(lo + spec.ball_center.cwiseProduct(extent));
      const double radius = absolute ? spec.radius : spec.radius * diagonal;
      for (Index v = 0; v < n; ++v) {
        if (!referenced[v]) continue;
        if ((mesh.vertices.row(v).transpose() - center).norm() <= radius) selected.push_back(v);
      }
      break;
    }
    case SelectionKind::kIndices:
      for (size_t i = 0; i < spec.indices.size(); ++i) {
        const int64_t index = spec.indices[i];
        if (index < 0 || index >= n) {
          Fail(spec.index_where[i], spec.label,
               fmt::format("select.indices: index {} out of range (the mesh has {} vertices, "
                           "valid 0..{})",
                           index, n, n - 1));
        }
        selected.push_back(static_cast<Index>(index));
      }
      break;
    case SelectionKind::kIndexFile:
      selected = ReadIndexFile(spec, n);
      break;
  }
  std::sort(selected.begin(), selected.end());
  selected.erase(std::unique(selected.begin(), selected.end()), selected.end());
  if (selected.empty()) {
    Fail(spec.select_where, spec.label,
         fmt::format("{} matches no vertex{}", DescribeSelection(spec, lo, lo + extent),
                     spec.units == Units::kFractions && (spec.kind == SelectionKind::kSlab ||
                                                         spec.kind == SelectionKind::kBall)
                         ? "; for mesh coordinates write units = \"absolute\" in the handle"
                         : ""));
  }
  return selected;
}

// target_file: lines "index x y z" (absolute coordinates; `#` comments, blank lines skipped).
// Fills the handle's vertices (ascending) and targets.
void ReadTargetFile(const HandleSpec& spec, Index num_vertices, ScenarioHandle& handle) {
  const std::string file = spec.target_file.string();
  const std::string text = ReadNamedText(spec.target_file, spec.target_file_where, "target_file");
  io_internal::LineReader lines(text);
  auto fail = [&](const std::string& problem) {
    throw InputError(fmt::format("{}: {}: target file {}:{}: {}", spec.target_file_where,
                                 spec.label, file, lines.line_number(), problem));
  };
  std::vector<std::pair<Index, Eigen::Vector3d>> entries;
  std::vector<size_t> line_of(static_cast<size_t>(num_vertices), 0);
  std::string_view line;
  while (lines.NextContent(line)) {
    std::string_view tokens[5];
    int count = 0;
    for (std::string_view token; !(token = io_internal::NextToken(line)).empty();) {
      if (count < 5) tokens[count] = token;
      ++count;
    }
    if (count != 4) {
      fail(fmt::format("expected 'index x y z' (4 values), found {} value{}", count,
                       count == 1 ? "" : "s"));
    }
    int64_t index = 0;
    if (!io_internal::ParseInteger(tokens[0], index)) {
      fail(fmt::format("{} is not a vertex index", io_internal::Quote(tokens[0])));
    }
    if (index < 0 || index >= num_vertices) {
      fail(fmt::format("index {} out of range (the mesh has {} vertices, valid 0..{})", index,
                       num_vertices, num_vertices - 1));
    }
    if (line_of[index] != 0) {
      fail(fmt::format("vertex {} has a target already (line {})", index, line_of[index]));
    }
    line_of[index] = lines.line_number();
    Eigen::Vector3d target;
    for (int d = 0; d < 3; ++d) {
      if (!io_internal::ParseDouble(tokens[d + 1], target[d])) {
        fail(fmt::format("{} is not a number", io_internal::Quote(tokens[d + 1])));
      }
      if (!std::isfinite(target[d])) {
        fail(fmt::format("{} is not a finite number", io_internal::Quote(tokens[d + 1])));
      }
    }
    entries.emplace_back(static_cast<Index>(index), target);
  }
  if (entries.empty()) {
    throw InputError(fmt::format("{}: {}: target file {} has no 'index x y z' line",
                                 spec.target_file_where, spec.label, file));
  }
  std::sort(entries.begin(), entries.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  handle.vertices.clear();
  handle.targets.resize(static_cast<Index>(entries.size()), 3);
  for (size_t i = 0; i < entries.size(); ++i) {
    handle.vertices.push_back(entries[i].first);
    handle.targets.row(static_cast<Index>(i)) = entries[i].second.transpose();
  }
}

// The deformation benchmark of Botsch & Sorkine's survey: `selection` (.sel: one label per
// vertex, 0 fixed, 1 free, 2 handle) and `deformation` (.def: the handle's 4x4 transform,
// row-major, applied to (x, y, z, 1)). Makes the handles "fixed" (if any 0) and "handle".
void AddBenchmarkHandles(const std::filesystem::path& selection_file,
                         const std::string& selection_where,
                         const std::filesystem::path& deformation_file,
                         const std::string& deformation_where, Scenario& scenario) {
  const Index n = scenario.mesh.num_vertices();
  const std::string sel_text = ReadNamedText(selection_file, selection_where, "selection");
  io_internal::LineReader lines(sel_text);
  auto fail_sel = [&](const std::string& problem) {
    throw InputError(fmt::format("{}: selection file {}:{}: {}", selection_where,
                                 selection_file.string(), lines.line_number(), problem));
  };
  ScenarioHandle fixed, moved;
  fixed.name = "fixed";
  moved.name = "handle";
  Index count = 0;
  std::string_view line;
  while (lines.NextContent(line)) {
    for (std::string_view token; !(token = io_internal::NextToken(line)).empty();) {
      int64_t label = 0;
      if (!io_internal::ParseInteger(token, label) || label < 0 || label > 2) {
        fail_sel(fmt::format("{} is not a vertex label (0 fixed, 1 free, 2 handle)",
                             io_internal::Quote(token)));
      }
      if (count >= n) {
        fail_sel(fmt::format("more labels than the mesh's {} vertices (one label per vertex)", n));
      }
      if (label == 0) fixed.vertices.push_back(count);
      if (label == 2) moved.vertices.push_back(count);
      ++count;
    }
  }
  if (count != n) {
    throw InputError(
        fmt::format("{}: selection file {} has {} labels, but the mesh has {} "
                    "vertices{} (one label per vertex: 0 fixed, 1 free, 2 handle)",
                    selection_where, selection_file.string(), count, n,
                    scenario.mesh_source.empty() ? "" : " (" + scenario.mesh_source + ")"));
  }
  if (moved.vertices.empty()) {
    throw InputError(fmt::format("{}: selection file {} marks no vertex as handle (label 2)",
                                 selection_where, selection_file.string()));
  }

  const std::string def_text = ReadNamedText(deformation_file, deformation_where, "deformation");
  io_internal::TokenCursor cursor(def_text, 1, /*skip_comments=*/true);
  Eigen::Matrix4d transform;
  for (int k = 0; k < 17; ++k) {
    const std::string_view token = cursor.Next();
    auto fail_def = [&](const std::string& problem) {
      throw InputError(fmt::format("{}: deformation file {}:{}: {}", deformation_where,
                                   deformation_file.string(), cursor.line(), problem));
    };
    if (k == 16) {
      if (!token.empty()) fail_def("more than the 16 numbers of a 4x4 matrix");
      break;
    }
    if (token.empty()) {
      fail_def(fmt::format("ends after {} of the 16 numbers of the 4x4 matrix (row-major)", k));
    }
    double value = 0.0;
    if (!io_internal::ParseDouble(token, value) || !std::isfinite(value)) {
      fail_def(fmt::format("{} is not a finite number", io_internal::Quote(token)));
    }
    transform(k / 4, k % 4) = value;
  }
  if (transform.row(3) != Eigen::RowVector4d(0.0, 0.0, 0.0, 1.0)) {
    throw InputError(
        fmt::format("{}: deformation file {}: the last row is ({}, {}, {}, {}), "
                    "not (0, 0, 0, 1): not an affine transform",
                    deformation_where, deformation_file.string(), transform(3, 0), transform(3, 1),
                    transform(3, 2), transform(3, 3)));
  }
  const Eigen::Matrix3d linear = transform.topLeftCorner<3, 3>();
  const Eigen::Vector3d shift = transform.topRightCorner<3, 1>();
  moved.targets.resize(static_cast<Index>(moved.vertices.size()), 3);
  for (size_t i = 0; i < moved.vertices.size(); ++i) {
    const Eigen::Vector3d p = scenario.mesh.vertices.row(moved.vertices[i]).transpose();
    moved.targets.row(static_cast<Index>(i)) = (linear * p + shift).transpose();
  }
  moved.selection = fmt::format("label 2 of {}", selection_file.filename().string());
  moved.motion = fmt::format(
      "4x4 transform from {}: linear part [{:.6g} {:.6g} {:.6g}; {:.6g} "
      "{:.6g} {:.6g}; {:.6g} {:.6g} {:.6g}], translation {}",
      deformation_file.filename().string(), linear(0, 0), linear(0, 1), linear(0, 2), linear(1, 0),
      linear(1, 1), linear(1, 2), linear(2, 0), linear(2, 1), linear(2, 2), Vec(shift));
  if (!fixed.vertices.empty()) {
    fixed.targets.resize(static_cast<Index>(fixed.vertices.size()), 3);
    for (size_t i = 0; i < fixed.vertices.size(); ++i) {
      fixed.targets.row(static_cast<Index>(i)) = scenario.mesh.vertices.row(fixed.vertices[i]);
    }
    fixed.selection = fmt::format("label 0 of {}", selection_file.filename().string());
    fixed.motion = "fixed (held at rest positions)";
    scenario.handles.push_back(std::move(fixed));
  }
  scenario.handles.push_back(std::move(moved));
}

}  // namespace

void AddHandles(const std::optional<BenchmarkHandlesSpec>& benchmark,
                const std::vector<HandleSpec>& specs, Scenario& scenario) {
  // Box of the referenced vertices (see the top of this file).
  const Mesh& mesh = scenario.mesh;
  const std::vector<bool> referenced = ReferencedVertices(mesh);
  const auto [box_min, box_max] = SelectionBox(mesh);
  const Eigen::Vector3d lo = box_min, hi = box_max;  // used in lambdas below
  const Eigen::Vector3d extent = hi - lo;
  const double diagonal = BoundingBoxDiagonal(mesh);
  scenario.box_min = lo;
  scenario.box_max = hi;

  if (benchmark) {
    AddBenchmarkHandles(benchmark->selection_file, benchmark->selection_where,
                        benchmark->deformation_file, benchmark->deformation_where, scenario);
  }
  for (const HandleSpec& spec : specs) {
    ScenarioHandle handle;
    handle.name = spec.name;
    handle.weight = spec.weight;
    if (spec.target == TargetKind::kFile) {
      ReadTargetFile(spec, mesh.num_vertices(), handle);
      handle.selection = fmt::format("the indices of target_file {}", spec.target_file.string());
      handle.motion = fmt::format("per-vertex targets from {} (absolute coordinates)",
                                  spec.target_file.string());
      scenario.handles.push_back(std::move(handle));
      continue;
    }
    handle.vertices = Select(spec, mesh, referenced, lo, extent, diagonal);
    handle.selection = DescribeSelection(spec, lo, hi);
    const Index count = static_cast<Index>(handle.vertices.size());
    handle.targets.resize(count, 3);
    if (spec.target == TargetKind::kInitial) {
      for (Index i = 0; i < count; ++i) {
        handle.targets.row(i) = scenario.initial->row(handle.vertices[i]);
      }
      handle.motion = "held at its positions in the initial configuration";
    } else {
      const bool absolute = spec.units == Units::kAbsolute;
      Eigen::Vector3d center = Eigen::Vector3d::Zero();
      if (spec.center) {
        center = absolute ? *spec.center : Eigen::Vector3d(lo + spec.center->cwiseProduct(extent));
      } else {
        for (const Index v : handle.vertices) center += mesh.vertices.row(v).transpose();
        center /= static_cast<double>(count);
      }
      const Eigen::Matrix3d rotation =
          Eigen::AngleAxisd(spec.degrees * std::numbers::pi / 180.0, spec.axis_vector.normalized())
              .toRotationMatrix();
      const Eigen::Vector3d shift = absolute ? spec.translation : spec.translation * diagonal;
      for (Index i = 0; i < count; ++i) {
        const Eigen::Vector3d p = mesh.vertices.row(handle.vertices[i]).transpose();
        // Without a rotation, p + t*D exactly (no round trip through the centre), so a fixed
        // handle holds its vertices at bit-identical rest positions.
        const Eigen::Vector3d target =
            spec.has_rotation ? Eigen::Vector3d(center + rotation * (p - center) + shift)
                              : Eigen::Vector3d(p + shift);
        handle.targets.row(i) = target.transpose();
      }
      std::vector<std::string> parts;
      if (spec.has_rotation) {
        parts.push_back(fmt::format("rotate {}° about {} through {}{}", spec.degrees,
                                    Vec(spec.axis_vector.normalized()), Point(center, diagonal),
                                    spec.center ? "" : " (the handle's centroid)"));
      }
      if (spec.has_translation) {
        parts.push_back(absolute ? fmt::format("translate {}", Vec(shift))
                                 : fmt::format("translate {} (= {} box diagonals)", Vec(shift),
                                               Vec(spec.translation)));
      }
      handle.motion = parts.empty() ? std::string("fixed (held at rest positions)")
                                    : fmt::format("{}", fmt::join(parts, ", then "));
    }
    scenario.handles.push_back(std::move(handle));
  }
}

namespace {

// The per-vertex or per-element factors of an `attribute` region.
void ReadStiffnessAttribute(const StiffnessSpec& spec, const MeshSpec& mesh_spec,
                            const Scenario& scenario, ScenarioStiffness& region) {
  const std::string& where = spec.attribute_where;
  const std::string extension = DetectFormat(mesh_spec.file).extension;
  if (mesh_spec.kind != MeshSpec::Kind::kFile || extension != "ply" || mesh_spec.refine > 0) {
    throw ConfigError(fmt::format(
        "{}: {}: attribute = \"{}\" reads a vertex or face property of the mesh's PLY file, so "
        "the scenario's mesh must be a PLY file used as it is (no refine, no tetrahedralize)",
        where, spec.region.label, spec.attribute));
  }
  const PlyMeshProperty property =
      ReadNamedFile(mesh_spec.file, where, "stiffness attribute", [&](const auto& path) {
        return ParsePlyMeshProperty(ReadFileMaybeXz(path), path.string(), spec.attribute);
      });
  const bool per_vertex = property.element == "vertex";
  const Index expected = per_vertex ? scenario.mesh.num_vertices() : scenario.mesh.num_elements();
  HARAP_CHECK(static_cast<Index>(property.values.size()) == expected,
              "PLY property '{}' has {} values for {} items", spec.attribute,
              property.values.size(), expected);
  double low = std::numeric_limits<double>::infinity(), high = 0.0;
  for (size_t k = 0; k < property.values.size(); ++k) {
    const double value = property.values[k];
    if (!(value > 0.0) || !std::isfinite(value)) {
      throw InputError(fmt::format(
          "{}: {}: {}: the {} property '{}' is {} at {} {} (0-based); a stiffness factor is a "
          "finite number > 0",
          where, spec.region.label, mesh_spec.file.string(), property.element, spec.attribute,
          value, per_vertex ? "vertex" : "triangle", k));
    }
    low = std::min(low, value);
    high = std::max(high, value);
  }
  region.attribute = spec.attribute;
  (per_vertex ? region.vertex_factors : region.element_factors) = property.values;
  region.selection = fmt::format("{} property '{}' of {}, factors {} to {}", property.element,
                                 spec.attribute, mesh_spec.file.filename().string(), low, high);
  if (per_vertex) {
    region.vertices.resize(static_cast<size_t>(scenario.mesh.num_vertices()));
    std::iota(region.vertices.begin(), region.vertices.end(), Index{0});
  } else {
    const std::vector<bool> used = ReferencedVertices(scenario.mesh);
    for (Index v = 0; v < scenario.mesh.num_vertices(); ++v) {
      if (used[static_cast<size_t>(v)]) region.vertices.push_back(v);
    }
  }
}

}  // namespace

void AddStiffness(const std::vector<StiffnessSpec>& specs, const MeshSpec& mesh_spec,
                  Scenario& scenario) {
  const Mesh& mesh = scenario.mesh;
  const std::vector<bool> referenced = ReferencedVertices(mesh);
  const Eigen::Vector3d extent = scenario.box_max - scenario.box_min;
  const double diagonal = BoundingBoxDiagonal(mesh);
  for (const StiffnessSpec& spec : specs) {
    ScenarioStiffness region;
    region.name = spec.region.name;
    if (!spec.attribute.empty()) {
      ReadStiffnessAttribute(spec, mesh_spec, scenario, region);
    } else {
      region.factor = spec.factor;
      region.vertices = Select(spec.region, mesh, referenced, scenario.box_min, extent, diagonal);
      region.selection = DescribeSelection(spec.region, scenario.box_min, scenario.box_max);
    }
    scenario.stiffness.push_back(std::move(region));
  }
}

}  // namespace harap::io_internal
