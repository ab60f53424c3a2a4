// SPDX-License-Identifier: MIT
//
// Tetrahedralization of closed surfaces with TetGen 1.5 (Debian libtet1.5-dev).
//
// Why a child process: TetGen 1.5.0 reports most failures by throwing an int (the library is
// built with TETLIBRARY), but on some inputs it crashes instead. Measured here: a closed cube
// surface with one vertex pushed through the opposite faces (self-intersecting) segfaults with
// -p, -pY and -pYJ; its self-intersection check -d segfaults on the (valid) armadillo-43k
// surface. Running TetGen in a forked child turns every such crash into an InputError; the
// child's stdout/stderr go to /dev/null so nothing is printed.
//
// Switches: -p (the input is a piecewise linear complex: our triangles), -Y (no Steiner points
// on the surface, so the surface vertices and triangles survive unchanged), -J (no jettisoning of
// unused input points, so TetGen's output numbering starts with our input points in order),
// -Q (quiet), plus -q ratio[/angle] and -a volume from the options. Every guarantee the header
// states is checked on the result rather than trusted.
#include "io/tetrahedralize.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <sys/resource.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <tetgen.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstring>
#include <string>
#include <tuple>
#include <vector>

#include "framework/error.h"
#include "io/tetrahedra.h"
#include "io/text_scanning.h"

