// SPDX-License-Identifier: MIT
// OctreeHierarchy: structure of the levels (Section 4 of the paper, Eqs. 2–5 and 10), the
// topology check, the fine → coarse maps, options and determinism.
#include "hierarchies/builders/octree_hierarchy.h"

#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <numeric>
#include <set>
#include <string>
#include <vector>

#include "api/builtins.h"
#include "framework/error.h"
#include "io/mesh_io.h"
#include "tests/support/shared_data.h"
#include "tests/support/test_meshes.h"

using namespace harap;
using namespace harap::testing;

namespace {

MeshHierarchy BuildOctree(const Mesh& mesh, OctreeHierarchy::Options options, int threads = 0) {
  return OctreeHierarchy(options).Build(mesh, Context::WithThreads(threads));
}

OctreeHierarchy::Options WithMinVertices(int min_vertices, bool topology_aware = true) {
  OctreeHierarchy::Options options;
  options.min_vertices = min_vertices;
  options.topology_aware = topology_aware;
  return options;
}

Mesh Translated(Mesh mesh, const Eigen::RowVector3d& offset) {
  mesh.vertices.rowwise() += offset;
  return mesh;
}

std::vector<Index> SortedRow(const Elements& elements, Index row) {
  std::vector<Index> s(elements.row(row).data(), elements.row(row).data() + elements.cols());
  std::sort(s.begin(), s.end());
  return s;
}

/// For each finest vertex, its vertex on `level` if it is a member of that vertex's cluster
/// (in_cluster on every level below), else kNoVertex.
std::vector<Index> FinestMembers(const MeshHierarchy& h, int level) {
  const Index n = h.levels[0].mesh.num_vertices();
  std::vector<Index> member(n, kNoVertex);
  for (Index i = 0; i < n; ++i) {
    Index v = i;
    for (int l = 0; l < level && v != kNoVertex; ++l) {
      v = h.levels[l].in_cluster[v] ? h.levels[l].coarse_vertex[v] : kNoVertex;
    }
    member[i] = v;
  }
  return member;
}

/// The structural contract of every level; returns the number of surviving fine elements
/// (before deduplication) summed over the levels.
Index CheckStructure(const Mesh& input, const MeshHierarchy& h) {
  REQUIRE(h.num_levels() >= 1);
  CHECK(h.levels[0].mesh.vertices == input.vertices);
  CHECK(h.levels[0].mesh.elements == input.elements);
  Index survivors = 0;
  for (int l = 0; l < h.num_levels(); ++l) {
    INFO("level " << l);
    const HierarchyLevel& level = h.levels[l];
    const Mesh& mesh = level.mesh;
    const Index n = mesh.num_vertices();
    CHECK(mesh.simplex_size() == input.simplex_size());
    CHECK(mesh.planar == input.planar);
    REQUIRE(mesh.num_elements() > 0);
    CHECK(mesh.elements.minCoeff() >= 0);
    CHECK(mesh.elements.maxCoeff() < n);
    if (l == h.num_levels() - 1) {
      CHECK(level.coarse_vertex.empty());
      CHECK(level.in_cluster.empty());
      continue;
    }
    const Mesh& coarse = h.levels[l + 1].mesh;
    CHECK(coarse.num_vertices() < n);  // strictly fewer vertices
    REQUIRE(level.coarse_vertex.size() == size_t(n));
    REQUIRE(level.in_cluster.size() == size_t(n));

    // Coarse levels are compact: every vertex is used, none twice by one element, no element
    // twice (as a vertex set).
    std::vector<bool> used(coarse.num_vertices(), false);
    std::set<std::vector<Index>> coarse_sets;
    for (Index t = 0; t < coarse.num_elements(); ++t) {
      const std::vector<Index> s = SortedRow(coarse.elements, t);
      CHECK(std::adjacent_find(s.begin(), s.end()) == s.end());
      CHECK(coarse_sets.insert(s).second);
      for (Index v : s) used[v] = true;
    }
    CHECK(std::count(used.begin(), used.end(), false) == 0);

    // Every coarse vertex has a member; maps point into the coarse level.
    std::vector<bool> has_member(coarse.num_vertices(), false);
    for (Index i = 0; i < n; ++i) {
      const Index c = level.coarse_vertex[i];
      CHECK((c == kNoVertex || (c >= 0 && c < coarse.num_vertices())));
      if (level.in_cluster[i]) {
        REQUIRE(c != kNoVertex);
        has_member[c] = true;
      }
    }
    CHECK(std::count(has_member.begin(), has_member.end(), false) == 0);

    // Eq. (5)/(10): the coarse elements are exactly the fine elements whose vertices lie in
    // different surviving clusters, as vertex sets.
    std::set<std::vector<Index>> mapped;
    for (Index t = 0; t < mesh.num_elements(); ++t) {
      std::vector<Index> s;
      bool members = true;
      for (int a = 0; a < mesh.simplex_size(); ++a) {
        const Index v = mesh.elements(t, a);
        members = members && level.in_cluster[v];
        s.push_back(level.coarse_vertex[v]);
      }
      std::sort(s.begin(), s.end());
      if (!members || std::adjacent_find(s.begin(), s.end()) != s.end()) continue;
      mapped.insert(s);
      ++survivors;
    }
    CHECK(mapped == coarse_sets);
  }
  return survivors;
}

/// Every vertex referenced by an element maps to a coarse vertex on every level.
void CheckAllMapped(const MeshHierarchy& h) {
  const Mesh& mesh = h.levels[0].mesh;
  const std::vector<bool> referenced = ReferencedVertices(mesh);
  for (int l = 1; l < h.num_levels(); ++l) {
    Index unmapped = 0;
    for (Index i = 0; i < mesh.num_vertices(); ++i) {
      const Index v = h.MapFinestVertex(i, l);
      if (referenced[i] && (v == kNoVertex || v >= h.levels[l].mesh.num_vertices())) ++unmapped;
    }
    INFO("level " << l);
    CHECK(unmapped == 0);
  }
}

void CheckEqual(const MeshHierarchy& a, const MeshHierarchy& b) {
  REQUIRE(a.num_levels() == b.num_levels());
  for (int l = 0; l < a.num_levels(); ++l) {
    INFO("level " << l);
    CHECK(a.levels[l].mesh.vertices == b.levels[l].mesh.vertices);
    CHECK(a.levels[l].mesh.elements == b.levels[l].mesh.elements);
    CHECK(a.levels[l].coarse_vertex == b.levels[l].coarse_vertex);
    CHECK(a.levels[l].in_cluster == b.levels[l].in_cluster);
  }
}

/// Eq. (2)–(3) recomputed independently: the per-axis bit depth and integer coordinates.
struct IntegerGrid {
  Eigen::RowVector3d lo, hi;
  std::array<int, 3> bits{};

