// SPDX-License-Identifier: MIT
#include "energies/kernels/rotation_coupling.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <Eigen/Eigenvalues>

#include "energies/kernels/mesh_adjacency.h"
#include "energies/kernels/polar_decomposition.h"
#include "framework/error.h"
#include "framework/mesh_topology.h"

namespace harap {

namespace {

constexpr Index kGrain = 2048;

// body(i) for every i in [0, count), in tasks of kGrain items on the context's threads.
template <class Body>
void ForEachIndex(Index count, const Context& context, Body&& body) {
  context.Run([&] {
    tbb::parallel_for(tbb::blocked_range<Index>(0, count, kGrain),
                      [&](const tbb::blocked_range<Index>& range) {
                        for (Index i = range.begin(); i != range.end(); ++i) body(i);
                      });
  });
}

// M_s(u) = Σ_j u_j c_sjᵀ  (deformed × rest), c_sj = coefficients[p] (site-major).
inline Eigen::Matrix3d Covariance(const RotationCoupling& coupling,
                                  const std::vector<Eigen::Vector3d>& coefficients,
                                  const Positions& u, Index s) {
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  for (Index p = coupling.site_offsets[s]; p < coupling.site_offsets[s + 1]; ++p) {
    const Index j = coupling.site_vertices[p];
    const Eigen::Vector3d uj(u(j, 0), u(j, 1), u(j, 2));
    m.noalias() += uj * coefficients[p].transpose();
  }
  return m;
}

inline Eigen::Matrix3d Covariance(const RotationCoupling& coupling, const Positions& u, Index s) {
  return Covariance(coupling, coupling.site_coefficients, u, s);
}

// tr(uᵀ A u), A symmetric in full storage.
double QuadraticTerm(const SparseMatrix& a, const Positions& u) {
  return tbb::parallel_deterministic_reduce(
      tbb::blocked_range<Index>(0, static_cast<Index>(a.outerSize()), kGrain), 0.0,
      [&](const tbb::blocked_range<Index>& range, double sum) {
        const Index* outer = a.outerIndexPtr();
        const Index* inner = a.innerIndexPtr();
        const double* value = a.valuePtr();
        for (Index col = range.begin(); col != range.end(); ++col) {
          Eigen::RowVector3d au = Eigen::RowVector3d::Zero();
          for (Index p = outer[col]; p < outer[col + 1]; ++p) au += value[p] * u.row(inner[p]);
          sum += au.dot(u.row(col));
        }
        return sum;
      },
      std::plus<double>());
}

}  // namespace

RotationCoupling MakeVertexSiteCoupling(const SparseMatrix& pattern,
                                        std::vector<Eigen::Vector3d> coefficient_by_entry,
                                        double constant) {
  HARAP_CHECK(static_cast<Index>(coefficient_by_entry.size()) == pattern.nonZeros(),
              "{} coefficients for {} pattern entries", coefficient_by_entry.size(),
              pattern.nonZeros());
  RotationCoupling coupling;
  const Index n = static_cast<Index>(pattern.outerSize());
  coupling.num_sites = n;
  coupling.num_vertices = n;
  coupling.constant = constant;
  coupling.site_offsets.assign(pattern.outerIndexPtr(), pattern.outerIndexPtr() + n + 1);
  coupling.site_vertices.assign(pattern.innerIndexPtr(),
                                pattern.innerIndexPtr() + pattern.nonZeros());
  // The pattern is symmetric: column j also lists the sites s coupled to vertex j, and the
  // coefficient c_sj sits at the mirror entry (row j, column s).
  coupling.vertex_offsets = coupling.site_offsets;
  coupling.vertex_sites = coupling.site_vertices;
  const std::vector<Index> mirror = TransposePositions(pattern);
  coupling.vertex_coefficients.resize(coefficient_by_entry.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, mirror.size(), 16 * kGrain),
                    [&](const tbb::blocked_range<size_t>& range) {
                      for (size_t p = range.begin(); p != range.end(); ++p) {
                        coupling.vertex_coefficients[p] = coefficient_by_entry[mirror[p]];
                      }
                    });
  coupling.site_coefficients = std::move(coefficient_by_entry);
  coupling.layout_outer = pattern.outerIndexPtr();
  coupling.layout_inner = pattern.innerIndexPtr();
  return coupling;
}