namespace harap {

namespace {

using io_internal::Fail;
using Triple = std::array<Index, 3>;

Triple Sorted(Triple t) {
  std::sort(t.begin(), t.end());
  return t;
}

// ---------------------------------------------------------------------------------------------
// The surface TetGen gets: the referenced vertices only (numbered compactly), after the checks
// TetGen needs to succeed.

struct CompactSurface {
  std::vector<double> points;   // 3 per compact vertex
  std::vector<int> triangles;   // 3 per triangle, compact numbering
  std::vector<Index> original;  // compact -> surface vertex
  double enclosed_volume = 0.0;
};

Eigen::Vector3d Position(const Mesh& surface, Index v) {
  return surface.vertices.row(v).transpose();
}

// Fails unless every triangle has an area and the surface is closed and consistently oriented:
// every edge is used by exactly two triangles, once in each direction.
void CheckClosedSurface(const Mesh& surface, std::string_view what) {
  const Index num_triangles = surface.num_elements();
  const auto position = [&](Index v) { return Position(surface, v); };
  // Directed edges sorted by their undirected key make each edge a run.
  struct DirectedEdge {
    Index low, high;
    bool forward;  // low -> high in the triangle
    Index triangle;
  };
  std::vector<DirectedEdge> edges;
  edges.reserve(static_cast<size_t>(num_triangles) * 3);
  for (Index f = 0; f < num_triangles; ++f) {
    for (int a = 0; a < 3; ++a) {
      const Index u = surface.elements(f, a);
      const Index v = surface.elements(f, (a + 1) % 3);
      edges.push_back({std::min(u, v), std::max(u, v), u < v, f});
    }
    const Eigen::Vector3d p = position(surface.elements(f, 0));
    const Eigen::Vector3d n =
        (position(surface.elements(f, 1)) - p).cross(position(surface.elements(f, 2)) - p);
    if (n.squaredNorm() == 0.0) {
      Fail(what,
           fmt::format("triangle {} (vertices {}, {}, {}) has zero area; TetGen needs a "
                       "surface of proper triangles",
                       f, surface.elements(f, 0), surface.elements(f, 1), surface.elements(f, 2)));
    }
  }
  std::sort(edges.begin(), edges.end(), [](const DirectedEdge& x, const DirectedEdge& y) {
    return std::tie(x.low, x.high, x.triangle) < std::tie(y.low, y.high, y.triangle);
  });
  size_t open_edges = 0;
  size_t first_bad = edges.size();
  size_t run_of_first_bad = 0;
  for (size_t begin = 0; begin < edges.size();) {
    size_t end = begin + 1;
    while (end < edges.size() && edges[end].low == edges[begin].low &&
           edges[end].high == edges[begin].high) {
      ++end;
    }
    const size_t run = end - begin;
    const bool bad = run != 2 || edges[begin].forward == edges[begin + 1].forward;
    if (bad) {
      if (run == 1) ++open_edges;
      if (first_bad == edges.size()) {
        first_bad = begin;
        run_of_first_bad = run;
      }
    }
    begin = end;
  }
  if (first_bad != edges.size()) {
    const DirectedEdge& edge = edges[first_bad];
    std::string problem;
    if (run_of_first_bad == 1) {
      problem = fmt::format(
          "the surface is not closed: edge ({}, {}) belongs to triangle {} "
          "only ({} such boundary edges in total)",
          edge.low, edge.high, edge.triangle, open_edges);
    } else if (run_of_first_bad > 2) {
      problem = fmt::format(
          "the surface is not a manifold: edge ({}, {}) belongs to {} "
          "triangles",
          edge.low, edge.high, run_of_first_bad);
    } else {
      problem = fmt::format(
          "the surface is not consistently oriented: triangles {} and {} "
          "both run through edge ({}, {}) in the same direction",
          edge.triangle, edges[first_bad + 1].triangle, edge.low, edge.high);
    }
    Fail(what, problem +
                   "; TetGen fills closed, consistently oriented surfaces (the boundary "
                   "of a solid)");
  }
}

// Coincident vertices: TetGen would merge them and lose the vertex a handle may refer to.
void CheckNoCoincidentVertices(const Mesh& surface, const std::vector<Index>& vertices,
                               std::string_view what) {
  std::vector<Index> order(vertices);
  std::sort(order.begin(), order.end(), [&](Index a, Index b) {
    const Positions& x = surface.vertices;
    return std::make_tuple(x(a, 0), x(a, 1), x(a, 2)) < std::make_tuple(x(b, 0), x(b, 1), x(b, 2));
  });
  for (size_t i = 1; i < order.size(); ++i) {
    if (surface.vertices.row(order[i]) == surface.vertices.row(order[i - 1])) {
      const Index a = std::min(order[i], order[i - 1]);
      const Index b = std::max(order[i], order[i - 1]);
      Fail(what, fmt::format("vertices {} and {} coincide (at {}, {}, {}); TetGen would merge "
                             "them",
                             a, b, surface.vertices(a, 0), surface.vertices(a, 1),
                             surface.vertices(a, 2)));
    }
  }
}

CompactSurface PrepareSurface(const Mesh& surface, std::string_view what) {
  if (surface.kind() != ElementKind::kTriangle) {
    Fail(what, "tetrahedralize needs a triangle surface, but the mesh has tetrahedra already");
  }
  CheckClosedSurface(surface, what);
  const Index num_triangles = surface.num_elements();
  const auto position = [&](Index v) { return Position(surface, v); };
  CompactSurface compact;
  const std::vector<bool> referenced = ReferencedVertices(surface);
  std::vector<int> to_compact(static_cast<size_t>(surface.num_vertices()), -1);
  for (Index v = 0; v < surface.num_vertices(); ++v) {
    if (!referenced[v]) continue;
    to_compact[v] = static_cast<int>(compact.original.size());
    compact.original.push_back(v);
    for (int d = 0; d < 3; ++d) compact.points.push_back(surface.vertices(v, d));
  }
  CheckNoCoincidentVertices(surface, compact.original, what);
  double six_volume = 0.0;
  compact.triangles.reserve(static_cast<size_t>(num_triangles) * 3);
  for (Index f = 0; f < num_triangles; ++f) {
    for (int a = 0; a < 3; ++a) compact.triangles.push_back(to_compact[surface.elements(f, a)]);
    six_volume +=
        position(surface.elements(f, 0))
            .dot(position(surface.elements(f, 1)).cross(position(surface.elements(f, 2))));
  }
  compact.enclosed_volume = std::abs(six_volume) / 6.0;
  if (!(compact.enclosed_volume > 0.0)) {
    Fail(what, "the surface encloses no volume");
  }
  return compact;
}

// ---------------------------------------------------------------------------------------------
// One TetGen run in a child process.

struct TetGenRun {
  enum class Outcome { kSuccess, kTetGenError, kCrashed, kSystemError };
  Outcome outcome = Outcome::kSystemError;
  int code = 0;              // TetGen's error code, or the signal that ended the child
  std::string system_error;  // for kSystemError
  std::vector<double> points;
  std::vector<int> indices;  // tetrahedra (4 per) or, for a -d run, intersecting faces (3 per)
};

// What the child writes: a header, then `num_points`×3 doubles and `num_indices` ints.
struct RunHeader {
  int32_t tetgen_error = 0;  // 0 or the int TetGen threw (-1: another exception)
  int32_t reserved = 0;
  int64_t num_points = 0;
  int64_t num_indices = 0;
};

bool WriteAll(int fd, const void* data, size_t size) {
  const char* bytes = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t written = ::write(fd, bytes, size);
    if (written < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    bytes += written;
    size -= static_cast<size_t>(written);
  }
  return true;
}

// Runs in the child: never returns, never throws, writes nothing but the result.
[[noreturn]] void RunTetGenChild(int fd, const CompactSurface& surface, std::string switches,
                                 bool detect_intersections) {
  // A crash is an expected outcome here: no core file.
  const rlimit no_core{0, 0};
  ::setrlimit(RLIMIT_CORE, &no_core);
  const int null_device = ::open("/dev/null", O_WRONLY);
  if (null_device >= 0) {
    ::dup2(null_device, STDOUT_FILENO);
    ::dup2(null_device, STDERR_FILENO);
  }
  RunHeader header;
  std::vector<double> points;
  std::vector<int> indices;
  try {
    tetgenio in;
    tetgenio out;
    in.firstnumber = 0;
    in.numberofpoints = static_cast<int>(surface.points.size() / 3);
    in.pointlist = new REAL[surface.points.size()];
    std::copy(surface.points.begin(), surface.points.end(), in.pointlist);
    const int num_triangles = static_cast<int>(surface.triangles.size() / 3);
    in.numberoffacets = num_triangles;
    in.facetlist = new tetgenio::facet[num_triangles];
    for (int f = 0; f < num_triangles; ++f) {
      tetgenio::facet& facet = in.facetlist[f];
      tetgenio::init(&facet);
      facet.numberofpolygons = 1;
      facet.polygonlist = new tetgenio::polygon[1];
      tetgenio::init(&facet.polygonlist[0]);
      facet.polygonlist[0].numberofvertices = 3;
      facet.polygonlist[0].vertexlist = new int[3];
      for (int a = 0; a < 3; ++a) facet.polygonlist[0].vertexlist[a] = surface.triangles[3 * f + a];
    }
    tetrahedralize(switches.data(), &in, &out);
    if (detect_intersections) {
      indices.assign(out.trifacelist,
                     out.trifacelist + 3 * static_cast<size_t>(out.numberoftrifaces));
    } else {
      points.assign(out.pointlist, out.pointlist + 3 * static_cast<size_t>(out.numberofpoints));
      if (out.numberofcorners == 4) {
        indices.assign(out.tetrahedronlist,
                       out.tetrahedronlist + 4 * static_cast<size_t>(out.numberoftetrahedra));
      }
    }
  } catch (int code) {
    header.tetgen_error = code == 0 ? -1 : code;
  } catch (...) {
    header.tetgen_error = -1;
  }
  header.num_points = static_cast<int64_t>(points.size() / 3);
  header.num_indices = static_cast<int64_t>(indices.size());
  const bool ok = WriteAll(fd, &header, sizeof(header)) &&
                  WriteAll(fd, points.data(), points.size() * sizeof(double)) &&
                  WriteAll(fd, indices.data(), indices.size() * sizeof(int));
  ::_exit(ok ? 0 : 1);
}

TetGenRun RunTetGen(const CompactSurface& surface, const std::string& switches,
                    bool detect_intersections) {
  TetGenRun run;
  int fds[2];
  if (::pipe(fds) != 0) {
    run.system_error = fmt::format("cannot create a pipe: {}", std::strerror(errno));
    return run;
  }
  const pid_t child = ::fork();
  if (child < 0) {
    run.system_error = fmt::format("cannot start a process for TetGen: {}", std::strerror(errno));
    ::close(fds[0]);
    ::close(fds[1]);
    return run;
  }
  if (child == 0) {
    ::close(fds[0]);
    RunTetGenChild(fds[1], surface, switches, detect_intersections);
  }
  ::close(fds[1]);
  std::string data;
  char buffer[1 << 16];
  while (true) {
    const ssize_t count = ::read(fds[0], buffer, sizeof(buffer));
    if (count < 0 && errno == EINTR) continue;
    if (count <= 0) break;
    data.append(buffer, static_cast<size_t>(count));
  }
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(child, &status, 0) < 0) {
    if (errno != EINTR) {
      run.system_error = fmt::format("waiting for TetGen failed: {}", std::strerror(errno));
      return run;
    }
  }
  if (WIFSIGNALED(status)) {
    run.outcome = TetGenRun::Outcome::kCrashed;
    run.code = WTERMSIG(status);
    return run;
  }
  RunHeader header;
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || data.size() < sizeof(header)) {
    run.system_error = "the TetGen process ended without a result";
    return run;
  }
  std::memcpy(&header, data.data(), sizeof(header));
  const size_t expected = sizeof(header) +
                          static_cast<size_t>(header.num_points) * 3 * sizeof(double) +
                          static_cast<size_t>(header.num_indices) * sizeof(int);
  if (header.num_points < 0 || header.num_indices < 0 || data.size() != expected) {
    run.system_error = "the TetGen process returned an incomplete result";
    return run;
  }
  if (header.tetgen_error != 0) {
    run.outcome = TetGenRun::Outcome::kTetGenError;
    run.code = header.tetgen_error;
    return run;
  }
  run.outcome = TetGenRun::Outcome::kSuccess;
  run.points.resize(static_cast<size_t>(header.num_points) * 3);
  run.indices.resize(static_cast<size_t>(header.num_indices));
  // memcpy needs valid pointers even for 0 bytes, and an empty vector's data() may be null.
  if (!run.points.empty()) {
    std::memcpy(run.points.data(), data.data() + sizeof(header),
                run.points.size() * sizeof(double));
  }
  if (!run.indices.empty()) {
    std::memcpy(run.indices.data(),
                data.data() + sizeof(header) + run.points.size() * sizeof(double),
                run.indices.size() * sizeof(int));
  }
  return run;
}

