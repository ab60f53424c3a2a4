// SPDX-License-Identifier: MIT
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "framework/config.h"
#include "framework/mesh.h"
#include "framework/optimizer.h"

namespace harap {

/// One kind of defect found by CheckMesh: how many elements have it, a few of them (for messages
/// and reports) and what the run does about it.
struct MeshFinding {
  std::string name;  ///< Report key, e.g. "duplicate_vertices".
  Index count = 0;   ///< Number of offending vertices / edges / faces.
  /// Up to kMaxExamples examples, each a tuple of 0-based indices whose meaning `example_kind`
  /// gives ("vertex", "vertex, earlier vertex at the same position", "edge", "face", ...).
  std::vector<std::vector<Index>> examples;
  std::string example_kind;
  std::string action;  ///< What the run does (filled by PrepareMesh).
};

/// One connected component of the elements (elements sharing a vertex index are connected).
struct MeshComponentInfo {
  Index first_element = 0;  ///< Lowest element index in the component (names it in messages).
  Index elements = 0;
  Index vertices = 0;
  Index constrained_vertices = 0;  ///< Handle vertices in it (0: pinned, see ConstrainedSystem).
};

/// Everything CheckMesh measures. Counts follow the definitions of ../shared/meshes/README.md
/// (MANIFEST.tsv), so they can be compared with it.
struct MeshCheckReport {
  static constexpr size_t kMaxExamples = 5;

  ElementKind kind = ElementKind::kTriangle;
  Index vertices = 0;
  Index elements = 0;

  MeshFinding non_finite_vertices;  ///< A coordinate is NaN or ±inf.
  MeshFinding unreferenced_vertices;
  /// Vertices whose exact coordinates repeat an earlier *referenced* vertex's; examples are
  /// (vertex, earlier vertex). Unreferenced vertices are not counted (they stay where they are).
  MeshFinding duplicate_vertices;
  /// Triangles with 2·area ≤ kDegenerateTriangleRatio · (longest edge)² (tetrahedra: 6·volume ≤
  /// kDegenerateTriangleRatio · (longest edge)³): the energies give them zero weight.
  MeshFinding degenerate_elements;
  MeshFinding duplicate_elements;  ///< Same vertex set as an earlier element: (element, earlier).
  MeshFinding boundary_edges;      ///< Edges (faces for tetrahedra) of exactly one element.
  MeshFinding non_manifold_edges;  ///< Edges of > 2 triangles (faces of > 2 tetrahedra).
  /// Vertices whose incident triangles form more than one fan (connected through shared edges);
  /// not computed for tetrahedra.
  MeshFinding non_manifold_vertices;
  /// Triangles: interior edges whose two triangles traverse them in the same direction.
  /// Tetrahedra: elements with negative signed volume when most are positive (or vice versa).
  MeshFinding inconsistent_orientation;

  std::vector<MeshComponentInfo> components;  ///< Largest first (ties: lowest first element).
  Index components_without_constraints = 0;

  /// The findings above in report order (pointers into this object).
  std::vector<const MeshFinding*> Findings() const;
  std::vector<MeshFinding*> Findings();
};

/// Analyses `mesh` (any vertex positions, even non-finite; indices must be in range, see
/// ValidateMesh) with the constrained vertex indices `constrained`. O(#elements log #elements).
MeshCheckReport CheckMesh(const Mesh& mesh, const std::vector<Index>& constrained);

/// Short human-readable lines for `checks`: one per finding with a non-zero count (count, first
/// example, action) and one about the components when there are several or some lack a handle.
std::vector<std::string> SummarizeMeshChecks(const MeshCheckReport& checks);

/// What to do with repairable defects before solving (the run config's `[mesh]` table).
struct MeshRepairOptions {
  /// Merge referenced vertices with identical coordinates into one before solving (an unwelded
  /// seam otherwise opens under deformation). Results are still written per input vertex: each
  /// merged vertex gets its representative's position.
  bool weld_duplicates = false;
  /// Solve without repeated copies of an element (a face listed twice would weigh double).
  bool drop_duplicate_elements = true;

  /// Reads `weld_duplicates` and `drop_duplicate_elements` and rejects unknown keys.
  static MeshRepairOptions FromConfig(OptionReader node);
};

/// The problem actually solved: possibly a welded mesh without duplicate elements, with the
/// constraints and start positions carried over, and the map back to the input's vertices.
class PreparedProblem {
 public:
  /// Checks the problem's mesh, fills each finding's `action`, and builds the solved problem.
  /// Throws InputError naming the vertex for non-finite coordinates, and naming both vertices
  /// when welding would merge two constrained vertices with different targets.
  PreparedProblem(const DeformationProblem& problem, const MeshRepairOptions& options);
  // problem() may point into this object: neither copyable nor movable.
  PreparedProblem(const PreparedProblem&) = delete;
  PreparedProblem& operator=(const PreparedProblem&) = delete;

  const MeshCheckReport& checks() const { return checks_; }
  /// The problem to hand to the optimizer (points into this object or the input's mesh).
  const DeformationProblem& problem() const { return problem_; }
  bool changed() const { return changed_; }
  /// Positions per input vertex from positions per solved vertex (identity if nothing changed).
  Positions ToInputVertices(const Positions& solved) const;
  /// Short human-readable lines for the terminal and the report's notes: one per finding with a
  /// non-zero count (count, first example, action).
  std::vector<std::string> Summary() const;
  /// When changed(): the checks of the solved (repaired) mesh with the solved constraints, each
  /// finding carrying the input's action; nullptr otherwise.
  const MeshCheckReport* repaired_checks() const { return changed_ ? &repaired_checks_ : nullptr; }
  /// Summary() of repaired_checks() (empty when nothing changed or nothing is left to report).
  std::vector<std::string> RepairedSummary() const;

 private:
  /// problem_'s constraints in the solved numbering (solved_vertex_ set, `solved_vertices` of
  /// them); throws InputError if two welded vertices have different targets.
  void SetSolvedConstraints(const DeformationProblem& problem, Index solved_vertices);

  MeshCheckReport checks_;
  MeshCheckReport repaired_checks_;
  Mesh repaired_mesh_;
  DeformationProblem problem_;
  std::vector<Index> solved_vertex_;  ///< input vertex → solved vertex (empty: identity)
  bool changed_ = false;
};

}  // namespace harap
