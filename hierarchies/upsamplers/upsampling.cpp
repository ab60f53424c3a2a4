// SPDX-License-Identifier: MIT
#include "hierarchies/upsamplers/upsampling.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

#include "framework/error.h"
#include "framework/mesh_topology.h"
#include "framework/rotation.h"

namespace harap {

bool PlanarRotations(const Mesh& mesh, RotationSite site) {
  return mesh.planar && site == RotationSite::kElement;
}

Rotations VertexRotations(const Mesh& mesh, RotationSite site, const Rotations& rotations,
                          const Context& context) {
  if (site == RotationSite::kVertex) {
    HARAP_CHECK(static_cast<Index>(rotations.size()) == mesh.num_vertices(),
                "{} rotations for {} vertices", rotations.size(), mesh.num_vertices());
    return rotations;
  }
  HARAP_CHECK(static_cast<Index>(rotations.size()) == mesh.num_elements(),
              "{} rotations for {} elements", rotations.size(), mesh.num_elements());
  const VertexIncidence incidence = VertexIncidence::Build(mesh.num_vertices(), mesh.elements);
  const std::vector<Index>& offsets = incidence.offsets;
  const bool planar = PlanarRotations(mesh, site);
  Rotations result(mesh.num_vertices(), Rotation::Identity());
  context.Run([&] {
    tbb::parallel_for(tbb::blocked_range<Index>(0, mesh.num_vertices(), 2048),
                      [&](const tbb::blocked_range<Index>& range) {
                        for (Index v = range.begin(); v != range.end(); ++v) {
                          const Index first = offsets[v];
                          result[v] = MeanElementRotation(
                              rotations, offsets[v + 1] - first,
                              [&](Index i) { return incidence.element(first + i); }, planar);
                        }
                      });
  });
  return result;
}

Rotations SiteRotations(const Mesh& mesh, RotationSite site, const Rotations& vertex_rotations,
                        const Context& context) {
  if (site == RotationSite::kVertex) return vertex_rotations;
  const bool planar = PlanarRotations(mesh, site);
  Rotations result(mesh.num_elements());
  context.Run([&] {
    tbb::parallel_for(tbb::blocked_range<Index>(0, mesh.num_elements(), 2048),
                      [&](const tbb::blocked_range<Index>& range) {
                        for (Index e = range.begin(); e != range.end(); ++e) {
                          Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
                          for (int a = 0; a < mesh.simplex_size(); ++a) {
                            sum += vertex_rotations[mesh.elements(e, a)];
                          }
                          result[e] = NearestRotation(sum, planar);
                        }
                      });
  });
  return result;
}

Rotations ProlongRotations(const HierarchyLevel& fine, const Rotations& coarse_vertex_rotations) {
  const Index n = fine.mesh.num_vertices();
  HARAP_CHECK(static_cast<Index>(fine.coarse_vertex.size()) == n,
              "fine level has {} vertices but a map of {}", n, fine.coarse_vertex.size());
  Rotations result(n, Rotation::Identity());
  for (Index j = 0; j < n; ++j) {
    const Index i = fine.coarse_vertex[j];
    if (i != kNoVertex) result[j] = coarse_vertex_rotations[i];
  }
  return result;
}

Positions ProlongPositions(const HierarchyLevel& fine, const HierarchyLevel& coarse,
                           const Positions& coarse_positions,
                           const Rotations& coarse_vertex_rotations) {
  const Index n = fine.mesh.num_vertices();
  HARAP_CHECK(static_cast<Index>(fine.coarse_vertex.size()) == n,
              "fine level has {} vertices but a map of {}", n, fine.coarse_vertex.size());
  Positions result = fine.mesh.vertices;
  for (Index j = 0; j < n; ++j) {
    const Index i = fine.coarse_vertex[j];
    if (i == kNoVertex) continue;
    const Eigen::Vector3d offset =
        (fine.mesh.vertices.row(j) - coarse.mesh.vertices.row(i)).transpose();
    result.row(j) = coarse_positions.row(i) + (coarse_vertex_rotations[i] * offset).transpose();
  }
  return result;
}

void SmoothVertexRotations(const Mesh& mesh, RotationSite site, int passes,
                           Rotations& vertex_rotations, const Context& context) {
  const bool planar = PlanarRotations(mesh, site);
  // The 1-ring (sorted, distinct): the sums below add the neighbours in ascending order.
  const Index n = mesh.num_vertices();
  const VertexAdjacency ring =
      context.Run([&] { return VertexAdjacency::Build(n, mesh.elements, /*include_self=*/false); });
  Rotations next(n);
  for (int pass = 0; pass < passes; ++pass) {
    context.Run([&] {
      tbb::parallel_for(
          tbb::blocked_range<Index>(0, n, 2048), [&](const tbb::blocked_range<Index>& range) {
            for (Index v = range.begin(); v != range.end(); ++v) {
              Eigen::Matrix3d sum = vertex_rotations[v];
              const Index begin = ring.offsets[v], end = ring.offsets[v + 1];
              for (Index p = begin; p < end; ++p) {
                sum += vertex_rotations[ring.neighbors[p]];
              }
              next[v] = begin == end ? vertex_rotations[v] : NearestRotation(sum, planar);
            }
          });
    });
    std::swap(next, vertex_rotations);
  }
}

}  // namespace harap

namespace harap {

void UpsampleCells(const HierarchyLevel& fine, const HierarchyLevel& coarse, RotationSite site,
                   const LevelState& coarse_state, int smoothing_passes, LevelState& fine_state,
                   const Context& context) {
  const Rotations coarse_vertex_rotations =
      VertexRotations(coarse.mesh, site, coarse_state.rotations, context);
  fine_state.positions =
      ProlongPositions(fine, coarse, coarse_state.positions, coarse_vertex_rotations);
  Rotations fine_vertex_rotations = ProlongRotations(fine, coarse_vertex_rotations);
  if (smoothing_passes > 0) {
    SmoothVertexRotations(fine.mesh, site, smoothing_passes, fine_vertex_rotations, context);
  }
  fine_state.rotations = SiteRotations(fine.mesh, site, fine_vertex_rotations, context);
}

}  // namespace harap