// TetGen's exit codes (terminatetetgen() in tetgen.h).
std::string DescribeTetGenError(int code) {
  switch (code) {
    case 1:
      return "TetGen ran out of memory";
    case 2:
      return "TetGen hit an internal error (it does on surfaces that intersect themselves or "
             "nearly touch)";
    case 3:
      return "TetGen found a self-intersection of the surface";
    case 4:
      return "TetGen found a very small input feature (vertices or triangles closer than its "
             "tolerance relative to the mesh size)";
    case 5:
      return "TetGen found two very close (nearly coincident) triangles";
    case 10:
      return "TetGen rejected the input";
    default:
      return fmt::format("TetGen failed (error code {})", code);
  }
}

// After a failure: what TetGen's self-intersection check (-d) says, as a sentence ("" if it
// finds nothing or fails itself).
std::string DescribeIntersections(const CompactSurface& surface) {
  const TetGenRun run = RunTetGen(surface, "pQd", /*detect_intersections=*/true);
  if (run.outcome != TetGenRun::Outcome::kSuccess || run.indices.empty()) return "";
  // Compact triangles back to the surface's triangle numbers.
  std::vector<std::pair<Triple, Index>> lookup;
  const size_t num_triangles = surface.triangles.size() / 3;
  for (size_t f = 0; f < num_triangles; ++f) {
    lookup.emplace_back(Sorted({surface.triangles[3 * f], surface.triangles[3 * f + 1],
                                surface.triangles[3 * f + 2]}),
                        static_cast<Index>(f));
  }
  std::sort(lookup.begin(), lookup.end());
  std::vector<std::string> named;
  const size_t found = run.indices.size() / 3;
  for (size_t i = 0; i < found && named.size() < 4; ++i) {
    const Triple key = Sorted({run.indices[3 * i], run.indices[3 * i + 1], run.indices[3 * i + 2]});
    const auto it = std::lower_bound(lookup.begin(), lookup.end(), std::make_pair(key, Index{0}));
    auto vertex = [&](int a) {
      return surface.original[static_cast<size_t>(run.indices[3 * i + a])];
    };
    if (it != lookup.end() && it->first == key) {
      named.push_back(fmt::format("{} ({}, {}, {})", it->second, vertex(0), vertex(1), vertex(2)));
    }
  }
  if (named.empty()) return "";
  return fmt::format(
      "; TetGen's self-intersection check finds {} triangles in intersecting "
      "pairs, e.g. triangles {}",
      found, fmt::join(named, ", "));
}