RotationCoupling MakeElementSiteCoupling(Index num_vertices, const Elements& elements,
                                         std::vector<Eigen::Vector3d> coefficient_by_corner,
                                         double constant, bool planar) {
  const Index num_elements = static_cast<Index>(elements.rows());
  const int size = static_cast<int>(elements.cols());
  HARAP_CHECK(static_cast<Index>(coefficient_by_corner.size()) == num_elements * size,
              "{} coefficients for {} elements of {} corners", coefficient_by_corner.size(),
              num_elements, size);
  RotationCoupling coupling;
  coupling.num_sites = num_elements;
  coupling.num_vertices = num_vertices;
  coupling.planar = planar;
  coupling.constant = constant;
  coupling.site_offsets.resize(num_elements + 1);
  for (Index t = 0; t <= num_elements; ++t) coupling.site_offsets[t] = t * size;
  coupling.site_vertices.assign(elements.data(), elements.data() + elements.size());
  // By vertex: the corners in element order within each vertex (the mesh's incidence).
  VertexIncidence incidence = VertexIncidence::Build(num_vertices, elements);
  coupling.vertex_sites.resize(incidence.corners.size());
  coupling.vertex_coefficients.resize(incidence.corners.size());
  for (size_t p = 0; p < incidence.corners.size(); ++p) {
    coupling.vertex_sites[p] = incidence.element(static_cast<Index>(p));
    coupling.vertex_coefficients[p] = coefficient_by_corner[incidence.corners[p]];
  }
  coupling.vertex_offsets = std::move(incidence.offsets);
  coupling.site_coefficients = std::move(coefficient_by_corner);
  return coupling;
}

double FitCoupledRotations(const RotationCoupling& coupling, const SparseMatrix& a,
                           const Positions& u, Rotations& rotations, const Context& context,
                           const std::vector<Eigen::Vector3d>* fit_coefficients) {
  HARAP_CHECK(static_cast<Index>(rotations.size()) == coupling.num_sites,
              "{} rotations for {} sites", rotations.size(), coupling.num_sites);
  HARAP_CHECK(u.rows() == coupling.num_vertices, "{} positions for {} vertices", u.rows(),
              coupling.num_vertices);
  HARAP_CHECK(!fit_coefficients || fit_coefficients->size() == coupling.site_coefficients.size(),
              "{} fit coefficients for {} coupling entries", fit_coefficients->size(),
              coupling.site_coefficients.size());
  // Fits site s's rotation (to M_s(u), or to the covariance of `fit_coefficients` when given)
  // and returns tr(R_sᵀ M_s).
  const auto fit = [&](Index s, const Eigen::Matrix3d& m) {
    const auto closest = [&](const Eigen::Matrix3d& target) {
      rotations[s] =
          coupling.planar ? ClosestPlanarRotation(target) : ClosestRotation(target, rotations[s]);
    };
    if (fit_coefficients) {
      closest(Covariance(coupling, *fit_coefficients, u, s));
    } else {
      closest(m);
    }
    return rotations[s].cwiseProduct(m).sum();
  };
  return context.Run([&] {
    if (a.outerIndexPtr() == coupling.layout_outer && a.innerIndexPtr() == coupling.layout_inner &&
        a.isCompressed() && a.outerSize() == coupling.num_sites &&
        a.nonZeros() == static_cast<Eigen::Index>(coupling.site_vertices.size())) {
      // One pass: M_s(u) and (A u)_s read the same entries, so tr(UᵀAU) = Σ_s u_s·(A u)_s comes
      // almost for free (the local step is memory-bound).
      const double* value = a.valuePtr();
      const double energy_without_constant = tbb::parallel_deterministic_reduce(
          tbb::blocked_range<Index>(0, coupling.num_sites, kGrain), 0.0,
          [&](const tbb::blocked_range<Index>& range, double sum) {
            for (Index s = range.begin(); s != range.end(); ++s) {
              Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
              Eigen::Vector3d au = Eigen::Vector3d::Zero();
              for (Index p = coupling.site_offsets[s]; p < coupling.site_offsets[s + 1]; ++p) {
                const Index j = coupling.site_vertices[p];
                const Eigen::Vector3d uj(u(j, 0), u(j, 1), u(j, 2));
                m.noalias() += uj * coupling.site_coefficients[p].transpose();
                au += value[p] * uj;
              }
              sum += au.dot(Eigen::Vector3d(u(s, 0), u(s, 1), u(s, 2))) - 2.0 * fit(s, m);
            }
            return sum;
          },
          std::plus<double>());
      return energy_without_constant + coupling.constant;
    }
    const double alignment = tbb::parallel_deterministic_reduce(
        tbb::blocked_range<Index>(0, coupling.num_sites, kGrain), 0.0,
        [&](const tbb::blocked_range<Index>& range, double sum) {
          for (Index s = range.begin(); s != range.end(); ++s) {
            sum += fit(s, Covariance(coupling, u, s));
          }
          return sum;
        },
        std::plus<double>());
    return QuadraticTerm(a, u) - 2.0 * alignment + coupling.constant;
  });
}

