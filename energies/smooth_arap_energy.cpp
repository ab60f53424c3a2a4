// SPDX-License-Identifier: MIT
#include "energies/smooth_arap_energy.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>

#include "energies/kernels/cotangent_weights.h"
#include "energies/kernels/triangle_stencil.h"
#include "framework/error.h"

namespace harap {

namespace {

constexpr Index kGrain = 1024;

// (face terms) + scale · L M⁻¹ L, on the union of the face terms' pattern (the 1-ring) and the
// 2-ring through vertices with mass. Column c of L M⁻¹ L is Σ_{i∈N(c)} L_ic m_i L_{:,i}; every
// entry sums its terms in ascending i as (L_ji·L_ic)·m_i, so the result is symmetric bit for bit
// (L is), like the matrices of the other energies. `laplacian` holds L on the face terms' pattern.
SparseMatrix AddWeightedBiLaplacian(const SparseMatrix& face_terms,
                                    const std::vector<double>& laplacian,
                                    const Eigen::VectorXd& inverse_mass, double scale) {
  const Index n = static_cast<Index>(face_terms.outerSize());
  const Index* outer = face_terms.outerIndexPtr();
  const Index* inner = face_terms.innerIndexPtr();
  const double* face_values = face_terms.valuePtr();
  struct Scratch {
    std::vector<char> in_column;
    std::vector<double> sum, base;
    std::vector<Index> rows;
  };
  tbb::enumerable_thread_specific<Scratch> scratch([n] {
    Scratch s;
    s.in_column.assign(n, 0);
    s.sum.assign(n, 0.0);
    s.base.assign(n, 0.0);
    return s;
  });
  // The rows of column c: its 1-ring, and the 1-ring of every neighbour i with mass.
  auto collect = [&](Scratch& s, Index c) {
    s.rows.clear();
    for (Index p = outer[c]; p < outer[c + 1]; ++p) {
      s.in_column[inner[p]] = 1;
      s.rows.push_back(inner[p]);
    }
    for (Index p = outer[c]; p < outer[c + 1]; ++p) {
      const Index i = inner[p];
      if (inverse_mass[i] == 0.0) continue;
      for (Index q = outer[i]; q < outer[i + 1]; ++q) {
        if (!s.in_column[inner[q]]) {
          s.in_column[inner[q]] = 1;
          s.rows.push_back(inner[q]);
        }
      }
    }
    for (Index j : s.rows) s.in_column[j] = 0;
  };

  std::vector<Index> counts(n + 1, 0);
  tbb::parallel_for(tbb::blocked_range<Index>(0, n, kGrain),
                    [&](const tbb::blocked_range<Index>& range) {
                      Scratch& s = scratch.local();
                      for (Index c = range.begin(); c != range.end(); ++c) {
                        collect(s, c);
                        counts[c + 1] = static_cast<Index>(s.rows.size());
                      }
                    });
  for (Index c = 0; c < n; ++c) counts[c + 1] += counts[c];
  SparseMatrix result(n, n);
  result.resizeNonZeros(counts[n]);
  std::copy(counts.begin(), counts.end(), result.outerIndexPtr());
  tbb::parallel_for(tbb::blocked_range<Index>(0, n, kGrain),
                    [&](const tbb::blocked_range<Index>& range) {
                      Scratch& s = scratch.local();
                      for (Index c = range.begin(); c != range.end(); ++c) {
                        collect(s, c);
                        for (Index j : s.rows) s.sum[j] = s.base[j] = 0.0;
                        for (Index p = outer[c]; p < outer[c + 1]; ++p)
                          s.base[inner[p]] = face_values[p];
                        for (Index p = outer[c]; p < outer[c + 1]; ++p) {
                          const Index i = inner[p];
                          const double m = inverse_mass[i];
                          if (m == 0.0) continue;
                          for (Index q = outer[i]; q < outer[i + 1]; ++q) {
                            s.sum[inner[q]] += (laplacian[q] * laplacian[p]) * m;
                          }
                        }
                        std::sort(s.rows.begin(), s.rows.end());
                        Index out = counts[c];
                        for (Index j : s.rows) {
                          result.innerIndexPtr()[out] = j;
                          result.valuePtr()[out] = scale * s.sum[j] + s.base[j];
                          ++out;
                        }
                      }
                    });
  return result;
}

// Mean mixed Voronoi area over the vertices that have area (0 if none has).
double MeanVertexArea(const Eigen::VectorXd& areas) {
  double total = 0.0;
  Index with_area = 0;
  for (Index i = 0; i < areas.size(); ++i) {
    if (areas[i] > 0.0) {
      total += areas[i];
      ++with_area;
    }
  }
  return with_area > 0 ? total / with_area : 0.0;
}

constexpr EnumNames<SmoothArapEnergy::RotationFit, 2> kRotationFitNames = {{
    {SmoothArapEnergy::RotationFit::kWholeEnergy, "energy"},
    {SmoothArapEnergy::RotationFit::kSpokesAndRims, "spokes_and_rims"},
}};
// normalize_mass_on_input: true = "input", false = "level".
constexpr EnumNames<bool, 2> kMassNormalizationNames = {{{true, "input"}, {false, "level"}}};

}  // namespace

SmoothArapEnergy::Options SmoothArapEnergy::Options::FromConfig(OptionReader node) {
  Options options;
  options.lambda = node.Get("lambda", options.lambda,
                            "weight of the Laplacian (smoothness) term; 0 is spokes_and_rims "
                            "exactly",
                            Range::HalfOpen(0.0, 1.0));
  options.rotation_fit = node.GetEnum(
      "rotation_fit", options.rotation_fit, kRotationFitNames,
      "local step: energy = minimize the whole energy per rotation (monotone); spokes_and_rims "
      "= fit to the spokes-and-rims part only, as the published code (may increase the energy)");
  options.normalize_mass_on_input =
      node.GetEnum("mass_normalization", options.normalize_mass_on_input, kMassNormalizationNames,
                   "rescale the mass matrix to mean 1 over the input mesh (input: every "
                   "hierarchy level approximates the same energy) or over each level's own mesh "
                   "(level)");
  node.RejectUnknownKeys();
  return options;
}

void SmoothArapEnergy::SetInputMesh(const Mesh& input, const Context& context) {
  CotangentArapEnergy::SetInputMesh(input, context);
  RequireTriangleMesh(input, kName);
  input_mean_area_ = context.Run(
      [&] { return MeanVertexArea(MixedVoronoiAreas(input.vertices, input.elements)); });
}

void SmoothArapEnergy::AddFace(const Face& face, double* a_values, Eigen::Vector3d* coefficients,
                               double& constant) const {
  AddSpokesAndRimsFace(face, 1.0 - options_.lambda, a_values, coefficients, constant);
}

void SmoothArapEnergy::AddNonFaceTerms(const RestGeometry& geometry, const Context& /*context*/) {
  if (options_.rotation_fit == RotationFit::kSpokesAndRims) {
    fit_coefficients_ = coupling_.site_coefficients;  // the E_SR part (scaled by 1 − λ > 0)
  }
  // λ = 0: nothing to add; A, coupling and constant are those of spokes_and_rims.
  if (options_.lambda == 0.0) return;
  const Mesh& rest = geometry.rest;
  const Index n = rest.num_vertices();

  // L on the adjacency pattern: L_jk = −Σ_f w_fjk, L_jj = −Σ_k L_jk (w = ½cot). Mirror entries
  // get the same additions in the same order, so L is symmetric bit for bit.
  std::vector<double> laplacian(a_.nonZeros(), 0.0);
  for (Index f = 0; f < rest.num_elements(); ++f) {
    const auto& at = geometry.entry[f];
    for (int a = 0; a < 3; ++a) {
      const int b = (a + 1) % 3, c = (a + 2) % 3;
      const double w = geometry.half_cot(f, a);
      laplacian[at[3 * b + b]] += w;
      laplacian[at[3 * c + c]] += w;
      laplacian[at[3 * b + c]] -= w;
      laplacian[at[3 * c + b]] -= w;
    }
  }

  // M: mixed Voronoi areas rescaled to mean 1 over the vertices that have area, those of the input
  // mesh if given (so that a coarse level approximates the input's energy). Vertices without area
  // have an empty row of L; they get no λ-term (inverse mass 0).
  const Eigen::VectorXd areas = MixedVoronoiAreas(rest.vertices, rest.elements);
  const double mean_area = options_.normalize_mass_on_input && input_mean_area_ > 0.0
                               ? input_mean_area_
                               : MeanVertexArea(areas);
  if (mean_area == 0.0) return;  // only degenerate triangles: every weight is zero anyway
  Eigen::VectorXd inverse_mass(n);
  for (Index i = 0; i < n; ++i) inverse_mass[i] = areas[i] > 0.0 ? mean_area / areas[i] : 0.0;

  // ℓ_i = (L V̄)_i (L is symmetric: row i = column i).
  const Index* outer = a_.outerIndexPtr();
  const Index* inner = a_.innerIndexPtr();
  std::vector<Eigen::Vector3d> rest_laplacian(n);
  tbb::parallel_for(tbb::blocked_range<Index>(0, n, kGrain),
                    [&](const tbb::blocked_range<Index>& range) {
                      for (Index i = range.begin(); i != range.end(); ++i) {
                        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
                        for (Index p = outer[i]; p < outer[i + 1]; ++p) {
                          sum += laplacian[p] * rest.vertices.row(inner[p]).transpose();
                        }
                        rest_laplacian[i] = sum;
                      }
                    });

  // k Σ_i m_i ‖(L U)_i − R_i ℓ_i‖² = k tr(Uᵀ L M⁻¹ L U) − 2 Σ_i ⟨R_i, Σ_j u_j c_ijᵀ⟩ + k Σ_i m_i
  // ‖ℓ_i‖² with c_ij = k m_i L_ij ℓ_i on the 1-ring: the coupling keeps its pattern. Both layouts
  // share it: entry p of column c, row r is c_{c r} by site and c_{r c} by vertex (L_rc = L_cr).
  const double k = 1.5 * options_.lambda;
  HARAP_CHECK(coupling_.site_coefficients.size() == laplacian.size(),
              "coupling has {} entries, the adjacency pattern {}",
              coupling_.site_coefficients.size(), laplacian.size());
  tbb::parallel_for(tbb::blocked_range<Index>(0, n, kGrain),
                    [&](const tbb::blocked_range<Index>& range) {
                      for (Index c = range.begin(); c != range.end(); ++c) {
                        for (Index p = outer[c]; p < outer[c + 1]; ++p) {
                          const Index r = inner[p];
                          coupling_.site_coefficients[p] +=
                              (k * inverse_mass[c] * laplacian[p]) * rest_laplacian[c];
                          coupling_.vertex_coefficients[p] +=
                              (k * inverse_mass[r] * laplacian[p]) * rest_laplacian[r];
                        }
                      }
                    });
  coupling_.constant += tbb::parallel_deterministic_reduce(
      tbb::blocked_range<Index>(0, n, kGrain), 0.0,
      [&](const tbb::blocked_range<Index>& range, double sum) {
        for (Index i = range.begin(); i != range.end(); ++i) {
          sum += k * inverse_mass[i] * rest_laplacian[i].squaredNorm();
        }
        return sum;
      },
      std::plus<double>());
  a_ = AddWeightedBiLaplacian(a_, laplacian, inverse_mass, k);
}

}  // namespace harap
