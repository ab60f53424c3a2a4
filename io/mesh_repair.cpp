// SPDX-License-Identifier: MIT
#include "io/mesh_repair.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <utility>

#include "framework/disjoint_sets.h"
#include "framework/error.h"
#include "framework/stiffness.h"

namespace harap {

namespace {

void Add(MeshFinding& finding, std::vector<Index> example) {
  if (finding.examples.size() < MeshCheckReport::kMaxExamples) {
    finding.examples.push_back(std::move(example));
  }
  ++finding.count;
}

MeshFinding Finding(std::string name, std::string example_kind) {
  MeshFinding finding;
  finding.name = std::move(name);
  finding.example_kind = std::move(example_kind);
  return finding;
}

bool FiniteRow(const Positions& vertices, Index v) {
  return std::isfinite(vertices(v, 0)) && std::isfinite(vertices(v, 1)) &&
         std::isfinite(vertices(v, 2));
}

// A sort key of N values with the index it belongs to; ordered by key, then index, so a parallel
// sort gives the same order as a stable one. Compared value by value: std::array's operators
// go through memcmp, which dominated the checks on large meshes.
template <class Value, size_t N>
struct KeyedIndex {
  std::array<Value, N> key;
  Index index;

  bool SameKey(const KeyedIndex& other) const {
    for (size_t i = 0; i < N; ++i) {
      if (key[i] != other.key[i]) return false;
    }
    return true;
  }
  bool operator<(const KeyedIndex& other) const {
    for (size_t i = 0; i < N; ++i) {
      if (key[i] != other.key[i]) return key[i] < other.key[i];
    }
    return index < other.index;
  }
};

// The records record_of(0..count−1) (KeyedIndex-like, key[0] a vertex index below
// `num_vertices`), sorted by key, then index: a counting sort on key[0], then each vertex's few
// records by the rest. Several times faster than one comparison sort of all records (the keys of
// sides and elements are vertices); the records are made twice instead of being stored unsorted.
// `bucket_begin_out`, if given, receives where each vertex's records begin (num_vertices + 1
// entries).
template <class MakeRecord>
auto SortByVertexKey(size_t count, Index num_vertices, const MakeRecord& record_of,
                     std::vector<size_t>* bucket_begin_out = nullptr) {
  using Record = decltype(record_of(size_t{0}));
  std::vector<size_t> local_bucket_begin;
  std::vector<size_t>& bucket_begin = bucket_begin_out ? *bucket_begin_out : local_bucket_begin;
  bucket_begin.assign(static_cast<size_t>(num_vertices) + 1, 0);
  for (size_t i = 0; i < count; ++i) ++bucket_begin[record_of(i).key[0] + 1];
  std::partial_sum(bucket_begin.begin(), bucket_begin.end(), bucket_begin.begin());
  std::vector<Record> sorted(count);
  std::vector<size_t> fill(bucket_begin.begin(), bucket_begin.end() - 1);
  for (size_t i = 0; i < count; ++i) {
    const Record record = record_of(i);
    sorted[fill[record.key[0]]++] = record;
  }
  tbb::parallel_for(tbb::blocked_range<Index>(0, num_vertices, 1024),
                    [&](const tbb::blocked_range<Index>& range) {
                      for (Index v = range.begin(); v != range.end(); ++v) {
                        std::sort(sorted.begin() + bucket_begin[v],
                                  sorted.begin() + bucket_begin[v + 1]);
                      }
                    });
  return sorted;
}

// For each of `count` items: the lowest index whose key equals its own, or kNoVertex if that is
// the item itself. `sorted` holds the keyed items (a subset of 0..count−1) sorted by key, index.
template <class Value, size_t N>
std::vector<Index> EarlierEqualKey(Index count, const std::vector<KeyedIndex<Value, N>>& sorted) {
  std::vector<Index> earlier(count, kNoVertex);
  for (size_t i = 1, first = 0; i < sorted.size(); ++i) {
    if (sorted[i].SameKey(sorted[first])) {
      earlier[sorted[i].index] = sorted[first].index;
    } else {
      first = i;
    }
  }
  return earlier;
}

// For each vertex: the lowest-index referenced vertex with exactly the same (finite) coordinates,
// or kNoVertex if it is that vertex itself, unreferenced or not finite.
std::vector<Index> EarlierDuplicateVertex(const Mesh& mesh, const std::vector<bool>& referenced) {
  std::vector<KeyedIndex<double, 3>> records;
  records.reserve(mesh.num_vertices());
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    if (referenced[v] && FiniteRow(mesh.vertices, v)) {
      records.push_back({{mesh.vertices(v, 0), mesh.vertices(v, 1), mesh.vertices(v, 2)}, v});
    }
  }
  tbb::parallel_sort(records.begin(), records.end());
  return EarlierEqualKey(mesh.num_vertices(), records);
}

// For each element: the lowest-index earlier element with the same vertex set, or kNoVertex.
std::vector<Index> EarlierDuplicateElement(const Elements& elements, Index num_vertices) {
  const Index count = static_cast<Index>(elements.rows());
  const int size = static_cast<int>(elements.cols());
  const auto record_of = [&](size_t i) {
    KeyedIndex<Index, 4> record{{kNoVertex, kNoVertex, kNoVertex, kNoVertex},
                                static_cast<Index>(i)};
    for (int a = 0; a < size; ++a) {  // insertion sort of the 3 or 4 vertices
      const Index vertex = elements(record.index, a);
      int b = a;
      for (; b > 0 && record.key[b - 1] > vertex; --b) record.key[b] = record.key[b - 1];
      record.key[b] = vertex;
    }
    return record;
  };
  return EarlierEqualKey(count, SortByVertexKey(count, num_vertices, record_of));
}

bool IsDegenerate(const Mesh& mesh, Index e) {
  const int size = mesh.simplex_size();
  Eigen::Vector3d p[4];
  for (int a = 0; a < size; ++a) p[a] = mesh.vertices.row(mesh.elements(e, a)).transpose();
  double longest = 0.0;
  for (int a = 0; a < size; ++a) {
    for (int b = a + 1; b < size; ++b) longest = std::max(longest, (p[a] - p[b]).squaredNorm());
  }
  if (size == 3) {
    const double double_area = (p[1] - p[0]).cross(p[2] - p[0]).norm();
    return !(double_area > kDegenerateTriangleRatio * longest);  // true for NaN as well
  }
  const double six_volume = std::abs((p[1] - p[0]).dot((p[2] - p[0]).cross(p[3] - p[0])));
  return !(six_volume > kDegenerateTriangleRatio * longest * std::sqrt(longest));
}

double SignedTetVolume6(const Mesh& mesh, Index e) {
  const Eigen::Vector3d p0 = mesh.vertices.row(mesh.elements(e, 0)).transpose();
  return (mesh.vertices.row(mesh.elements(e, 1)).transpose() - p0)
      .dot((mesh.vertices.row(mesh.elements(e, 2)).transpose() - p0)
               .cross(mesh.vertices.row(mesh.elements(e, 3)).transpose() - p0));
}

// A side of an element: an edge of a triangle or a face of a tetrahedron, with its vertices
// sorted (key), the element (index) and (triangles) whether the element runs along it in sorted
// order. Ordered by vertices, then element.
struct Side : KeyedIndex<Index, 3> {
  bool forward;
};

std::vector<Side> CollectSides(const Mesh& mesh) {
  const bool triangles = mesh.kind() == ElementKind::kTriangle;
  const int per_element = triangles ? 3 : 4;
  const auto side_of = [&](size_t i) {
    const Index e = static_cast<Index>(i / per_element);
    const int a = static_cast<int>(i % per_element);
    Side side;
    side.index = e;
    if (triangles) {
      const Index u = mesh.elements(e, a), v = mesh.elements(e, (a + 1) % 3);
      side.key = {std::min(u, v), std::max(u, v), kNoVertex};
      side.forward = u < v;
    } else {  // the face opposite corner a
      for (int b = 0, k = 0; b < 4; ++b) {
        if (b != a) side.key[k++] = mesh.elements(e, b);
      }
      std::sort(side.key.begin(), side.key.end());
      side.forward = true;
    }
    return side;
  };
  return SortByVertexKey(static_cast<size_t>(mesh.num_elements()) * per_element,
                         mesh.num_vertices(), side_of);
}

int CornerOf(const Mesh& mesh, Index e, Index v) {
  for (int a = 0; a < mesh.simplex_size(); ++a) {
    if (mesh.elements(e, a) == v) return a;
  }
  return -1;
}

std::vector<Index> SideExample(const Side& side, bool triangles) {
  std::vector<Index> example(side.key.begin(), side.key.begin() + (triangles ? 2 : 3));
  return example;
}

// Triangles: for each vertex, whether its incident triangles form more than one fan, two of
// them being in one fan when they share an edge at the vertex (directly or through others).
// Works vertex by vertex on its corners (in parallel, in cache): two corners are joined when
// their triangles' other two vertices share one. The repeated corner of a triangle that lists a
// vertex twice joins nothing, so such a vertex always counts as non-manifold.
std::vector<bool> VerticesWithSeveralFans(const Mesh& mesh) {
  const Index n = mesh.num_vertices();
  // Each vertex's corners (3·triangle + corner), ascending.
  std::vector<size_t> corners_begin;
  const std::vector<KeyedIndex<Index, 1>> corners = SortByVertexKey(
      3 * static_cast<size_t>(mesh.num_elements()), n,
      [&](size_t c) {
        return KeyedIndex<Index, 1>{{mesh.elements(static_cast<Index>(c / 3), c % 3)},
                                    static_cast<Index>(c)};
      },
      &corners_begin);
  std::vector<char> several(n, 0);  // not vector<bool>: written from several threads
  tbb::parallel_for(tbb::blocked_range<Index>(0, n, 1024),
                    [&](const tbb::blocked_range<Index>& range) {
                      std::vector<std::pair<Index, Index>> links;  // (other vertex, local corner)
                      DisjointSets<Index> fans;
                      for (Index v = range.begin(); v != range.end(); ++v) {
                        const size_t first = corners_begin[v];
                        const Index count = static_cast<Index>(corners_begin[v + 1] - first);
                        if (count < 2) continue;
                        links.clear();
                        for (Index j = 0; j < count; ++j) {
                          const Index e = corners[first + j].index / 3;
                          const int a = corners[first + j].index % 3;
                          if (CornerOf(mesh, e, v) != a) continue;
                          links.emplace_back(mesh.elements(e, (a + 1) % 3), j);
                          links.emplace_back(mesh.elements(e, (a + 2) % 3), j);
                        }
                        std::sort(links.begin(), links.end());
                        fans.Reset(count);
                        for (size_t i = 1; i < links.size(); ++i) {
                          if (links[i].first == links[i - 1].first)
                            fans.Unite(links[i].second, links[i - 1].second);
                        }
                        // A set's root is its smallest member: corner 0 roots its own fan.
                        for (Index j = 1; j < count && !several[v]; ++j)
                          several[v] = fans.Find(j) != 0;
                      }
                    });
  return std::vector<bool>(several.begin(), several.end());
}

void CheckSides(const Mesh& mesh, MeshCheckReport& report) {
  const bool triangles = mesh.kind() == ElementKind::kTriangle;
  const std::vector<Side> sides = CollectSides(mesh);
  for (size_t begin = 0; begin < sides.size();) {
    size_t end = begin + 1;
    while (end < sides.size() && sides[end].SameKey(sides[begin])) ++end;
    const size_t multiplicity = end - begin;
    if (multiplicity == 1) {
      Add(report.boundary_edges, SideExample(sides[begin], triangles));
    } else if (multiplicity > 2) {
      Add(report.non_manifold_edges, SideExample(sides[begin], triangles));
    } else if (triangles && sides[begin].forward == sides[begin + 1].forward) {
      Add(report.inconsistent_orientation, SideExample(sides[begin], triangles));
    }
    begin = end;
  }
  if (triangles) {
    const std::vector<bool> several = VerticesWithSeveralFans(mesh);
    for (Index v = 0; v < mesh.num_vertices(); ++v) {
      if (several[v]) Add(report.non_manifold_vertices, {v});
    }
  } else {
    // Tetrahedra: orientation is the sign of the volume; the minority sign is "inconsistent".
    Index positive = 0, negative = 0;
    std::vector<double> volumes(mesh.num_elements());
    for (Index e = 0; e < mesh.num_elements(); ++e) {
      volumes[e] = SignedTetVolume6(mesh, e);
      positive += volumes[e] > 0.0;
      negative += volumes[e] < 0.0;
    }
    const bool minority_negative = negative <= positive;
    for (Index e = 0; e < mesh.num_elements(); ++e) {
      if (minority_negative ? volumes[e] < 0.0 : volumes[e] > 0.0) {
        Add(report.inconsistent_orientation, {e});
      }
    }
  }
}

void CheckComponents(const Mesh& mesh, const std::vector<bool>& referenced,
                     const std::vector<Index>& constrained, MeshCheckReport& report) {
  const Index n = mesh.num_vertices();
  DisjointSets<size_t> sets(n);
  for (Index e = 0; e < mesh.num_elements(); ++e) {
    for (int a = 1; a < mesh.simplex_size(); ++a)
      sets.Unite(mesh.elements(e, 0), mesh.elements(e, a));
  }
  std::vector<Index> component_of_root(n, kNoVertex);
  for (Index e = 0; e < mesh.num_elements(); ++e) {
    const size_t root = sets.Find(mesh.elements(e, 0));
    if (component_of_root[root] == kNoVertex) {
      component_of_root[root] = static_cast<Index>(report.components.size());
      report.components.push_back({e, 0, 0, 0});
    }
    ++report.components[component_of_root[root]].elements;
  }
  for (Index v = 0; v < n; ++v) {
    if (referenced[v]) ++report.components[component_of_root[sets.Find(v)]].vertices;
  }
  for (const Index v : constrained) {
    if (v >= 0 && v < n && referenced[v]) {
      ++report.components[component_of_root[sets.Find(v)]].constrained_vertices;
    }
  }
  std::stable_sort(report.components.begin(), report.components.end(),
                   [](const MeshComponentInfo& a, const MeshComponentInfo& b) {
                     return a.elements > b.elements;
                   });
  for (const auto& component : report.components) {
    report.components_without_constraints += component.constrained_vertices == 0;
  }
}

std::string DescribeExample(const MeshFinding& finding, const MeshCheckReport& report) {
  if (finding.examples.empty()) return "";
  const std::vector<Index>& example = finding.examples.front();
  const bool triangles = report.kind == ElementKind::kTriangle;
  const char* element = triangles ? "face" : "tetrahedron";
  if (&finding == &report.duplicate_vertices) {
    return fmt::format("vertex {} is at the position of vertex {}", example[0], example[1]);
  }
  if (&finding == &report.duplicate_elements) {
    return fmt::format("{} {} repeats {} {}", element, example[0], element, example[1]);
  }
  if (finding.example_kind == "edge" || finding.example_kind == "face (vertex triple)") {
    return fmt::format("{} {}", triangles ? "edge" : "face", fmt::join(example, "-"));
  }
  return fmt::format("{} {}", finding.example_kind, example[0]);
}

}  // namespace

