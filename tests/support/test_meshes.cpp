// SPDX-License-Identifier: MIT
#include "tests/support/test_meshes.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numeric>
#include <random>
#include <vector>

namespace harap::testing {

Mesh Grid(int nx, int ny) {
  Mesh mesh;
  mesh.vertices.resize(nx * ny, 3);
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      mesh.vertices.row(j * nx + i) << double(i) / (nx - 1), double(j) / (ny - 1), 0.0;
    }
  }
  mesh.elements.resize(2 * (nx - 1) * (ny - 1), 3);
  int f = 0;
  for (int j = 0; j + 1 < ny; ++j) {
    for (int i = 0; i + 1 < nx; ++i) {
      const int a = j * nx + i, b = a + 1, c = a + nx, d = c + 1;
      mesh.elements.row(f++) << a, b, d;
      mesh.elements.row(f++) << a, d, c;
    }
  }
  return mesh;
}

Mesh PlanarGrid(int nx, int ny) {
  Mesh mesh = Grid(nx, ny);
  mesh.planar = true;
  return mesh;
}

Mesh TetBox(int nx, int ny, int nz, int tets_per_cube) {
  Mesh mesh;
  mesh.vertices.resize(nx * ny * nz, 3);
  auto id = [&](int i, int j, int k) { return (k * ny + j) * nx + i; };
  for (int k = 0; k < nz; ++k) {
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        mesh.vertices.row(id(i, j, k)) << double(i) / (nx - 1), double(j) / (ny - 1),
            double(k) / (nz - 1);
      }
    }
  }
  std::vector<std::array<int, 4>> tets;
  for (int k = 0; k + 1 < nz; ++k) {
    for (int j = 0; j + 1 < ny; ++j) {
      for (int i = 0; i + 1 < nx; ++i) {
        // Corner (a, b, c) ∈ {0,1}³ of the cube at (i, j, k).
        auto corner = [&](int a, int b, int c) { return id(i + a, j + b, k + c); };
        if (tets_per_cube == 6) {
          // Paths from corner 000 to 111 along the axes in each of the 6 orders.
          const std::array<std::array<int, 3>, 6> orders = {
              {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
          for (const auto& order : orders) {
            std::array<int, 3> c = {0, 0, 0};
            std::array<int, 4> tet;
            tet[0] = corner(0, 0, 0);
            for (int s = 0; s < 3; ++s) {
              ++c[order[s]];
              tet[s + 1] = corner(c[0], c[1], c[2]);
            }
            tets.push_back(tet);
          }
        } else {
          // The middle tetrahedron joins the corners of even global parity, so neighbouring
          // cubes split their shared face along the same diagonal; each odd corner cuts off a
          // corner tetrahedron with its three (even) neighbours.
          const int parity = (i + j + k) % 2;
          std::array<int, 4> middle;
          int m = 0;
          for (int a = 0; a < 2; ++a) {
            for (int b = 0; b < 2; ++b) {
              for (int c = 0; c < 2; ++c) {
                if ((parity + a + b + c) % 2 == 0) {
                  middle[m++] = corner(a, b, c);
                } else {
                  tets.push_back({corner(a, b, c), corner(1 - a, b, c), corner(a, 1 - b, c),
                                  corner(a, b, 1 - c)});
                }
              }
            }
          }
          tets.push_back(middle);
        }
      }
    }
  }
  mesh.elements.resize(tets.size(), 4);
  for (size_t t = 0; t < tets.size(); ++t) {
    auto& tet = tets[t];
    const Eigen::Vector3d p0 = mesh.vertices.row(tet[0]);
    const Eigen::Matrix3d d =
        (Eigen::Matrix3d() << mesh.vertices.row(tet[1]) - p0.transpose(),
         mesh.vertices.row(tet[2]) - p0.transpose(), mesh.vertices.row(tet[3]) - p0.transpose())
            .finished();
    if (d.determinant() < 0) std::swap(tet[2], tet[3]);
    for (int a = 0; a < 4; ++a) mesh.elements(t, a) = tet[a];
  }
  return mesh;
}

Mesh Jittered(Mesh mesh, int n, double amount, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> offset(-1.0, 1.0);
  const double step = amount / (n - 1);
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    for (int d = 0; d < (mesh.planar ? 2 : 3); ++d) mesh.vertices(v, d) += step * offset(rng);
  }
  return mesh;
}

Mesh Shuffled(Mesh mesh, unsigned seed, std::vector<Index>* moved_to) {
  std::vector<Index> to(mesh.num_vertices());
  std::iota(to.begin(), to.end(), Index{0});
  std::shuffle(to.begin(), to.end(), std::mt19937(seed));
  Positions shuffled(mesh.num_vertices(), 3);
  for (Index v = 0; v < mesh.num_vertices(); ++v) shuffled.row(to[v]) = mesh.vertices.row(v);
  mesh.vertices = shuffled;
  for (Index e = 0; e < mesh.num_elements(); ++e) {
    for (int a = 0; a < mesh.simplex_size(); ++a) mesh.elements(e, a) = to[mesh.elements(e, a)];
  }
  if (moved_to != nullptr) *moved_to = std::move(to);
  return mesh;
}