  explicit IntegerGrid(const Mesh& mesh) {
    lo = mesh.vertices.colwise().minCoeff();
    hi = mesh.vertices.colwise().maxCoeff();
    std::set<std::pair<Index, Index>> edges;
    for (Index t = 0; t < mesh.num_elements(); ++t) {
      for (int a = 0; a < mesh.simplex_size(); ++a) {
        for (int b = a + 1; b < mesh.simplex_size(); ++b) {
          edges.insert(std::minmax(mesh.elements(t, a), mesh.elements(t, b)));
        }
      }
    }
    double sum = 0.0;
    for (const auto& [a, b] : edges) sum += (mesh.vertices.row(a) - mesh.vertices.row(b)).norm();
    const double mean_edge = sum / double(edges.size());
    for (int d = 0; d < 3; ++d) {
      // The smallest q whose cell extent / (2^q − 1) is at most Ē (0 for a flat axis).
      int q = 0;
      while (hi[d] - lo[d] > mean_edge * (q == 0 ? 1.0 : double((1 << q) - 1))) ++q;
      bits[d] = q;
    }
  }
  std::array<long, 3> W(const Eigen::RowVector3d& p) const {
    std::array<long, 3> w{};
    for (int d = 0; d < 3; ++d) {
      const double top = double((1L << bits[d]) - 1);
      w[d] = bits[d] == 0 ? 0 : long(std::floor(top * ((p[d] - lo[d]) / (hi[d] - lo[d])) + 0.5));
    }
    return w;
  }
  std::array<long, 3> Cell(const Eigen::RowVector3d& p, int shift) const {
    std::array<long, 3> c = W(p);
    for (long& x : c) x >>= shift;
    return c;
  }
  Eigen::RowVector3d Centre(const std::array<long, 3>& cell, int shift) const {
    Eigen::RowVector3d p;
    for (int d = 0; d < 3; ++d) {
      const long top = (1L << bits[d]) - 1;
      const long first = cell[d] << shift, last = std::min(((cell[d] + 1) << shift) - 1, top);
      const double step = bits[d] == 0 ? 0.0 : (hi[d] - lo[d]) / double(top);
      p[d] = lo[d] + 0.5 * double(first + last) * step;
    }
    return p;
  }
};

}  // namespace