std::vector<const MeshFinding*> MeshCheckReport::Findings() const {
  return {&non_finite_vertices, &unreferenced_vertices, &duplicate_vertices,
          &degenerate_elements, &duplicate_elements,    &boundary_edges,
          &non_manifold_edges,  &non_manifold_vertices, &inconsistent_orientation};
}

std::vector<MeshFinding*> MeshCheckReport::Findings() {
  std::vector<MeshFinding*> findings;
  for (const MeshFinding* finding : std::as_const(*this).Findings()) {
    findings.push_back(const_cast<MeshFinding*>(finding));
  }
  return findings;
}

MeshCheckReport CheckMesh(const Mesh& mesh, const std::vector<Index>& constrained) {
  const bool triangles = mesh.kind() == ElementKind::kTriangle;
  const std::string element = triangles ? "face" : "tetrahedron";
  const std::string side = triangles ? "edge" : "face (vertex triple)";
  MeshCheckReport report;
  report.kind = mesh.kind();
  report.vertices = mesh.num_vertices();
  report.elements = mesh.num_elements();
  report.non_finite_vertices = Finding("non_finite_vertices", "vertex");
  report.unreferenced_vertices = Finding("unreferenced_vertices", "vertex");
  report.duplicate_vertices = Finding("duplicate_vertices", "vertex, earlier vertex");
  report.degenerate_elements =
      Finding(triangles ? "zero_area_faces" : "zero_volume_tetrahedra", element);
  report.duplicate_elements = Finding(triangles ? "duplicate_faces" : "duplicate_tetrahedra",
                                      element + ", earlier " + element);
  report.boundary_edges = Finding(triangles ? "boundary_edges" : "boundary_faces", side);
  report.non_manifold_edges =
      Finding(triangles ? "non_manifold_edges" : "non_manifold_faces", side);
  report.non_manifold_vertices = Finding("non_manifold_vertices", "vertex");
  report.inconsistent_orientation =
      Finding(triangles ? "inconsistently_oriented_edges" : "inverted_tetrahedra",
              triangles ? side : element);

  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    if (!FiniteRow(mesh.vertices, v)) Add(report.non_finite_vertices, {v});
  }
  const std::vector<bool> referenced = ReferencedVertices(mesh);
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    if (!referenced[v]) Add(report.unreferenced_vertices, {v});
  }
  const std::vector<Index> earlier_vertex = EarlierDuplicateVertex(mesh, referenced);
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    if (earlier_vertex[v] != kNoVertex) Add(report.duplicate_vertices, {v, earlier_vertex[v]});
  }
  for (Index e = 0; e < mesh.num_elements(); ++e) {
    if (IsDegenerate(mesh, e)) Add(report.degenerate_elements, {e});
  }
  const std::vector<Index> earlier_element =
      EarlierDuplicateElement(mesh.elements, mesh.num_vertices());
  for (Index e = 0; e < mesh.num_elements(); ++e) {
    if (earlier_element[e] != kNoVertex) Add(report.duplicate_elements, {e, earlier_element[e]});
  }
  CheckSides(mesh, report);
  CheckComponents(mesh, referenced, constrained, report);
  return report;
}

