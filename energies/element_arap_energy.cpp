// SPDX-License-Identifier: MIT
#include "energies/element_arap_energy.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <type_traits>

#include "energies/kernels/cotangent_weights.h"
#include "energies/kernels/mesh_adjacency.h"
#include "framework/error.h"

namespace harap {

namespace {

constexpr Index kGrain = 4096;

/// Column of the weight of corner pair (a, b), a ≠ b, in the kernels' weight matrices: for
/// triangles the column of the opposite corner (HalfCotangents), for tetrahedra the position in
/// kTetrahedronEdges.
template <int K>
constexpr int PairColumn(int a, int b) {
  if constexpr (K == 3) {
    return 3 - a - b;
  } else {
    const int lo = a < b ? a : b, hi = a < b ? b : a;
    return lo == 0 ? hi - 1 : lo + hi;  // (0,1)→0 (0,2)→1 (0,3)→2 (1,2)→3 (1,3)→4 (2,3)→5
  }
}

/// D = [x_1 − x_0, …, x_{K−1} − x_0] of the element with corners `c`, (K−1)×(K−1): 3×3 for
/// tetrahedra, the xy block 2×2 for (planar) triangles.
template <int K>
Eigen::Matrix<double, K - 1, K - 1> EdgeMatrix(const Positions& x, const Index* c) {
  Eigen::Matrix<double, K - 1, K - 1> d;
  for (int a = 1; a < K; ++a) {
    for (int i = 0; i < K - 1; ++i) d(i, a - 1) = x(c[a], i) - x(c[0], i);
  }
  return d;
}

void RequireSupportedMesh(const Mesh& mesh) {
  if (mesh.kind() == ElementKind::kTetrahedron) {
    if (mesh.planar) {
      throw InputError(
          fmt::format("energy '{}': the mesh is marked planar but has tetrahedra; "
                      "planar meshes have triangles",
                      ElementArapEnergy::kName));
    }
    return;
  }
  if (mesh.simplex_size() != 3) {
    throw InputError(
        fmt::format("energy '{}' needs tetrahedra or planar triangles, but the mesh "
                    "has {} vertices per element",
                    ElementArapEnergy::kName, mesh.simplex_size()));
  }
  if (!mesh.planar) {
    throw InputError(fmt::format(
        "energy '{}' works on tetrahedral meshes and on planar triangle meshes (2D, z = 0, "
        "rotations in the plane), but this is a surface triangle mesh; use 'spokes_and_rims' or "
        "'spokes' for surfaces",
        ElementArapEnergy::kName));
  }
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    if (mesh.vertices(v, 2) != 0.0) {
      throw InputError(fmt::format("energy '{}': the mesh is planar but vertex {} has z = {}",
                                   ElementArapEnergy::kName, v, mesh.vertices(v, 2)));
    }
  }
}

}  // namespace

void ElementArapEnergy::PrecomputeCoupledForm(const Mesh& rest, const Context& context) {
  RequireSupportedMesh(rest);
  context.Run([&] {
    Eigen::MatrixXd weights =
        rest.kind() == ElementKind::kTetrahedron
            ? Eigen::MatrixXd(
                  TetrahedronCotangentWeights(rest.vertices, rest.elements, &num_degenerate_))
            : Eigen::MatrixXd(HalfCotangents(rest.vertices, rest.elements, &num_degenerate_));
    // Stiffness multiplies every weight of its element (and so E_t = s_t |t| ‖F_t − R_t‖²).
    for (size_t t = 0; t < stiffness_.size(); ++t)
      weights.row(static_cast<Index>(t)) *= stiffness_[t];
    if (rest.kind() == ElementKind::kTetrahedron) {
      Assemble<4>(rest, weights);
    } else {
      Assemble<3>(rest, weights);
    }
  });
}