// The boundary faces of `mesh`'s tetrahedra (faces of exactly one tetrahedron), sorted.
std::vector<Triple> BoundaryFaces(const Mesh& mesh) {
  static constexpr int kFaces[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  std::vector<Triple> faces;
  faces.reserve(static_cast<size_t>(mesh.num_elements()) * 4);
  for (Index t = 0; t < mesh.num_elements(); ++t) {
    for (const auto& face : kFaces) {
      faces.push_back(Sorted(
          {mesh.elements(t, face[0]), mesh.elements(t, face[1]), mesh.elements(t, face[2])}));
    }
  }
  std::sort(faces.begin(), faces.end());
  std::vector<Triple> boundary;
  for (size_t i = 0; i < faces.size();) {
    size_t j = i + 1;
    while (j < faces.size() && faces[j] == faces[i]) ++j;
    if (j - i == 1) boundary.push_back(faces[i]);
    i = j;
  }
  return boundary;
}

}  // namespace

std::string CheckTetrahedralizeOptions(const TetrahedralizeOptions& options) {
  if (!std::isfinite(options.max_volume) || options.max_volume < 0.0 || options.max_volume >= 1.0) {
    return fmt::format(
        "max_volume must be in [0, 1) (a fraction of the enclosed volume; 0: no "
        "bound), got {}",
        options.max_volume);
  }
  if (!std::isfinite(options.max_radius_edge_ratio) ||
      (options.max_radius_edge_ratio != 0.0 && options.max_radius_edge_ratio < 1.1)) {
    return fmt::format(
        "max_radius_edge_ratio must be 0 (no quality refinement) or at least 1.1, "
        "got {}",
        options.max_radius_edge_ratio);
  }
  if (!std::isfinite(options.min_dihedral_angle) || options.min_dihedral_angle < 0.0 ||
      options.min_dihedral_angle > 25.0) {
    return fmt::format("min_dihedral_angle must be in [0, 25] degrees, got {}",
                       options.min_dihedral_angle);
  }
  if (options.min_dihedral_angle > 0.0 && options.max_radius_edge_ratio == 0.0) {
    return "min_dihedral_angle needs quality refinement (max_radius_edge_ratio > 0)";
  }
  return "";
}