MeshRepairOptions MeshRepairOptions::FromConfig(OptionReader node) {
  MeshRepairOptions options;
  options.weld_duplicates = node.Get(
      "weld_duplicates", options.weld_duplicates,
      "merge referenced vertices with identical coordinates before solving (unwelded seams "
      "otherwise open under deformation); output keeps the input's vertices, merged ones share "
      "a position");
  options.drop_duplicate_elements = node.Get(
      "drop_duplicate_elements", options.drop_duplicate_elements,
      "solve with one copy of each element listed more than once (false: every copy adds its "
      "energy)");
  node.RejectUnknownKeys();
  return options;
}

namespace {

// What PreparedProblem changes: which vertex each input vertex becomes (before compaction), the
// elements in those vertices and which of them are kept.
struct RepairPlan {
  std::vector<Index> representative;
  Elements elements;
  std::vector<bool> keep;
  Index welded = 0;     // vertices welded into an earlier one
  Index collapsed = 0;  // elements welding left with two equal corners
  Index dropped = 0;    // repeated elements left out
  bool changes() const { return welded > 0 || collapsed > 0 || dropped > 0; }
};

RepairPlan PlanRepair(const Mesh& mesh, const MeshCheckReport& checks,
                      const MeshRepairOptions& options) {
  RepairPlan plan;
  const std::vector<bool> referenced = ReferencedVertices(mesh);
  plan.representative.resize(mesh.num_vertices());
  std::iota(plan.representative.begin(), plan.representative.end(), 0);
  if (options.weld_duplicates && checks.duplicate_vertices.count > 0) {
    const std::vector<Index> earlier = EarlierDuplicateVertex(mesh, referenced);
    for (Index v = 0; v < mesh.num_vertices(); ++v) {
      if (earlier[v] != kNoVertex) {
        plan.representative[v] = earlier[v];
        ++plan.welded;
      }
    }
  }
  Elements& elements = plan.elements;
  elements = mesh.elements;
  for (Index e = 0; e < elements.rows(); ++e) {
    for (int a = 0; a < elements.cols(); ++a) elements(e, a) = plan.representative[elements(e, a)];
  }
  std::vector<bool>& keep = plan.keep;
  keep.assign(elements.rows(), true);
  for (Index e = 0; e < elements.rows(); ++e) {
    for (int a = 0; a < elements.cols() && keep[e]; ++a) {
      for (int b = 0; b < a; ++b) {
        if (elements(e, a) == elements(e, b)) {
          keep[e] = false;  // welding merged two of its corners: it had no area anyway
          ++plan.collapsed;
          break;
        }
      }
    }
  }
  // Without welding the elements are the checked ones, so the check's count says whether any
  // repeat; welding can make new repeats, so then they are searched again.
  if (options.drop_duplicate_elements && (plan.welded > 0 || checks.duplicate_elements.count > 0)) {
    const std::vector<Index> earlier = EarlierDuplicateElement(elements, mesh.num_vertices());
    for (Index e = 0; e < elements.rows(); ++e) {
      if (keep[e] && earlier[e] != kNoVertex) {
        keep[e] = false;
        ++plan.dropped;
      }
    }
  }
  return plan;
}

// Each finding's action, for the report and the summary (short: they are printed one line per
// finding).
void DescribeActions(const RepairPlan& plan, const MeshRepairOptions& options, bool triangles,
                     MeshCheckReport& checks) {
  const char* element = triangles ? "face" : "tetrahedron";
  checks.non_finite_vertices.action = "rejected";
  checks.unreferenced_vertices.action = "not solved for, kept at their initial positions";
  checks.duplicate_vertices.action =
      plan.welded > 0
          ? fmt::format("welded into the earlier vertex, which both follow{}",
                        plan.collapsed > 0 ? fmt::format("; {} {}s collapsed by welding left out",
                                                         plan.collapsed, element)
                                           : std::string())
          : "kept separate, so the surface may open there; --set mesh.weld_duplicates=true "
            "merges them";
  checks.degenerate_elements.action = "zero weight in the energy";
  checks.duplicate_elements.action =
      options.drop_duplicate_elements
          ? fmt::format(
                "{} copies left out of the solve (mesh.drop_duplicate_elements = false "
                "keeps them)",
                plan.dropped)
          : "kept: each copy adds its energy";
  checks.boundary_edges.action = "fine: open surfaces are allowed";
  const char* no_manifold_needed =
      "fine: the energy needs no manifold connectivity (only `refine` does)";
  checks.non_manifold_edges.action = no_manifold_needed;
  checks.non_manifold_vertices.action = no_manifold_needed;
  checks.inconsistent_orientation.action =
      triangles ? "fine: cotangent weights and rotation fitting ignore face orientation"
                : "reported only";
}

}  // namespace