template <int K>
void ElementArapEnergy::Assemble(const Mesh& rest, const Eigen::MatrixXd& weights) {
  const Elements& elements = rest.elements;
  const Index num_elements = rest.num_elements();
  const Positions& v = rest.vertices;
  auto rest_edge = [&](Index t, int a, int b) {
    return Eigen::Vector3d((v.row(elements(t, a)) - v.row(elements(t, b))).transpose());
  };

  // Expanding w‖(u_j − u_k) − R_t ē_jk‖² over the edges of t: the cross term is
  // −2⟨R_t, Σ_j u_j c_tjᵀ⟩ with c_tj = Σ_k w_jk ē_jk (the element Laplacian applied to the rest
  // positions, written with differences to keep far-from-origin meshes exact), the constant
  // Σ w‖ē‖² (‖R ē‖ = ‖ē‖).
  std::vector<Eigen::Vector3d> coefficient(std::size_t(num_elements) * K);
  const double constant = tbb::parallel_deterministic_reduce(
      tbb::blocked_range<Index>(0, num_elements, kGrain), 0.0,
      [&](const tbb::blocked_range<Index>& range, double sum) {
        for (Index t = range.begin(); t != range.end(); ++t) {
          for (int a = 0; a < K; ++a) {
            Eigen::Vector3d c = Eigen::Vector3d::Zero();
            for (int b = 0; b < K; ++b) {
              if (b == a) continue;
              const double w = weights(t, PairColumn<K>(a, b));
              const Eigen::Vector3d e = rest_edge(t, a, b);
              c += w * e;
              if (b > a) sum += w * e.squaredNorm();
            }
            coefficient[std::size_t(t) * K + a] = c;
          }
        }
        return sum;
      },
      std::plus<double>());
  // Rest volumes (areas) for AuxiliaryMeasures(); zero for the degenerate (zero-weight) ones.
  rest_vertices_ = v;
  measure_.resize(num_elements);
  tbb::parallel_for(tbb::blocked_range<Index>(0, num_elements, kGrain),
                    [&](const tbb::blocked_range<Index>& range) {
                      for (Index t = range.begin(); t != range.end(); ++t) {
                        const double volume =
                            std::abs(EdgeMatrix<K>(v, &elements(t, 0)).determinant()) /
                            (K == 4 ? 6.0 : 2.0);
                        const double factor = stiffness_.empty() ? 1.0 : stiffness_[t];
                        measure_[t] = weights.row(t).isZero(0.0) ? 0.0 : factor * volume;
                      }
                    });
  coupling_ = MakeElementSiteCoupling(rest.num_vertices(), elements, std::move(coefficient),
                                      constant, rest.planar);

  // A = Σ_t L_t (L_t,jk = −w_jk, L_t,jj = Σ_k w_jk), assembled by column in parallel: column j
  // gathers the elements around j (the coupling's by-vertex lists), so no two tasks write the
  // same entry.
  a_ = AdjacencyPattern(rest.num_vertices(), elements);
  double* values = a_.valuePtr();
  tbb::parallel_for(tbb::blocked_range<Index>(0, rest.num_vertices(), 1024),
                    [&](const tbb::blocked_range<Index>& range) {
                      for (Index j = range.begin(); j != range.end(); ++j) {
                        const Index diagonal = EntryPosition(a_, j, j);
                        for (Index p = coupling_.vertex_offsets[j];
                             p < coupling_.vertex_offsets[j + 1]; ++p) {
                          const Index t = coupling_.vertex_sites[p];
                          int a = 0;
                          while (elements(t, a) != j) ++a;
                          for (int b = 0; b < K; ++b) {
                            if (b == a) continue;
                            const double w = weights(t, PairColumn<K>(a, b));
                            values[diagonal] += w;
                            values[EntryPosition(a_, elements(t, b), j)] -= w;
                          }
                        }
                      }
                    });
}

std::map<std::string, double> ElementArapEnergy::AuxiliaryMeasures(const Positions& u,
                                                                   const Rotations& rotations,
                                                                   const Context& context) const {
  HARAP_CHECK(u.rows() == rest_vertices_.rows(), "{} positions for {} vertices", u.rows(),
              rest_vertices_.rows());
  HARAP_CHECK(static_cast<Index>(rotations.size()) == num_rotations(), "{} rotations for {} sites",
              rotations.size(), num_rotations());
  // Σ_t ½ |t| ‖F_t − R_t‖²_F with F_t = D_t(u) D_t(v̄)⁻¹; equal to E / 2 (the class comment).
  const Index num_elements = static_cast<Index>(measure_.size());
  const int size = num_elements > 0 ? coupling_.site_offsets[1] : 0;
  const Index* corners = coupling_.site_vertices.data();  // the elements, row by row
  auto sum = [&](auto k) {
    constexpr int K = decltype(k)::value;
    return tbb::parallel_deterministic_reduce(
        tbb::blocked_range<Index>(0, num_elements, kGrain), 0.0,
        [&](const tbb::blocked_range<Index>& range, double total) {
          for (Index t = range.begin(); t != range.end(); ++t) {
            if (measure_[t] == 0.0) continue;
            const Index* c = corners + std::size_t(t) * K;
            const auto f =
                (EdgeMatrix<K>(u, c) * EdgeMatrix<K>(rest_vertices_, c).inverse()).eval();
            const auto r = rotations[t].topLeftCorner<K - 1, K - 1>();
            total += 0.5 * measure_[t] * (f - r).squaredNorm();
          }
          return total;
        },
        std::plus<double>());
  };
  const double wrapd = context.Run([&] {
    return size == 4 ? sum(std::integral_constant<int, 4>())
                     : sum(std::integral_constant<int, 3>());
  });
  return {{"energy_wrapd", wrapd}};
}

}  // namespace harap
