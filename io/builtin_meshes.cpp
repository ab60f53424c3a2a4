// SPDX-License-Identifier: MIT
#include "io/builtin_meshes.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include "framework/error.h"

namespace harap {

namespace {

constexpr double kPi = std::numbers::pi;

// Positions and triangles under construction.
struct MeshBuilder {
  std::vector<double> xyz;
  std::vector<Index> triangles;

  Index AddVertex(double x, double y, double z) {
    xyz.insert(xyz.end(), {x, y, z});
    return static_cast<Index>(xyz.size() / 3 - 1);
  }
  void AddTriangle(Index a, Index b, Index c) { triangles.insert(triangles.end(), {a, b, c}); }

  Mesh Finish() const {
    Mesh mesh;
    mesh.vertices.resize(static_cast<Index>(xyz.size() / 3), 3);
    for (Index v = 0; v < mesh.num_vertices(); ++v) {
      for (int d = 0; d < 3; ++d) mesh.vertices(v, d) = xyz[3 * v + d];
    }
    mesh.elements.resize(static_cast<Index>(triangles.size() / 3), 3);
    for (Index t = 0; t < mesh.num_elements(); ++t) {
      for (int a = 0; a < 3; ++a) mesh.elements(t, a) = triangles[3 * t + a];
    }
    return mesh;
  }
};

// A closed loop of vertices around the z axis: vertex i sits at angle offset + 2*pi*i/size.
struct Ring {
  Index first = 0;  // index of vertex 0; the ring's vertices are consecutive
  int size = 0;
  double offset = 0.0;  // in [0, 2*pi/size)