TEST_CASE("octree: level structure on generated meshes", "[hierarchies][octree]") {
  const std::vector<std::pair<std::string, Mesh>> meshes = {
      {"icosphere", Icosphere(5)}, {"tube", Tube(80, 64)}, {"grid", Grid(90, 70)}};
  for (const auto& [name, mesh] : meshes) {
    for (bool aware : {true, false}) {
      DYNAMIC_SECTION(name << (aware ? " topology-aware" : " plain")) {
        const MeshHierarchy h = BuildOctree(mesh, WithMinVertices(20, aware));
        CHECK(h.num_levels() >= 4);
        CheckStructure(mesh, h);
        CheckAllMapped(h);  // the meshes are connected
        CHECK(h.levels.back().mesh.num_vertices() <= 20);
      }
    }
  }
}

TEST_CASE("octree: clusters are cells of the nested grid (Eqs. 2–4)", "[hierarchies][octree]") {
  Mesh mesh = Grid(57, 41);
  for (Index i = 0; i < mesh.num_vertices(); ++i) {
    mesh.vertices(i, 2) = 0.05 * std::sin(4.0 * mesh.vertices(i, 0)) * mesh.vertices(i, 1);
  }
  // z spans a few edge lengths: q_z < q_x, q_y, so the coarser cells are clipped in z.
  const IntegerGrid grid(mesh);
  REQUIRE(grid.bits[2] >= 1);
  REQUIRE(grid.bits[2] + 2 < grid.bits[0]);
  for (bool aware : {true, false}) {
    OctreeHierarchy::Options options = WithMinVertices(10, aware);
    options.coarse_positions = OctreeHierarchy::CoarsePositions::kQuantized;
    const MeshHierarchy h = BuildOctree(mesh, options);
    REQUIRE(h.num_levels() >= 3);
    for (int l = 1; l < h.num_levels(); ++l) {
      DYNAMIC_SECTION((aware ? "topology-aware" : "plain") << " level " << l) {
        // On this mesh every shift merges vertices, so level l uses the cells w >> l.
        const std::vector<Index> member = FinestMembers(h, l);
        std::map<Index, std::array<long, 3>> cell_of;
        std::map<std::array<long, 3>, std::set<Index>> vertices_in_cell;
        for (Index i = 0; i < mesh.num_vertices(); ++i) {
          if (member[i] == kNoVertex) continue;
          const auto cell = grid.Cell(mesh.vertices.row(i), l);
          const auto [it, inserted] = cell_of.emplace(member[i], cell);
          CHECK(it->second == cell);  // a cluster lies in one cell
          vertices_in_cell[cell].insert(member[i]);
        }
        for (const auto& [cell, coarse] : vertices_in_cell) {
          // Without the topology check a cell is one cluster (with it, a cell may split).
          if (!aware) CHECK(coarse.size() == 1);
          if (coarse.size() != 1) continue;
          // Quantized positions: the cell centre decoded from the truncated coordinates.
          const Index c = *coarse.begin();
          CHECK((h.levels[l].mesh.vertices.row(c) - grid.Centre(cell, l)).norm() < 1e-12);
        }
      }
    }
  }
}