BentTube::BentTube(int rings, int segments, double height, double angle,
                   const Eigen::Vector3d& shift)
    : mesh(Tube(rings, segments)) {
  mesh.vertices.col(2) *= height;
  problem.mesh = &mesh;
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitX()).toRotationMatrix();
  for (int s = 0; s < segments; ++s) problem.constraints.indices.push_back(s);
  for (int s = 0; s < segments; ++s) {
    problem.constraints.indices.push_back((rings - 1) * segments + s);
  }
  problem.constraints.targets.resize(problem.constraints.indices.size(), 3);
  for (size_t k = 0; k < problem.constraints.indices.size(); ++k) {
    Eigen::Vector3d p = mesh.vertices.row(problem.constraints.indices[k]);
    if (k >= static_cast<size_t>(segments)) p = turn * p + shift;
    problem.constraints.targets.row(k) = p.transpose();
  }
}

Constraints WithSoftGroups(const BentTube& tube, int segments, int groups, unsigned seed) {
  const Mesh& mesh = tube.mesh;
  Constraints c = tube.problem.constraints;
  c.weights.assign(c.indices.size(), Constraints::kHardWeight);
  std::mt19937 random(seed);
  std::vector<unsigned char> used(mesh.num_vertices(), 0);
  for (Index v : c.indices) used[v] = 1;
  std::vector<Eigen::RowVector3d> targets;
  for (Index k = 0; k < c.targets.rows(); ++k) targets.push_back(c.targets.row(k));
  for (int group = 0; group < groups;) {
    const Index first =
        segments + static_cast<Index>(random() % (mesh.num_vertices() - 3 * segments));
    if (used[first] || used[first + 1] || used[first + 2]) continue;
    Eigen::RowVector3d out = mesh.vertices.row(first);
    out.z() = 0.0;
    for (Index v = first; v < first + 3; ++v) {
      used[v] = 1;
      c.indices.push_back(v);
      targets.push_back(mesh.vertices.row(v) + 0.05 * out);
      c.weights.push_back(0.5 + (group % 5));
    }
    ++group;
  }
  c.targets.resize(static_cast<Index>(targets.size()), 3);
  for (size_t k = 0; k < targets.size(); ++k) c.targets.row(static_cast<Index>(k)) = targets[k];
  return c;
}

namespace {

/// Fixes the vertices `select` picks, at `target(rest position)`.
template <class Select, class Target>
void FixVertices(const Mesh& mesh, Select&& select, Target&& target, Constraints& constraints) {
  std::vector<Eigen::RowVector3d> targets;
  for (Index v = 0; v < mesh.num_vertices(); ++v) {
    const Eigen::Vector3d p = mesh.vertices.row(v).transpose();
    if (!select(p)) continue;
    constraints.indices.push_back(v);
    targets.push_back(target(p).transpose());
  }
  constraints.targets.resize(static_cast<Index>(targets.size()), 3);
  for (size_t k = 0; k < targets.size(); ++k) constraints.targets.row(k) = targets[k];
}

}  // namespace

TwistedTetBar::TwistedTetBar(int nx, int ny, int nz, double height, double angle)
    : mesh(TetBox(nx, ny, nz)) {
  mesh.vertices.col(2) *= height;
  problem.mesh = &mesh;
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3d axis(0.5, 0.5, 0.0);
  FixVertices(
      mesh, [&](const Eigen::Vector3d& p) { return p.z() == 0.0 || p.z() == height; },
      [&](const Eigen::Vector3d& p) -> Eigen::Vector3d {
        return p.z() == 0.0 ? p : Eigen::Vector3d(turn * (p - axis) + axis);
      },
      problem.constraints);
}

ShearedPlanarGrid::ShearedPlanarGrid(int nx, int ny, const Eigen::Vector2d& shift)
    : mesh(PlanarGrid(nx, ny)) {
  problem.mesh = &mesh;
  FixVertices(
      mesh, [](const Eigen::Vector3d& p) { return p.x() == 0.0 || p.x() == 1.0; },
      [&](const Eigen::Vector3d& p) -> Eigen::Vector3d {
        return p.x() == 0.0 ? p : Eigen::Vector3d(p + Eigen::Vector3d(shift.x(), shift.y(), 0.0));
      },
      problem.constraints);
}

