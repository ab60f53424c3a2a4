// SPDX-License-Identifier: MIT
// A scenario's handles from their description: select.* (slab, ball, indices, index_file) →
// vertex sets, rotate/translate/target → targets, target_file and the deformation benchmark's
// .sel/.def files. The TOML side (which keys, which values) is scenario_reading.h; this side
// needs the mesh. Internal to harap::io.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "io/mesh_sourcing.h"
#include "io/scenario.h"

namespace harap::io_internal {

enum class SelectionKind { kSlab, kBall, kIndices, kIndexFile };
enum class TargetKind { kMotion, kInitial, kFile };

/// How the numbers of slab/ball selections, rotate.center and translate are meant.
enum class Units { kFractions, kAbsolute };

/// One [[handle]] as written (positions of its keys kept for messages).
struct HandleSpec {
  std::string name;
  std::string label;         ///< "handle 'feet'" or "handle 2" (for messages)
  std::string select_where;  ///< position of `select`, for selection errors
  SelectionKind kind = SelectionKind::kSlab;
  int axis = 0;  ///< slab
  double from = 0.0, to = 0.0;
  Eigen::Vector3d ball_center = Eigen::Vector3d::Zero();  ///< box fractions
  double radius = 0.0;                                    ///< in box diagonals
  std::vector<int64_t> indices;
  std::vector<std::string> index_where;  ///< per inline index
  std::filesystem::path index_file;
  std::string index_file_where;
  Units units = Units::kFractions;  ///< slab, ball, rotate center, translate

  TargetKind target = TargetKind::kMotion;
  bool has_rotation = false;
  Eigen::Vector3d axis_vector = Eigen::Vector3d::UnitZ();
  double degrees = 0.0;
  std::optional<Eigen::Vector3d> center;  ///< box fractions
  bool has_translation = false;
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  std::filesystem::path target_file;  ///< target_file = "...": per-vertex "index x y z" lines
  std::string target_file_where;
  /// `weight = w`: a soft handle (Constraints::weights); +∞ (the default) pins.
  double weight = std::numeric_limits<double>::infinity();
};

/// One [[stiffness]] as written: a region selected like a handle's vertices (`region.name`,
/// `region.label`, the selection and its units) and its factor.
struct StiffnessSpec {
  HandleSpec region;  ///< the name and label; the selection unless `attribute` is set
  double factor = 1.0;
  /// `attribute = "NAME"`: the factors are the mesh file's PLY vertex or face property NAME.
  std::string attribute;
  std::string attribute_where;
};

/// `selection = "x.sel"` with `deformation = "x.def"`: the deformation benchmark of Botsch &
/// Sorkine's survey (per-vertex labels 0 fixed, 1 free, 2 handle; the handle's 4x4 transform).
struct BenchmarkHandlesSpec {
  std::filesystem::path selection_file;
  std::string selection_where;
  std::filesystem::path deformation_file;
  std::string deformation_where;
};

/// Sets the selection box of `scenario` (its mesh and initial positions known) and appends its
/// handles: the benchmark's ("fixed" if any vertex is labelled 0, then "handle"), then one per
/// spec. Selections that match nothing and indices out of range are ConfigErrors naming the
/// handle and where it is written; problems with the files named are InputErrors.
void AddHandles(const std::optional<BenchmarkHandlesSpec>& benchmark,
                const std::vector<HandleSpec>& specs, Scenario& scenario);

/// Appends the stiffness regions of `specs` to `scenario` (after AddHandles: its selection box
/// is set). Selections that match nothing are ConfigErrors naming the region and where it is
/// written. An `attribute` is read from the file `mesh` names: a ConfigError unless the mesh is a
/// PLY file used as it is (no refine, no tetrahedralize); an InputError naming the file, the
/// element and the index for a missing property or a value that is not a finite number > 0.
void AddStiffness(const std::vector<StiffnessSpec>& specs, const MeshSpec& mesh,
                  Scenario& scenario);

/// "(x, y, z)" with 6 significant digits.
std::string Vec(const Eigen::Vector3d& v);

}  // namespace harap::io_internal