TEST_CASE("octree: mean coarse positions average the finest members", "[hierarchies][octree]") {
  const Mesh mesh = Icosphere(4);
  const MeshHierarchy h = BuildOctree(mesh, WithMinVertices(30));
  REQUIRE(h.num_levels() >= 3);
  for (int l = 1; l < h.num_levels(); ++l) {
    const std::vector<Index> member = FinestMembers(h, l);
    const Index n = h.levels[l].mesh.num_vertices();
    Positions sum = Positions::Zero(n, 3);
    std::vector<int> count(n, 0);
    for (Index i = 0; i < mesh.num_vertices(); ++i) {
      if (member[i] == kNoVertex) continue;
      sum.row(member[i]) += mesh.vertices.row(i);
      ++count[member[i]];
    }
    for (Index c = 0; c < n; ++c) {
      REQUIRE(count[c] > 0);
      CHECK((h.levels[l].mesh.vertices.row(c) - sum.row(c) / count[c]).norm() < 1e-12);
    }
  }
}

TEST_CASE("octree: parallel sheets merge only without the topology check",
          "[hierarchies][octree]") {
  // Two unconnected copies of a grid, 1/1000 of a cell apart.
  const Mesh sheet = Grid(48, 48);
  const Mesh sheets = Concatenate(sheet, Translated(sheet, Eigen::RowVector3d(0, 0, 1e-3 / 47)));
  const Index half = sheet.num_vertices();
  auto sheets_per_coarse_vertex = [&](const MeshHierarchy& h, int level) {
    std::vector<std::set<int>> sheets_of(h.levels[level].mesh.num_vertices());
    for (Index i = 0; i < sheets.num_vertices(); ++i) {
      const Index v = h.MapFinestVertex(i, level);
      REQUIRE(v != kNoVertex);
      sheets_of[v].insert(i < half ? 0 : 1);
    }
    return sheets_of;
  };

  SECTION("topology-aware: no coarse vertex takes vertices of both sheets") {
    for (auto positions :
         {OctreeHierarchy::CoarsePositions::kMean, OctreeHierarchy::CoarsePositions::kQuantized}) {
      OctreeHierarchy::Options options = WithMinVertices(20, true);
      options.coarse_positions = positions;
      const MeshHierarchy h = BuildOctree(sheets, options);
      REQUIRE(h.num_levels() >= 3);
      CheckStructure(sheets, h);
      for (int l = 1; l < h.num_levels(); ++l) {
        for (const auto& s : sheets_per_coarse_vertex(h, l)) CHECK(s.size() == 1);
        // Split cells hold one cluster per sheet; they must not coincide (quantized positions
        // fall back to the mean there).
        const Positions& v = h.levels[l].mesh.vertices;
        std::set<std::array<double, 3>> distinct;
        for (Index c = 0; c < v.rows(); ++c) distinct.insert({v(c, 0), v(c, 1), v(c, 2)});
        CHECK(distinct.size() == size_t(v.rows()));
      }
    }
  }
  SECTION("plain clustering merges the sheets") {
    const MeshHierarchy h = BuildOctree(sheets, WithMinVertices(20, false));
    REQUIRE(h.num_levels() >= 2);
    const Index survivors = CheckStructure(sheets, h);
    Index coarse_elements = 0;
    for (int l = 1; l < h.num_levels(); ++l) coarse_elements += h.levels[l].mesh.num_elements();
    CHECK(survivors > coarse_elements);  // both sheets' copies of a triangle are kept once
    Index both = 0;
    for (const auto& s : sheets_per_coarse_vertex(h, 1)) both += s.size() == 2;
    CHECK(both == h.levels[1].mesh.num_vertices());
  }
}

