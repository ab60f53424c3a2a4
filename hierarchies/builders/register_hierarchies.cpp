// SPDX-License-Identifier: MIT
#include "hierarchies/builders/register_hierarchies.h"

#include "hierarchies/builders/edge_collapse_hierarchy.h"
#include "hierarchies/builders/octree_hierarchy.h"

namespace harap {

void RegisterHierarchies(Registry<Hierarchy>& registry) {
  registry.Add<OctreeHierarchy>(
      "vertex clustering on nested regular grids with the topology check, elements "
      "kept while their vertices lie in different clusters [Meyer et al. 2025, Sec. 4]");
  registry.Add<EdgeCollapseHierarchy>(
      "manifold-preserving levels by quadric-error edge collapse (OpenMesh's decimater), "
      "by default with the octree's level vertex counts; the alternative of the "
      "paper's Fig. 18");
}

}  // namespace harap