  Index Vertex(int i) const { return first + i % size; }
  double Angle(int i) const { return offset + 2.0 * kPi * i / size; }
};

Ring AddRing(MeshBuilder& builder, int size, double radius, double z, double offset) {
  Ring ring{static_cast<Index>(builder.xyz.size() / 3), size, offset};
  for (int i = 0; i < size; ++i) {
    const double angle = ring.Angle(i);
    builder.AddVertex(radius * std::cos(angle), radius * std::sin(angle), z);
  }
  return ring;
}

// Triangulates the band between two rings (a "zipper"): walking around both rings, each step adds
// one triangle and advances one ring, choosing the shorter of the two possible new rungs (the
// locally Delaunay choice). On the side (equal rings, half-step stagger) this gives equilateral
// triangles; between cap rings of different sizes the smallest angle stays above 35 degrees,
// where comparing angles instead left 25-degree slivers. Orientation: with t the counter-clockwise
// tangent and d the direction from ring a to ring b, the normals point along t x d. A ring of size
// 1 is a centre point (a fan).
void StitchRings(MeshBuilder& builder, const Ring& a, const Ring& b) {
  if (b.size == 1) {
    for (int i = 0; i < a.size; ++i) builder.AddTriangle(a.Vertex(i), a.Vertex(i + 1), b.first);
    return;
  }
  if (a.size == 1) {
    for (int k = 0; k < b.size; ++k) builder.AddTriangle(a.first, b.Vertex(k + 1), b.Vertex(k));
    return;
  }
  auto squared_distance = [&builder](Index p, Index q) {
    double sum = 0.0;
    for (int d = 0; d < 3; ++d) {
      const double delta = builder.xyz[3 * p + d] - builder.xyz[3 * q + d];
      sum += delta * delta;
    }
    return sum;
  };
  int i = 0;
  int k = 0;
  while (i < a.size || k < b.size) {
    // Of the two possible next rungs, take the shorter (the locally Delaunay choice).
    const bool advance_a =
        k == b.size || (i < a.size && squared_distance(a.Vertex(i + 1), b.Vertex(k)) <=
                                          squared_distance(a.Vertex(i), b.Vertex(k + 1)));
    if (advance_a) {
      builder.AddTriangle(a.Vertex(i), a.Vertex(i + 1), b.Vertex(k));
      ++i;
    } else {
      builder.AddTriangle(a.Vertex(i), b.Vertex(k + 1), b.Vertex(k));
      ++k;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Disks of radius 0.5 (cylinder caps and the planar `disk`): concentric rings spaced like
// equilateral triangle rows (sqrt(3)/2 of the boundary's edge length), ring j of `rings` holding
// about segments*j/rings vertices, so every ring has the boundary's edge length too.

struct DiskLayout {
  int rings = 0;                // rings from the centre (0) to the boundary ring (rings)
  std::vector<int> ring_sizes;  // ring_sizes[j], j = 1..rings-1 (index 0 unused)
  int64_t inner_vertices = 0;   // centre and inner rings (the boundary ring not counted)
};

constexpr double kDiskRadius = 0.5;

// Distance between equilateral rows whose edges are those of a ring of `segments` on the disk.
double RowSpacing(int segments) {
  const double edge = 2.0 * kPi * kDiskRadius / segments;
  return edge * std::sqrt(3.0) / 2.0;
}

DiskLayout LayoutDisk(int segments) {
  DiskLayout layout;
  layout.rings = std::max(1, static_cast<int>(std::lround(kDiskRadius / RowSpacing(segments))));
  layout.ring_sizes.assign(layout.rings, 0);
  layout.inner_vertices = 1;  // centre
  for (int j = 1; j < layout.rings; ++j) {
    layout.ring_sizes[j] = std::max(
        3, static_cast<int>(std::lround(static_cast<double>(segments) * j / layout.rings)));
    layout.inner_vertices += layout.ring_sizes[j];
  }
  return layout;
}

// Fills the existing ring `boundary` (radius 0.5, height z) with a disk; its normals point along
// +z if `up`, else along -z.
void AddDisk(MeshBuilder& builder, const DiskLayout& layout, const Ring& boundary, double z,
             bool up) {
  std::vector<Ring> rings(layout.rings + 1);
  rings[0] = Ring{builder.AddVertex(0.0, 0.0, z), 1, 0.0};
  for (int j = 1; j < layout.rings; ++j) {
    const int size = layout.ring_sizes[j];
    // Alternate half-step turns, as on the cylinder's side, so neighbouring rings do not line up.
    rings[j] = AddRing(builder, size, kDiskRadius * j / layout.rings, z, (j % 2) * kPi / size);
  }
  rings[layout.rings] = boundary;
  // Normal -z: stitch from the inside out; +z: outside in (see StitchRings).
  for (int j = 0; j < layout.rings; ++j) {
    if (up) {
      StitchRings(builder, rings[j + 1], rings[j]);
    } else {
      StitchRings(builder, rings[j], rings[j + 1]);
    }
  }
}

// The segment (or row) count in [estimate - 8, estimate + 8], at least `minimum`, whose exact
// vertex count, `count(segments)`, comes closest to `vertices`.
template <class Count>
int ClosestSegmentCount(int vertices, double estimate, Count count, int minimum = 3) {
  const int center = std::max(minimum, static_cast<int>(std::lround(std::min(estimate, 1e9))));
  int best = 0;
  int64_t best_count = 0;
  for (int segments = std::max(minimum, center - 8); segments <= center + 8; ++segments) {
    const int64_t c = count(segments);
    if (best == 0 || std::llabs(c - vertices) < std::llabs(best_count - vertices)) {
      best = segments;
      best_count = c;
    }
  }
  return best;
}

void RequireVertices(OptionReader parameters, std::string_view name, int vertices, int minimum) {
  if (vertices < minimum) {
    throw ConfigError(fmt::format("{}: built-in {}: 'vertices' must be at least {}, got {}",
                                  parameters.Where("vertices"), name, minimum, vertices));
  }
}

void RequireAspect(OptionReader parameters, std::string_view name, double aspect) {
  if (!(aspect > 0.0) || aspect > 1e4) {
    throw ConfigError(fmt::format("{}: built-in {}: 'aspect' must be in (0, 1e4], got {}",
                                  parameters.Where("aspect"), name, aspect));
  }
}

void RequireNotTooMany(OptionReader parameters, std::string_view name, int64_t count,
                       int vertices) {
  if (count > std::numeric_limits<Index>::max() / 4) {
    throw ConfigError(fmt::format("{}: built-in {}: {} vertices is too many",
                                  parameters.Where("vertices"), name, vertices));
  }
}

// ---------------------------------------------------------------------------------------------
// Cylinder: radius 0.5 (diameter 1), z in [0, aspect]. The side is a staggered grid (every other
// row turned by half a segment) whose row spacing is sqrt(3)/2 of the segment length, i.e.
// equilateral triangles. Each cap is a disk (above) whose boundary ring is the last side row.

struct CylinderLayout {
  int segments = 0;  // vertices per side row
  int row_gaps = 0;  // side rows - 1
  DiskLayout cap;    // used if caps
  int64_t vertex_count = 0;
};

CylinderLayout LayoutCylinder(int segments, double aspect, bool caps) {
  CylinderLayout layout;
  layout.segments = segments;
  layout.row_gaps = std::max(1, static_cast<int>(std::lround(aspect / RowSpacing(segments))));
  layout.vertex_count = static_cast<int64_t>(segments) * (layout.row_gaps + 1);
  if (caps) {
    layout.cap = LayoutDisk(segments);
    layout.vertex_count += 2 * layout.cap.inner_vertices;
  }
  return layout;
}

Mesh MakeCylinder(OptionReader parameters) {
  const int vertices = parameters.Get("vertices", 10000, "approximate number of vertices");
  const double aspect = parameters.Get("aspect", 4.0, "height / diameter (the diameter is 1)");
  const bool caps = parameters.Get("caps", true, "close both ends with triangulated disks");
  parameters.RejectUnknownKeys();
  RequireVertices(parameters, "cylinder", vertices, 10);
  RequireAspect(parameters, "cylinder", aspect);

  // vertices ~ segments^2 * (2 aspect + caps) / (pi sqrt 3) (side rows plus two disks); search
  // around that estimate for the segment count whose exact layout comes closest.
  const double per_segment_squared = (2.0 * aspect + (caps ? 1.0 : 0.0)) / (kPi * std::sqrt(3.0));
  const CylinderLayout best = LayoutCylinder(
      ClosestSegmentCount(
          vertices, std::sqrt(vertices / per_segment_squared),
          [&](int segments) { return LayoutCylinder(segments, aspect, caps).vertex_count; }),
      aspect, caps);
  RequireNotTooMany(parameters, "cylinder", best.vertex_count, vertices);

  MeshBuilder builder;
  builder.xyz.reserve(static_cast<size_t>(best.vertex_count) * 3);
  const int s = best.segments;
  const double half_step = kPi / s;
  const double height = aspect;
  std::vector<Ring> rows;
  for (int row = 0; row <= best.row_gaps; ++row) {
    const double z = height * row / best.row_gaps;
    rows.push_back(AddRing(builder, s, kDiskRadius, z, (row % 2) * half_step));
  }
  for (int row = 0; row < best.row_gaps; ++row) StitchRings(builder, rows[row], rows[row + 1]);
  if (caps) {
    AddDisk(builder, best.cap, rows.front(), 0.0, /*up=*/false);
    AddDisk(builder, best.cap, rows.back(), height, /*up=*/true);
  }
  return builder.Finish();
}

// ---------------------------------------------------------------------------------------------
// Disk (planar): radius 0.5 about the origin in the xy-plane, normals +z (counter-clockwise).

Mesh MakeDisk(OptionReader parameters) {
  const int vertices = parameters.Get("vertices", 10000, "approximate number of vertices");
  parameters.RejectUnknownKeys();
  RequireVertices(parameters, "disk", vertices, 4);
  // vertices ~ area / (sqrt(3)/2 edge^2) with edge = pi/segments: segments^2 / (2 sqrt(3) pi).
  const auto count = [](int segments) { return segments + LayoutDisk(segments).inner_vertices; };
  const int segments =
      ClosestSegmentCount(vertices, std::sqrt(vertices * 2.0 * std::sqrt(3.0) * kPi), count);
  RequireNotTooMany(parameters, "disk", count(segments), vertices);
  MeshBuilder builder;
  builder.xyz.reserve(static_cast<size_t>(count(segments)) * 3);
  const Ring boundary = AddRing(builder, segments, kDiskRadius, 0.0, 0.0);
  AddDisk(builder, LayoutDisk(segments), boundary, 0.0, /*up=*/true);
  Mesh mesh = builder.Finish();
  mesh.planar = true;
  return mesh;
}

// ---------------------------------------------------------------------------------------------
// Grids (the spike plane and the planar `rectangle`): columns x in [0, width], rows y in
// [0, height], vertex (row i, column j) = i * columns + j; the cells' diagonals alternate, which
// avoids a preferred direction; counter-clockwise seen from +z. `z` (rows*columns, or empty for
// 0) lifts the vertices.

void AddGrid(MeshBuilder& builder, int rows, int columns, double width, double height,
             const std::vector<double>& z) {
  const Index first = static_cast<Index>(builder.xyz.size() / 3);
  for (int i = 0; i < rows; ++i) {
    for (int j = 0; j < columns; ++j) {
      builder.AddVertex(j * (width / (columns - 1)), i * (height / (rows - 1)),
                        z.empty() ? 0.0 : z[static_cast<size_t>(i) * columns + j]);
    }
  }
  for (int i = 0; i + 1 < rows; ++i) {
    for (int j = 0; j + 1 < columns; ++j) {
      const Index v00 = first + i * columns + j;
      const Index v01 = v00 + 1;        // +x
      const Index v10 = v00 + columns;  // +y
      const Index v11 = v10 + 1;
      if ((i + j) % 2 == 0) {
        builder.AddTriangle(v00, v01, v11);
        builder.AddTriangle(v00, v11, v10);
      } else {
        builder.AddTriangle(v00, v01, v10);
        builder.AddTriangle(v01, v11, v10);
      }
    }
  }
}

// Rectangle (planar): [0, aspect] x [0, 1] in the xy-plane, a grid of nearly square cells.
Mesh MakeRectangle(OptionReader parameters) {
  const int vertices = parameters.Get("vertices", 10000, "approximate number of vertices");
  const double aspect = parameters.Get("aspect", 4.0, "width (along x) / height (along y = 1)");
  parameters.RejectUnknownKeys();
  RequireVertices(parameters, "rectangle", vertices, 4);
  RequireAspect(parameters, "rectangle", aspect);
  // Square cells: (columns - 1) ~ aspect (rows - 1), at least 2 of each; of the row counts near
  // sqrt(vertices / aspect), the one whose rows * columns comes closest to `vertices`.
  const auto columns_for = [aspect](int rows) {
    return static_cast<int64_t>(
        std::max(2.0, std::min(std::round(aspect * (rows - 1)) + 1.0, 1e9)));
  };
  const int rows = ClosestSegmentCount(
      vertices, std::sqrt(static_cast<double>(vertices) / aspect),
      [&](int r) { return static_cast<int64_t>(r) * columns_for(r); }, /*minimum=*/2);
  RequireNotTooMany(parameters, "rectangle", rows * columns_for(rows), vertices);
  const int columns = static_cast<int>(columns_for(rows));
  MeshBuilder builder;
  builder.xyz.reserve(static_cast<size_t>(rows) * columns * 3);
  AddGrid(builder, rows, columns, aspect, 1.0, {});
  Mesh mesh = builder.Finish();
  mesh.planar = true;
  return mesh;
}

// ---------------------------------------------------------------------------------------------
// Spike plane: an n x n grid on [0,1]^2 (z = 0) with `spikes` cones of height `spike_height` and
// base radius `spike_radius`, their tips on grid vertices at pseudo-random positions. The thin
// spikes are features a coarse hierarchy level cannot represent.

// splitmix64 (Steele, Lea, Flood 2014): fixed and tiny, so the plane is the same with every
// standard library (std::uniform_int_distribution's output is implementation-defined).
uint64_t SplitMix64(uint64_t& state) {
  uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

Mesh MakePlane(OptionReader parameters) {
  const int vertices = parameters.Get("vertices", 10000, "approximate number of vertices");
  const int spikes = parameters.Get("spikes", 16, "number of spikes");
  const double spike_height =
      parameters.Get("spike_height", 0.2, "height of each spike (the plane's side is 1)");
  const double spike_radius =
      parameters.Get("spike_radius", 0.02, "base radius of each conical spike (side = 1)");
  const int seed = parameters.Get("seed", 1, "seed of the spike positions");
  parameters.RejectUnknownKeys();
  RequireVertices(parameters, "plane", vertices, 4);
  if (spikes < 0) {
    throw ConfigError(fmt::format("{}: built-in plane: 'spikes' must be >= 0, got {}",
                                  parameters.Where("spikes"), spikes));
  }
  if (!(spike_radius > 0.0) || spike_radius >= 0.5) {
    throw ConfigError(fmt::format("{}: built-in plane: 'spike_radius' must be in (0, 0.5), got {}",
                                  parameters.Where("spike_radius"), spike_radius));
  }

  const int n =
      std::max(2, static_cast<int>(std::lround(std::sqrt(static_cast<double>(vertices)))));
  const double spacing = 1.0 / (n - 1);
  // Spike tips stay a radius plus one cell away from the border, so the border is flat.
  const int margin = static_cast<int>(std::ceil(spike_radius / spacing)) + 1;
  const int lo = margin;
  const int hi = n - 1 - margin;
  if (spikes > 0 && hi < lo) {
    throw ConfigError(
        fmt::format("{}: built-in plane: spikes of radius {} do not fit on a grid "
                    "of {} x {} vertices (use more vertices or a smaller "
                    "'spike_radius')",
                    parameters.Where("spike_radius"), spike_radius, n, n));
  }
  std::vector<double> height(static_cast<size_t>(n) * n, 0.0);
  uint64_t state = static_cast<uint64_t>(static_cast<int64_t>(seed));
  const uint64_t range = static_cast<uint64_t>(hi - lo + 1);
  for (int spike = 0; spike < spikes; ++spike) {
    // Modulo bias is below range / 2^64: irrelevant here.
    const int ti = lo + static_cast<int>(SplitMix64(state) % range);
    const int tj = lo + static_cast<int>(SplitMix64(state) % range);
    const int reach = static_cast<int>(std::ceil(spike_radius / spacing));
    for (int i = std::max(0, ti - reach); i <= std::min(n - 1, ti + reach); ++i) {
      for (int j = std::max(0, tj - reach); j <= std::min(n - 1, tj + reach); ++j) {
        const double distance = std::hypot(i - ti, j - tj) * spacing;
        const double z = spike_height * std::max(0.0, 1.0 - distance / spike_radius);
        double& h = height[static_cast<size_t>(i) * n + j];
        // Overlapping spikes: the higher one wins (no sums that exceed spike_height).
        if (std::abs(z) > std::abs(h)) h = z;
      }
    }
  }

  MeshBuilder builder;
  builder.xyz.reserve(static_cast<size_t>(n) * n * 3);
  AddGrid(builder, n, n, 1.0, 1.0, height);
  return builder.Finish();
}

}  // namespace

std::vector<std::string> BuiltinMeshNames() { return {"cylinder", "plane", "disk", "rectangle"}; }

Mesh MakeBuiltinMesh(const ConfigNode& parameters) {
  return MakeBuiltinMesh(OptionReader(parameters));
}

Mesh MakeBuiltinMesh(OptionReader parameters) {
  const std::vector<std::string> names = BuiltinMeshNames();
  if (!parameters.Has("builtin")) {
    throw ConfigError(
        fmt::format("{}: a built-in mesh table needs `builtin = NAME` with NAME "
                    "one of: {}",
                    parameters.Where("builtin"), fmt::join(names, ", ")));
  }
  const std::string name =
      parameters.GetChoice("builtin", names.front(), names, "which built-in mesh to generate");
  Mesh mesh = name == "cylinder" ? MakeCylinder(parameters)
              : name == "plane"  ? MakePlane(parameters)
              : name == "disk"   ? MakeDisk(parameters)
                                 : MakeRectangle(parameters);
  ValidateMesh(mesh, fmt::format("built-in mesh '{}'", name));
  return mesh;
}

}  // namespace harap