TEST_CASE("octree: vertices of vanished clusters map to the closest survivor",
          "[hierarchies][octree]") {
  // A grid with a long strip, much thinner than a cell, attached at its corner (1, 1): every
  // strip triangle collapses on level 1, and the strip's only way back is through the corner.
  const int n = 21, strip = 30;
  Mesh mesh = Grid(n, n);
  const Index corner = n * n - 1;
  const Index first = mesh.num_vertices();
  mesh.vertices.conservativeResize(first + 2 * strip, 3);
  for (int s = 0; s < strip; ++s) {
    const double x = 1.0 + (s + 1) * 0.05;
    mesh.vertices.row(first + 2 * s) << x, 1.0, 0.0;
    mesh.vertices.row(first + 2 * s + 1) << x, 1.0 + 1e-5, 0.0;
  }
  // A tiny separate triangle that vanishes entirely.
  const Index island = mesh.num_vertices();
  mesh.vertices.conservativeResize(island + 3, 3);
  mesh.vertices.row(island) << 0.5, -0.5, 0.0;
  mesh.vertices.row(island + 1) << 0.5 + 1e-5, -0.5, 0.0;
  mesh.vertices.row(island + 2) << 0.5, -0.5 + 1e-5, 0.0;
  std::vector<std::array<Index, 3>> faces;
  for (Index t = 0; t < mesh.num_elements(); ++t) {
    faces.push_back({mesh.elements(t, 0), mesh.elements(t, 1), mesh.elements(t, 2)});
  }
  Index previous_bottom = corner, previous_top = corner;
  for (int s = 0; s < strip; ++s) {
    const Index bottom = first + 2 * s, top = first + 2 * s + 1;
    if (s == 0) {
      faces.push_back({corner, bottom, top});
    } else {
      faces.push_back({previous_bottom, bottom, top});
      faces.push_back({previous_bottom, top, previous_top});
    }
    previous_bottom = bottom;
    previous_top = top;
  }
  faces.push_back({island, island + 1, island + 2});
  mesh.elements.resize(faces.size(), 3);
  for (size_t t = 0; t < faces.size(); ++t) {
    mesh.elements.row(t) << faces[t][0], faces[t][1], faces[t][2];
  }

  for (bool aware : {true, false}) {
    DYNAMIC_SECTION((aware ? "topology-aware" : "plain")) {
      const MeshHierarchy h = BuildOctree(mesh, WithMinVertices(10, aware));
      REQUIRE(h.num_levels() >= 2);
      CheckStructure(mesh, h);
      const HierarchyLevel& level0 = h.levels[0];
      REQUIRE(level0.in_cluster[corner]);
      Index substitutes = 0;
      for (Index i = first; i < island; ++i) {
        // Strip vertices in the corner's cell belong to its cluster; the others are replaced
        // by the corner's coarse vertex, the only survivor they can reach.
        CHECK(level0.coarse_vertex[i] == level0.coarse_vertex[corner]);
        substitutes += level0.in_cluster[i] ? 0 : 1;
      }
      CHECK(substitutes > strip);
      for (Index i = island; i < island + 3; ++i) {
        CHECK(level0.coarse_vertex[i] == kNoVertex);
        CHECK(level0.in_cluster[i] == 0);
      }
    }
  }
}

TEST_CASE("octree: unreferenced input vertices map to no coarse vertex", "[hierarchies][octree]") {
  Mesh mesh = Icosphere(4);
  const Index n = mesh.num_vertices();
  mesh.vertices.conservativeResize(n + 3, 3);
  mesh.vertices.row(n) << 0.0, 0.0, 0.0;            // inside the sphere, in a cell of its own
  mesh.vertices.row(n + 1) << 1.0, 0.0, 0.0;        // on the sphere: shares a cell with it
  mesh.vertices.row(n + 2) = mesh.vertices.row(5);  // coincides with a referenced vertex
  for (bool aware : {true, false}) {
    DYNAMIC_SECTION((aware ? "topology-aware" : "plain")) {
      const MeshHierarchy h = BuildOctree(mesh, WithMinVertices(30, aware));
      REQUIRE(h.num_levels() >= 3);
      CheckStructure(mesh, h);
      CHECK(h.levels[0].mesh.num_vertices() == n + 3);
      for (Index i = n; i < n + 3; ++i) {
        CHECK(h.levels[0].coarse_vertex[i] == kNoVertex);
        CHECK(h.levels[0].in_cluster[i] == 0);
        CHECK(h.MapFinestVertex(i, h.num_levels() - 1) == kNoVertex);
      }
      CheckAllMapped(h);
      // The coarse levels do not see them: same as without them.
      Mesh referenced_only = mesh;
      referenced_only.vertices.conservativeResize(n, 3);
      const MeshHierarchy reference = BuildOctree(referenced_only, WithMinVertices(30, aware));
      REQUIRE(reference.num_levels() == h.num_levels());
      for (int l = 1; l < h.num_levels(); ++l) {
        CHECK(reference.levels[l].mesh.vertices == h.levels[l].mesh.vertices);
        CHECK(reference.levels[l].mesh.elements == h.levels[l].mesh.elements);
      }
    }
  }
}