Mesh Tetrahedralize(const Mesh& surface, const TetrahedralizeOptions& options,
                    std::string_view what) {
  const std::string problem = CheckTetrahedralizeOptions(options);
  if (!problem.empty()) throw ConfigError(fmt::format("{}: {}", what, problem));
  const CompactSurface compact = PrepareSurface(surface, what);

  std::string switches = "pYJQ";
  if (options.max_radius_edge_ratio > 0.0) {
    switches += fmt::format("q{}", options.max_radius_edge_ratio);
    if (options.min_dihedral_angle > 0.0)
      switches += fmt::format("/{}", options.min_dihedral_angle);
  }
  if (options.max_volume > 0.0) {
    switches += fmt::format("a{:e}", options.max_volume * compact.enclosed_volume);
  }
  const TetGenRun run = RunTetGen(compact, switches, /*detect_intersections=*/false);
  switch (run.outcome) {
    case TetGenRun::Outcome::kSuccess:
      break;
    case TetGenRun::Outcome::kTetGenError:
      Fail(what, fmt::format("tetrahedralization (TetGen -{}) failed: {}{}", switches,
                             DescribeTetGenError(run.code),
                             run.code == 1 ? "" : DescribeIntersections(compact)));
    case TetGenRun::Outcome::kCrashed:
      Fail(what, fmt::format("tetrahedralization (TetGen -{}) crashed ({}); TetGen 1.5 does so on "
                             "self-intersecting surfaces{}",
                             switches, strsignal(run.code), DescribeIntersections(compact)));
    case TetGenRun::Outcome::kSystemError:
      Fail(what, fmt::format("tetrahedralization (TetGen -{}): {}", switches, run.system_error));
  }

  // Back to the surface's numbering: compact vertex i is surface vertex original[i]; TetGen's
  // Steiner points (index >= the compact count) follow all surface vertices.
  const size_t num_compact = compact.original.size();
  const size_t num_points = run.points.size() / 3;
  if (num_points < num_compact) {
    Fail(what,
         fmt::format("TetGen returned {} points for {} surface vertices", num_points, num_compact));
  }
  for (size_t i = 0; i < num_compact * 3; ++i) {
    if (run.points[i] != compact.points[i]) {
      Fail(what, fmt::format("TetGen moved surface vertex {}", compact.original[i / 3]));
    }
  }
  if (run.indices.empty()) {
    Fail(what, "TetGen produced no tetrahedra (is the surface the boundary of a solid?)");
  }
  const Index num_surface = surface.num_vertices();
  Mesh mesh;
  mesh.vertices.resize(num_surface + static_cast<Index>(num_points - num_compact), 3);
  mesh.vertices.topRows(num_surface) = surface.vertices;
  for (size_t p = num_compact; p < num_points; ++p) {
    for (int d = 0; d < 3; ++d) {
      mesh.vertices(num_surface + static_cast<Index>(p - num_compact), d) = run.points[3 * p + d];
    }
  }
  const Index num_tets = static_cast<Index>(run.indices.size() / 4);
  mesh.elements.resize(num_tets, 4);
  for (Index t = 0; t < num_tets; ++t) {
    for (int a = 0; a < 4; ++a) {
      const int index = run.indices[4 * static_cast<size_t>(t) + a];
      if (index < 0 || static_cast<size_t>(index) >= num_points) {
        Fail(what, fmt::format("TetGen returned tetrahedron {} with point {} of {}", t, index,
                               num_points));
      }
      mesh.elements(t, a) = static_cast<size_t>(index) < num_compact
                                ? compact.original[static_cast<size_t>(index)]
                                : num_surface + static_cast<Index>(index - num_compact);
    }
  }
  ValidateMesh(mesh, what);

  // The surface must be exactly the boundary of the result (TetGen -Y promises it; check).
  std::vector<Triple> triangles;
  triangles.reserve(static_cast<size_t>(surface.num_elements()));
  for (Index f = 0; f < surface.num_elements(); ++f) {
    triangles.push_back(
        Sorted({surface.elements(f, 0), surface.elements(f, 1), surface.elements(f, 2)}));
  }
  std::sort(triangles.begin(), triangles.end());
  if (BoundaryFaces(mesh) != triangles) {
    Fail(what,
         "TetGen's tetrahedra do not have the surface as their boundary (it changed the "
         "surface despite -Y)");
  }
  const TetrahedronOrientation orientation = OrientTetrahedra(mesh);
  if (!orientation.degenerate.empty()) {
    Fail(what, fmt::format("TetGen produced {} flat tetrahedra (e.g. tetrahedron {})",
                           orientation.degenerate.size(), orientation.degenerate.front()));
  }
  return mesh;
}

}  // namespace harap