PreparedProblem::PreparedProblem(const DeformationProblem& problem,
                                 const MeshRepairOptions& options)
    : problem_(problem) {
  HARAP_CHECK(problem.mesh != nullptr, "DeformationProblem without a mesh");
  const Mesh& mesh = *problem.mesh;
  ValidateStiffness(problem.stiffness, mesh, "the stiffness");
  checks_ = CheckMesh(mesh, problem.constraints.indices);

  if (checks_.non_finite_vertices.count > 0) {
    const Index v = checks_.non_finite_vertices.examples.front()[0];
    throw InputError(fmt::format(
        "vertex {} (0-based) has a non-finite coordinate ({}, {}, {}); {} vertices are affected. "
        "Fix the mesh file: ARAP needs finite rest positions",
        v, mesh.vertices(v, 0), mesh.vertices(v, 1), mesh.vertices(v, 2),
        checks_.non_finite_vertices.count));
  }

  const RepairPlan plan = PlanRepair(mesh, checks_, options);
  DescribeActions(plan, options, mesh.kind() == ElementKind::kTriangle, checks_);
  changed_ = plan.changes();
  if (!changed_) return;

  // Compact: welded-away vertices disappear, every other vertex keeps its relative order.
  std::vector<Index> compact(mesh.num_vertices(), kNoVertex);
  Index kept_vertices = 0;
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    if (plan.representative[v] == v) compact[v] = kept_vertices++;
  }
  solved_vertex_.resize(mesh.num_vertices());
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    solved_vertex_[v] = compact[plan.representative[v]];
  }

  repaired_mesh_.planar = mesh.planar;
  repaired_mesh_.vertices.resize(kept_vertices, 3);
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    if (compact[v] != kNoVertex) repaired_mesh_.vertices.row(compact[v]) = mesh.vertices.row(v);
  }
  const Elements& elements = plan.elements;
  const Index kept_elements =
      static_cast<Index>(std::count(plan.keep.begin(), plan.keep.end(), true));
  repaired_mesh_.elements.resize(kept_elements, elements.cols());
  for (Index e = 0, row = 0; e < elements.rows(); ++e) {
    if (!plan.keep[e]) continue;
    for (int a = 0; a < elements.cols(); ++a) {
      repaired_mesh_.elements(row, a) = compact[elements(e, a)];
    }
    ++row;
  }
  problem_.mesh = &repaired_mesh_;
  if (!problem.stiffness.empty()) {
    // Per kept element, as the elements themselves.
    problem_.stiffness.clear();
    for (Index e = 0; e < elements.rows(); ++e) {
      if (plan.keep[e]) problem_.stiffness.push_back(problem.stiffness[e]);
    }
  }
  SetSolvedConstraints(problem, kept_vertices);
  if (problem.initial) {
    Positions initial(kept_vertices, 3);
    for (Index v = 0; v < mesh.num_vertices(); ++v) {
      if (compact[v] != kNoVertex) initial.row(compact[v]) = problem.initial->row(v);
    }
    problem_.initial = std::move(initial);
  }

  // What is left after the repair (e.g. a soup that welding joined into one surface), for the
  // summary: the solved mesh is what the energy sees. Each finding keeps the input's action.
  repaired_checks_ = CheckMesh(repaired_mesh_, problem_.constraints.indices);
  const std::vector<const MeshFinding*> input_findings = std::as_const(checks_).Findings();
  const std::vector<MeshFinding*> repaired_findings = repaired_checks_.Findings();
  for (size_t k = 0; k < repaired_findings.size(); ++k) {
    repaired_findings[k]->action = input_findings[k]->action;
  }
}