TEST_CASE("octree: min_vertices and max_levels stop the hierarchy", "[hierarchies][octree]") {
  const Mesh mesh = Icosphere(5);  // 10242 vertices
  SECTION("min_vertices") {
    for (int min_vertices : {0, 50, 750, 3000}) {
      const MeshHierarchy h = BuildOctree(mesh, WithMinVertices(min_vertices));
      const int last = h.num_levels() - 1;
      INFO("min_vertices " << min_vertices << ", levels " << h.num_levels());
      REQUIRE(last >= 1);
      CHECK(h.levels[last - 1].mesh.num_vertices() > min_vertices);
      if (min_vertices > 0) CHECK(h.levels[last].mesh.num_vertices() <= min_vertices);
    }
    // The default is the paper's 750.
    const MeshHierarchy h = BuildOctree(mesh, OctreeHierarchy::Options{});
    CHECK(h.levels.back().mesh.num_vertices() <= 750);
    CHECK(h.levels[h.num_levels() - 2].mesh.num_vertices() > 750);
    // Already small enough: one level.
    CHECK(BuildOctree(mesh, WithMinVertices(10242)).num_levels() == 1);
    CHECK(BuildOctree(Icosphere(2), OctreeHierarchy::Options{}).num_levels() == 1);
  }
  SECTION("coarsest = at_least keeps every level at or above min_vertices (the paper's rule)") {
    for (int min_vertices : {50, 750, 3000}) {
      const MeshHierarchy at_most = BuildOctree(mesh, WithMinVertices(min_vertices));
      OctreeHierarchy::Options options = WithMinVertices(min_vertices);
      options.coarsest = LevelLimits::Coarsest::kAtLeast;
      const MeshHierarchy at_least = BuildOctree(mesh, options);
      INFO("min_vertices " << min_vertices << ", levels " << at_least.num_levels());
      CheckStructure(mesh, at_least);
      CHECK(at_least.levels.back().mesh.num_vertices() >= min_vertices);
      CHECK(at_least.levels.back().coarse_vertex.empty());
      // The same levels, without the one at_most adds below the bound.
      REQUIRE(at_least.num_levels() == at_most.num_levels() - 1);
      for (int l = 0; l < at_least.num_levels(); ++l) {
        CHECK(at_least.levels[l].mesh.num_vertices() == at_most.levels[l].mesh.num_vertices());
      }
    }
    // A first coarse level below the bound leaves the input alone.
    OctreeHierarchy::Options options = WithMinVertices(10000);
    options.coarsest = LevelLimits::Coarsest::kAtLeast;
    CHECK(BuildOctree(mesh, options).num_levels() == 1);
  }
  SECTION("min_vertices 0 coarsens until nothing is left to merge") {
    const MeshHierarchy h = BuildOctree(mesh, WithMinVertices(0));
    CheckStructure(mesh, h);
    CHECK(h.levels.back().mesh.num_vertices() < 20);
  }
  SECTION("max_levels") {
    for (int max_levels : {1, 2, 3}) {
      OctreeHierarchy::Options options = WithMinVertices(0);
      options.max_levels = max_levels;
      const MeshHierarchy h = BuildOctree(mesh, options);
      CHECK(h.num_levels() == max_levels);
      CheckStructure(mesh, h);
    }
  }
}