void AssembleCoupledRhs(const RotationCoupling& coupling, const Rotations& rotations,
                        Positions& rhs, const Context& context) {
  HARAP_CHECK(rhs.rows() == coupling.num_vertices, "rhs has {} rows for {} vertices", rhs.rows(),
              coupling.num_vertices);
  ForEachIndex(coupling.num_vertices, context, [&](Index j) {
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    for (Index p = coupling.vertex_offsets[j]; p < coupling.vertex_offsets[j + 1]; ++p) {
      b.noalias() += rotations[coupling.vertex_sites[p]] * coupling.vertex_coefficients[p];
    }
    rhs.row(j) = b.transpose();
  });
}

double EvaluateCoupledEnergy(const RotationCoupling& coupling, const SparseMatrix& a,
                             const Positions& u, const Rotations& rotations,
                             const Context& context) {
  HARAP_CHECK(static_cast<Index>(rotations.size()) == coupling.num_sites,
              "{} rotations for {} sites", rotations.size(), coupling.num_sites);
  return context.Run([&] {
    const double alignment = tbb::parallel_deterministic_reduce(
        tbb::blocked_range<Index>(0, coupling.num_sites, kGrain), 0.0,
        [&](const tbb::blocked_range<Index>& range, double sum) {
          for (Index s = range.begin(); s != range.end(); ++s) {
            sum += rotations[s].cwiseProduct(Covariance(coupling, u, s)).sum();
          }
          return sum;
        },
        std::plus<double>());
    return QuadraticTerm(a, u) - 2.0 * alignment + coupling.constant;
  });
}

namespace {

constexpr double kRelativeFloor = 1e-8;

/// Σ_a g(λ_a) e_a e_aᵀ over the eigenpairs of the symmetric 3×3 `m`.
template <class Function>
Eigen::Matrix3d SpectralFunction(const Eigen::Matrix3d& m, Function&& g) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
  eigen.computeDirect(m);
  const double floor = kRelativeFloor * eigen.eigenvalues().cwiseAbs().maxCoeff();
  Eigen::Matrix3d result = Eigen::Matrix3d::Zero();
  for (int a = 0; a < 3; ++a) {
    const double value = g(eigen.eigenvalues()(a), floor);
    if (value != 0.0) {
      result.noalias() +=
          value * eigen.eigenvectors().col(a) * eigen.eigenvectors().col(a).transpose();
    }
  }
  return result;
}