void PreparedProblem::SetSolvedConstraints(const DeformationProblem& problem,
                                           Index solved_vertices) {
  // Constraints on merged vertices must agree.
  const Constraints& input = problem.constraints;
  std::vector<Index> constraint_of(solved_vertices, kNoVertex);
  std::vector<std::pair<Index, Index>> solved_constraints;  // (solved vertex, input row)
  for (size_t k = 0; k < input.indices.size(); ++k) {
    const Index v = input.indices[k];
    const Index s = solved_vertex_[v];
    if (constraint_of[s] == kNoVertex) {
      constraint_of[s] = static_cast<Index>(k);
      solved_constraints.emplace_back(s, static_cast<Index>(k));
      continue;
    }
    const Index other = input.indices[constraint_of[s]];
    if (input.targets.row(static_cast<Index>(k)) != input.targets.row(constraint_of[s])) {
      throw InputError(fmt::format(
          "mesh.weld_duplicates: vertices {} and {} (0-based) are at the same position and "
          "would be welded, but the handles move them to different targets ({}, {}, {}) and "
          "({}, {}, {}). Select them with the same handle, or set mesh.weld_duplicates = false",
          other, v, input.targets(constraint_of[s], 0), input.targets(constraint_of[s], 1),
          input.targets(constraint_of[s], 2), input.targets(k, 0), input.targets(k, 1),
          input.targets(k, 2)));
    }
  }
  std::sort(solved_constraints.begin(), solved_constraints.end());
  problem_.constraints.indices.clear();
  problem_.constraints.weights.clear();
  problem_.constraints.targets.resize(static_cast<Index>(solved_constraints.size()), 3);
  for (size_t k = 0; k < solved_constraints.size(); ++k) {
    problem_.constraints.indices.push_back(solved_constraints[k].first);
    problem_.constraints.targets.row(static_cast<Index>(k)) =
        input.targets.row(solved_constraints[k].second);
    if (!input.weights.empty()) {
      problem_.constraints.weights.push_back(input.weights[solved_constraints[k].second]);
    }
  }
}