TEST_CASE("octree: tetrahedral meshes (Eq. 10)", "[hierarchies][octree]") {
  const std::vector<std::pair<std::string, Mesh>> meshes = {
      {"6-tet box", TetBox(14, 14, 14, 6)},
      {"jittered 5-tet box", Jittered(TetBox(13, 12, 11, 5), 13, 0.2, 5)}};
  for (const auto& [name, mesh] : meshes) {
    for (bool aware : {true, false}) {
      for (auto positions : {OctreeHierarchy::CoarsePositions::kMean,
                             OctreeHierarchy::CoarsePositions::kQuantized}) {
        DYNAMIC_SECTION(name << (aware ? " topology-aware " : " plain ")
                             << OctreeHierarchy::ToString(positions)) {
          OctreeHierarchy::Options options = WithMinVertices(20, aware);
          options.coarse_positions = positions;
          const MeshHierarchy h = BuildOctree(mesh, options);
          REQUIRE(h.num_levels() >= 3);
          CheckStructure(mesh, h);
          CheckAllMapped(h);
          for (const auto& level : h.levels) CHECK(level.mesh.elements.cols() == 4);
        }
      }
    }
  }
}

TEST_CASE("octree: planar meshes stay in the plane", "[hierarchies][octree]") {
  const Mesh mesh = PlanarGrid(64, 40);
  // A quadtree: the flat z axis is a single cell (q_z = 0), so cells never split along z.
  REQUIRE(IntegerGrid(mesh).bits[2] == 0);
  for (auto positions :
       {OctreeHierarchy::CoarsePositions::kMean, OctreeHierarchy::CoarsePositions::kQuantized}) {
    OctreeHierarchy::Options options = WithMinVertices(20);
    options.coarse_positions = positions;
    const MeshHierarchy h = BuildOctree(mesh, options);
    REQUIRE(h.num_levels() >= 3);
    CheckStructure(mesh, h);
    for (const auto& level : h.levels) {
      CHECK(level.mesh.planar);
      CHECK(level.mesh.vertices.col(2).cwiseAbs().maxCoeff() == 0.0);
    }
  }
}

TEST_CASE("octree: deterministic, whatever the thread count", "[hierarchies][octree]") {
  Mesh mesh = Concatenate(Tube(60, 48), Icosphere(4));
  for (bool aware : {true, false}) {
    OctreeHierarchy::Options options = WithMinVertices(40, aware);
    options.coarse_positions = aware ? OctreeHierarchy::CoarsePositions::kQuantized
                                     : OctreeHierarchy::CoarsePositions::kMean;
    const MeshHierarchy a = BuildOctree(mesh, options, 1);
    const MeshHierarchy b = BuildOctree(mesh, options, 2);
    const MeshHierarchy c = BuildOctree(mesh, options, 2);
    REQUIRE(a.num_levels() >= 3);
    CheckEqual(a, b);
    CheckEqual(b, c);
  }
}