/// The clamped twist curvature β̃ of a mode whose pair sum relative to rest is μ (see
/// PrepareCoupledRotationDerivative): exact 1/μ when stretched (μ ≥ 1), 1 (the rest value, site
/// Hessian singular in that mode) when compressed, 0 when inverted.
double ClampedTwist(double mu) { return mu >= 1.0 ? 1.0 / mu : (mu > 0.0 ? 1.0 : 0.0); }

}  // namespace

std::vector<Eigen::Matrix3d> TwistMetrics(const RotationCoupling& coupling, const Positions& rest,
                                          const Context& context) {
  HARAP_CHECK(rest.rows() == coupling.num_vertices, "{} rest positions for {} vertices",
              rest.rows(), coupling.num_vertices);
  std::vector<Eigen::Matrix3d> metric(coupling.num_sites);
  ForEachIndex(coupling.num_sites, context, [&](Index s) {
    const Eigen::Matrix3d covariance = Covariance(coupling, rest, s);
    metric[s].setZero();
    if (coupling.planar) {
      const double sum = covariance(0, 0) + covariance(1, 1);
      const double scale = covariance.topLeftCorner<2, 2>().cwiseAbs().maxCoeff();
      if (sum > kRelativeFloor * scale) metric[s](2, 2) = 1.0 / std::sqrt(sum);
      return;
    }
    const Eigen::Matrix3d symmetric = 0.5 * (covariance + covariance.transpose());
    metric[s] = SpectralFunction(
        symmetric.trace() * Eigen::Matrix3d::Identity() - symmetric,
        [](double nu, double floor) { return nu > floor ? 1.0 / std::sqrt(nu) : 0.0; });
  });
  return metric;
}

void PrepareCoupledRotationDerivative(const RotationCoupling& coupling, const Positions& u,
                                      const Rotations& rotations,
                                      const std::vector<Eigen::Matrix3d>* twist_metric,
                                      std::vector<Eigen::Matrix3d>& curvature,
                                      const Context& context) {
  HARAP_CHECK(static_cast<Index>(rotations.size()) == coupling.num_sites,
              "{} rotations for {} sites", rotations.size(), coupling.num_sites);
  HARAP_CHECK(u.rows() == coupling.num_vertices, "{} positions for {} vertices", u.rows(),
              coupling.num_vertices);
  HARAP_CHECK(!twist_metric || static_cast<Index>(twist_metric->size()) == coupling.num_sites,
              "{} twist metrics for {} sites", twist_metric->size(), coupling.num_sites);
  curvature.resize(coupling.num_sites);
  ForEachIndex(coupling.num_sites, context, [&](Index s) {
    const Eigen::Matrix3d stretch = rotations[s].transpose() * Covariance(coupling, u, s);
    Eigen::Matrix3d& k = curvature[s];
    if (coupling.planar) {
      const double sum = stretch(0, 0) + stretch(1, 1);
      k.setZero();
      if (twist_metric) {
        const double w = (*twist_metric)[s](2, 2);
        k(2, 2) = w * w * ClampedTwist(sum * w * w);
      } else if (sum > kRelativeFloor * stretch.topLeftCorner<2, 2>().cwiseAbs().maxCoeff()) {
        k(2, 2) = 1.0 / sum;
      }
      return;
    }
    const Eigen::Matrix3d symmetric = 0.5 * (stretch + stretch.transpose());
    const Eigen::Matrix3d pair_sums = symmetric.trace() * Eigen::Matrix3d::Identity() - symmetric;
    if (!twist_metric) {
      k = SpectralFunction(pair_sums, [](double lambda, double floor) {
        return lambda > floor ? 1.0 / lambda : 0.0;
      });
      return;
    }
    // K̃ = W B̃ W with W = N^-½: the eigenvalues μ of W (tr S I − S) W are the pair sums relative
    // to rest, β = 1/μ those of N^½ K N^½.
    const Eigen::Matrix3d& w = (*twist_metric)[s];
    const Eigen::Matrix3d relative = w * pair_sums * w;
    k = w *
        SpectralFunction(0.5 * (relative + relative.transpose()),
                         [](double mu, double) { return ClampedTwist(mu); }) *
        w;
  });
}

