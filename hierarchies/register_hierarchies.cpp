// SPDX-License-Identifier: MIT
#include "hierarchies/register_hierarchies.h"

#include "hierarchies/octree_hierarchy.h"

namespace harap {

void RegisterHierarchies(Registry<Hierarchy>& registry) {
  registry.Add(std::string(OctreeHierarchy::kName),
               "vertex clustering on nested regular grids with the topology check, elements "
               "kept while their vertices lie in different clusters [Meyer et al. 2025, Sec. 4]",
               &OctreeHierarchy::Create);
}

}  // namespace harap