TEST_CASE("octree: options from config", "[hierarchies][octree]") {
  const Registries registries = MakeBuiltinRegistries();
  REQUIRE(registries.hierarchies.Contains("octree"));

  SECTION("defaults") {
    const auto options = OctreeHierarchy::Options::FromConfig(OptionReader(ConfigNode()));
    CHECK(options.topology_aware);
    CHECK(options.coarse_positions == OctreeHierarchy::CoarsePositions::kMean);
    CHECK(options.min_vertices == 750);
    CHECK(options.max_levels == 0);
    std::vector<std::string> keys;
    for (const auto& option : registries.hierarchies.DescribeOptions("octree")) {
      keys.push_back(option.key);
    }
    CHECK(options.coarsest == LevelLimits::Coarsest::kAtMost);
    CHECK(keys == std::vector<std::string>{"topology_aware", "coarse_positions", "min_vertices",
                                           "coarsest", "max_levels"});
  }
  SECTION("values are read") {
    const std::string table =
        "topology_aware = false\ncoarse_positions = \"quantized\"\nmin_vertices = 100\n"
        "coarsest = \"at_least\"\nmax_levels = 4\n";
    const auto options =
        OctreeHierarchy::Options::FromConfig(OptionReader(ConfigNode::Parse(table, "test")));
    const ConfigNode config = ConfigNode::Parse("[hierarchy]\ntype = \"octree\"\n" + table, "test");
    CHECK_FALSE(options.topology_aware);
    CHECK(options.coarse_positions == OctreeHierarchy::CoarsePositions::kQuantized);
    CHECK(options.min_vertices == 100);
    CHECK(options.coarsest == LevelLimits::Coarsest::kAtLeast);
    CHECK(options.max_levels == 4);
    auto hierarchy = registries.hierarchies.Create(config.Child("hierarchy"), "octree");
    const MeshHierarchy h = hierarchy->Build(Icosphere(4), Context());
    CHECK(h.num_levels() <= 4);
    CHECK(h.levels.back().mesh.num_vertices() >= 100);
  }
  SECTION("unknown keys and bad values are rejected") {
    auto create = [&](const std::string& table) {
      const ConfigNode config = ConfigNode::Parse("[hierarchy]\n" + table, "test");
      return registries.hierarchies.Create("octree", config.Child("hierarchy"));
    };
    auto error = [&](const std::string& table) -> std::string {
      try {
        create(table);
      } catch (const ConfigError& e) {
        return e.what();
      }
      return "no ConfigError";
    };
    using Catch::Matchers::Contains;
    CHECK_THAT(error("min_vertexes = 10\n"),
               Contains("min_vertexes") && Contains("topology_aware") &&
                   Contains("coarse_positions") && Contains("min_vertices") &&
                   Contains("max_levels"));
    CHECK_THAT(error("coarse_positions = \"centroid\"\n"),
               Contains("centroid") && Contains("mean") && Contains("quantized"));
    CHECK_THAT(error("min_vertices = -1\n"), Contains("min_vertices"));
    CHECK_THAT(error("max_levels = -2\n"), Contains("max_levels"));
    CHECK_THAT(error("coarsest = \"above\"\n"),
               Contains("above") && Contains("at_most") && Contains("at_least"));
    CHECK_THROWS_AS(create("topology_aware = \"yes\"\n"), ConfigError);
    CHECK_THROWS_AS(create("min_vertices = 1.5\n"), ConfigError);
    OctreeHierarchy::Options bad;
    bad.max_levels = -1;
    CHECK_THROWS_AS(OctreeHierarchy(bad), ConfigError);
  }
}

TEST_CASE("octree: Armadillo", "[hierarchies][octree][shared]") {
  HARAP_REQUIRE_SHARED(file, "meshes/armadillo-43k.obj.xz");
  const Mesh mesh = ReadMesh(file);
  for (bool aware : {true, false}) {
    DYNAMIC_SECTION((aware ? "topology-aware" : "plain")) {
      const MeshHierarchy h = BuildOctree(mesh, WithMinVertices(750, aware));
      INFO("levels " << h.num_levels());
      CHECK(h.num_levels() >= 4);
      CheckStructure(mesh, h);
      CheckAllMapped(h);
      CHECK(h.levels.back().mesh.num_vertices() <= 750);
    }
  }
}

TEST_CASE("octree: degenerate inputs give a single level", "[hierarchies][octree]") {
  OctreeHierarchy::Options options = WithMinVertices(0);
  SECTION("no elements") {
    Mesh mesh = Icosphere(2);
    mesh.elements.resize(0, 3);
    const MeshHierarchy h = BuildOctree(mesh, options);
    REQUIRE(h.num_levels() == 1);
    CHECK(h.levels[0].mesh.vertices == mesh.vertices);
    CHECK(h.levels[0].coarse_vertex.empty());
  }
  SECTION("all vertices in one point") {
    Mesh mesh = Icosphere(2);
    mesh.vertices.setConstant(0.5);
    CHECK(BuildOctree(mesh, options).num_levels() == 1);
  }
  SECTION("a single triangle") {
    Mesh mesh;
    mesh.vertices.resize(3, 3);
    mesh.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0;
    mesh.elements.resize(1, 3);
    mesh.elements << 0, 1, 2;
    const MeshHierarchy h = BuildOctree(mesh, options);
    CHECK(h.num_levels() == 1);
  }
  SECTION("bad element indices are an internal error") {
    Mesh mesh = Icosphere(1);
    mesh.elements(3, 1) = mesh.num_vertices();
    CHECK_THROWS_AS(BuildOctree(mesh, options), InternalError);
  }
}