Mesh SeamedGrid(int n, std::vector<std::pair<Index, Index>>& seam) {
  Mesh mesh = Grid(n, n);
  const Index original_count = mesh.num_vertices();
  std::vector<Index> copy(original_count, kNoVertex);
  std::vector<Index> seam_vertices;
  for (Index v = 0; v < original_count; ++v) {
    if (mesh.vertices(v, 0) == 0.5) {
      copy[v] = original_count + static_cast<Index>(seam_vertices.size());
      seam_vertices.push_back(v);
      seam.emplace_back(copy[v], v);
    }
  }
  mesh.vertices.conservativeResize(original_count + static_cast<Index>(seam_vertices.size()), 3);
  for (size_t k = 0; k < seam_vertices.size(); ++k) {
    mesh.vertices.row(original_count + static_cast<Index>(k)) =
        mesh.vertices.row(seam_vertices[k]).eval();
  }
  for (Index f = 0; f < mesh.num_elements(); ++f) {
    double centroid_x = 0.0;
    for (int a = 0; a < 3; ++a) centroid_x += mesh.vertices(mesh.elements(f, a), 0) / 3.0;
    if (centroid_x < 0.5) continue;
    for (int a = 0; a < 3; ++a) {
      const Index v = mesh.elements(f, a);
      if (copy[v] != kNoVertex) mesh.elements(f, a) = copy[v];
    }
  }
  return mesh;
}

Mesh Icosphere(int subdivisions) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                                    {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                                    {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<Eigen::Vector3i> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                    {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                    {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                    {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& p : v) p.normalize();
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<int, int>, int> midpoint;
    auto mid = [&](int a, int b) {
      auto key = std::minmax(a, b);
      auto it = midpoint.find(key);
      if (it != midpoint.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      return midpoint[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<Eigen::Vector3i> next;
    for (const auto& tri : f) {
      const int ab = mid(tri[0], tri[1]), bc = mid(tri[1], tri[2]), ca = mid(tri[2], tri[0]);
      next.push_back({tri[0], ab, ca});
      next.push_back({tri[1], bc, ab});
      next.push_back({tri[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    f = next;
  }
  Mesh mesh;
  mesh.vertices.resize(v.size(), 3);
  for (size_t i = 0; i < v.size(); ++i) mesh.vertices.row(i) = v[i].transpose();
  mesh.elements.resize(f.size(), 3);
  for (size_t i = 0; i < f.size(); ++i) mesh.elements.row(i) = f[i].transpose();
  return mesh;
}

Mesh Tube(int rings, int segments) {
  Mesh mesh;
  mesh.vertices.resize(rings * segments, 3);
  for (int r = 0; r < rings; ++r) {
    for (int s = 0; s < segments; ++s) {
      // Alternate rings are offset by half a segment for well-shaped triangles.
      const double angle = 2.0 * M_PI * (s + 0.5 * (r % 2)) / segments;
      mesh.vertices.row(r * segments + s) << 0.25 * std::cos(angle), 0.25 * std::sin(angle),
          double(r) / (rings - 1);
    }
  }
  mesh.elements.resize(2 * (rings - 1) * segments, 3);
  int f = 0;
  for (int r = 0; r + 1 < rings; ++r) {
    for (int s = 0; s < segments; ++s) {
      const int a = r * segments + s, b = r * segments + (s + 1) % segments;
      const int c = (r + 1) * segments + s, d = (r + 1) * segments + (s + 1) % segments;
      if (r % 2 == 0) {
        mesh.elements.row(f++) << a, b, c;
        mesh.elements.row(f++) << b, d, c;
      } else {
        mesh.elements.row(f++) << a, d, c;
        mesh.elements.row(f++) << a, b, d;
      }
    }
  }
  return mesh;
}

Mesh Concatenate(const Mesh& a, const Mesh& b) {
  Mesh mesh;
  mesh.vertices.resize(a.num_vertices() + b.num_vertices(), 3);
  mesh.vertices << a.vertices, b.vertices;
  mesh.elements.resize(a.num_elements() + b.num_elements(), a.simplex_size());
  mesh.elements.topRows(a.num_elements()) = a.elements;
  mesh.elements.bottomRows(b.num_elements()) = b.elements.array() + a.num_vertices();
  return mesh;
}

Eigen::Matrix3d RandomRotation(unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  Eigen::Quaterniond q(normal(rng), normal(rng), normal(rng), normal(rng));
  return q.normalized().toRotationMatrix();
}

Positions SmoothlyDeformed(const Positions& rest, double amount) {
  Positions u = rest;
  for (Eigen::Index i = 0; i < rest.rows(); ++i) {
    const double x = rest(i, 0), y = rest(i, 1), z = rest(i, 2);
    const double angle = amount * (z + 0.5 * x);
    u(i, 0) = std::cos(angle) * x - std::sin(angle) * y + 0.3 * amount * z * z;
    u(i, 1) = std::sin(angle) * x + std::cos(angle) * y + 0.2 * amount * x * y;
    u(i, 2) = z * (1.0 + 0.1 * amount * x) + 0.15 * amount * y * y;
  }
  return u;
}

}  // namespace harap::testing