void CoupledRotationDerivative(const RotationCoupling& coupling, const Positions& v,
                               const Rotations& rotations,
                               const std::vector<Eigen::Matrix3d>& curvature,
                               Rotations& d_rotations, const Context& context) {
  HARAP_CHECK(static_cast<Index>(curvature.size()) == coupling.num_sites &&
                  static_cast<Index>(rotations.size()) == coupling.num_sites,
              "{} curvatures and {} rotations for {} sites", curvature.size(), rotations.size(),
              coupling.num_sites);
  HARAP_CHECK(v.rows() == coupling.num_vertices, "{} directions for {} vertices", v.rows(),
              coupling.num_vertices);
  d_rotations.resize(coupling.num_sites);
  ForEachIndex(coupling.num_sites, context, [&](Index s) {
    const Eigen::Matrix3d x = rotations[s].transpose() * Covariance(coupling, v, s);
    const Eigen::Vector3d axial(x(2, 1) - x(1, 2), x(0, 2) - x(2, 0), x(1, 0) - x(0, 1));
    const Eigen::Vector3d w = curvature[s] * axial;
    Eigen::Matrix3d cross;
    cross << 0.0, -w(2), w(1), w(2), 0.0, -w(0), -w(1), w(0), 0.0;
    d_rotations[s].noalias() = rotations[s] * cross;
  });
}

double CoupledQuadraticEnergy::FitRotations(const Positions& u, Rotations& rotations,
                                            const Context& context) const {
  return FitCoupledRotations(coupling_, a_, u, rotations, context,
                             fit_coefficients_.empty() ? nullptr : &fit_coefficients_);
}

void CoupledQuadraticEnergy::AssembleRhs(const Rotations& rotations, Positions& rhs,
                                         const Context& context) const {
  AssembleCoupledRhs(coupling_, rotations, rhs, context);
}

double CoupledQuadraticEnergy::Evaluate(const Positions& u, const Rotations& rotations,
                                        const Context& context) const {
  return EvaluateCoupledEnergy(coupling_, a_, u, rotations, context);
}

void CoupledQuadraticEnergy::Precompute(const Mesh& rest, const Context& context) {
  {
    const std::lock_guard lock(twist_mutex_);
    rest_positions_ = rest.vertices;
    twist_metric_.clear();
  }
  HARAP_CHECK(stiffness_.empty() || static_cast<Index>(stiffness_.size()) == rest.num_elements(),
              "{} stiffness factors for a mesh of {} elements", stiffness_.size(),
              rest.num_elements());
  PrecomputeCoupledForm(rest, context);
}

void CoupledQuadraticEnergy::PrepareRotationDerivative(const Positions& u,
                                                       const Rotations& rotations, bool project,
                                                       std::vector<Eigen::Matrix3d>& curvature,
                                                       const Context& context) const {
  HARAP_CHECK(has_rotation_derivative(), "rotation derivative of a partial rotation fit");
  const std::vector<Eigen::Matrix3d>* metric = nullptr;
  if (project) {
    const std::lock_guard lock(twist_mutex_);
    if (twist_metric_.empty()) twist_metric_ = TwistMetrics(coupling_, rest_positions_, context);
    metric = &twist_metric_;
  }
  PrepareCoupledRotationDerivative(coupling_, u, rotations, metric, curvature, context);
}

void CoupledQuadraticEnergy::RotationDerivative(const Positions& v, const Rotations& rotations,
                                                const std::vector<Eigen::Matrix3d>& curvature,
                                                Rotations& d_rotations,
                                                const Context& context) const {
  CoupledRotationDerivative(coupling_, v, rotations, curvature, d_rotations, context);
}

}  // namespace harap