Positions PreparedProblem::ToInputVertices(const Positions& solved) const {
  if (solved_vertex_.empty()) return solved;
  Positions positions(static_cast<Index>(solved_vertex_.size()), 3);
  for (size_t v = 0; v < solved_vertex_.size(); ++v) {
    positions.row(static_cast<Index>(v)) = solved.row(solved_vertex_[v]);
  }
  return positions;
}

std::vector<std::string> PreparedProblem::Summary() const { return SummarizeMeshChecks(checks_); }

std::vector<std::string> PreparedProblem::RepairedSummary() const {
  return changed_ ? SummarizeMeshChecks(repaired_checks_) : std::vector<std::string>();
}

std::vector<std::string> SummarizeMeshChecks(const MeshCheckReport& checks) {
  std::vector<std::string> lines;
  for (const MeshFinding* finding : checks.Findings()) {
    if (finding->count == 0) continue;
    std::string name = finding->name;
    std::replace(name.begin(), name.end(), '_', ' ');
    if (name.rfind("non manifold", 0) == 0) name[3] = '-';
    lines.push_back(fmt::format("{} {} (e.g. {}): {}", name, finding->count,
                                DescribeExample(*finding, checks), finding->action));
  }
  const auto& components = checks.components;
  if (components.size() > 1 || checks.components_without_constraints > 0) {
    std::string line = fmt::format("components {}", components.size());
    if (checks.components_without_constraints > 0) {
      const auto free = std::find_if(components.begin(), components.end(),
                                     [](const auto& c) { return c.constrained_vertices == 0; });
      line += fmt::format(
          ", {} without a handle (e.g. the one with {} {}, {} {}s): pinned in place by one "
          "vertex each, free to rotate and deform",
          checks.components_without_constraints,
          checks.kind == ElementKind::kTriangle ? "face" : "tetrahedron", free->first_element,
          free->elements, checks.kind == ElementKind::kTriangle ? "face" : "tetrahedron");
    } else {
      line += ", each with a handle";
    }
    lines.push_back(std::move(line));
  }
  return lines;
}

}  // namespace harap
