// SPDX-License-Identifier: MIT
#pragma once

#include <array>
#include <string_view>
#include <vector>

#include "energies/kernels/rotation_coupling.h"
#include "energies/kernels/weight_schemes.h"

namespace harap {

/// The weight options of the edge-based energies (`weights`, `coarse_weights`, `min_cotangent`;
/// docs/energies.md, "Weight schemes"). Defaults are the energy's.
struct WeightOptions {
  WeightScheme input_level = WeightScheme::kCotangent;  ///< `weights`: on the input mesh
  /// `coarse_weights`: on the coarse levels of a hierarchy (kAsInputLevel: as `weights`).
  WeightScheme coarse_levels = WeightScheme::kAsInputLevel;
  double min_cotangent = 0.01;  ///< `min_cotangent`: the bound of the `clamped` scheme
  static WeightOptions FromConfig(OptionReader node, const WeightOptions& defaults);
};

/// Shared precomputation of the per-vertex cotangent ARAP energies on triangle meshes (spokes,
/// spokes-and-rims, smooth ARAP): ½cot weights of a weight scheme with degenerate triangles
/// zeroed, the adjacency pattern, a loop over faces in which the concrete energy adds its face's
/// contributions to A, to the coupling coefficients and to the constant, and a hook for terms
/// beyond per-face sums.
class CotangentArapEnergy : public CoupledQuadraticEnergy {
 public:
  void PrecomputeCoupledForm(const Mesh& rest, const Context& context) final;
  /// Marks the next Precompute() as a coarse level's (its weights: `coarse_weights`).
  void SetInputMesh(const Mesh& input, const Context& context) override;
  EnergyWeights weights() const override { return weights_; }

  /// Triangles whose weights were zeroed as degenerate in the last Precompute().
  Index num_degenerate_triangles() const { return num_degenerate_; }

 protected:
  /// `negative_weights_break_squares`: whether a negative edge weight takes the energy out of
  /// the sum-of-squares form (spokes: each edge is its own square; not so for per-face sums).
  CotangentArapEnergy(std::string_view name, const WeightOptions& weight_options,
                      bool negative_weights_break_squares)
      : CoupledQuadraticEnergy(RotationSite::kVertex),
        name_(name),
        weight_options_(weight_options),
        negative_weights_break_squares_(negative_weights_break_squares) {}
  /// Raw cotangent weights on every level, for energies that keep a sum of squares with them.
  explicit CotangentArapEnergy(std::string_view name)
      : CotangentArapEnergy(name, WeightOptions{}, /*negative_weights_break_squares=*/false) {}

  /// One face's data for AddFace: its vertices' rest positions, the ½cot weight of the edge
  /// opposite each corner, and where its 3×3 vertex pairs live in A's value array (entry
  /// (row v_a, column v_b) at positions[3a + b]).
  struct Face {
    std::array<Eigen::Vector3d, 3> rest;
    std::array<double, 3> half_cot;
    const std::array<Index, 9>& positions;
  };
  /// Adds the face's terms: to A's values (`a_values`), to the coupling coefficients c_sx at the
  /// entry (row x, column s) (`coefficients`), and to the constant.
  virtual void AddFace(const Face& face, double* a_values, Eigen::Vector3d* coefficients,
                       double& constant) const = 0;

  /// The spokes-and-rims terms of one face (Eq. 1), every weight multiplied by `scale`: the
  /// AddFace of `spokes_and_rims` (scale 1) and of energies that contain it as a part.
  static void AddSpokesAndRimsFace(const Face& face, double scale, double* a_values,
                                   Eigen::Vector3d* coefficients, double& constant);

  /// What the face loop was built from, for AddNonFaceTerms.
  struct RestGeometry {
    const Mesh& rest;
    const Elements& triangles;  ///< the triangles the weights live on (the scheme's)
    const Eigen::Matrix<double, Eigen::Dynamic, 3>& half_cot;  ///< HalfCotangents(), #F×3
    /// TriangleEntryPositions() in the adjacency pattern (a_'s pattern when the hook is called).
    const std::vector<std::array<Index, 9>>& entry;
  };
  /// Called once at the end of Precompute(), when a_ and coupling_ hold the face terms on the
  /// adjacency pattern. Energies with terms that are not sums over faces (smooth_arap's Laplacian
  /// term) add them here; a_ may be replaced by a matrix with a larger pattern (coupling_ keeps
  /// its own). Runs inside the context's arena.
  virtual void AddNonFaceTerms(const RestGeometry& /*geometry*/, const Context& /*context*/) {}

 private:
  /// Multiplies each triangle's weights by its stiffness factor (none without stiffness).
  void ApplyStiffness(const Mesh& rest, TriangleWeights& weights) const;

  std::string_view name_;
  WeightOptions weight_options_;
  bool negative_weights_break_squares_;
  bool coarse_level_ = false;
  Index num_degenerate_ = 0;
  EnergyWeights weights_;
};

/// The energies whose only options are their weights (spokes, spokes_and_rims): `Options` holds
/// the weight options with the energy's defaults (Derived::kDefaultWeights), FromConfig reads them
/// and rejects every other key, and the constructor hands them to CotangentArapEnergy with
/// Derived::kNegativeWeightsBreakSquares. The energy itself adds its name, those two constants
/// and AddFace.
template <class Derived>
class WeightedCotangentEnergy : public CotangentArapEnergy {
 public:
  struct Options {
    /// `weights`, `coarse_weights`, `min_cotangent` (docs/energies.md, "Weight schemes").
    WeightOptions weights = Derived::kDefaultWeights;
    static Options FromConfig(OptionReader node) {
      Options options;
      options.weights = WeightOptions::FromConfig(node, options.weights);
      node.RejectUnknownKeys();
      return options;
    }
  };

  explicit WeightedCotangentEnergy(const Options& options)
      : CotangentArapEnergy(Derived::kName, options.weights,
                            Derived::kNegativeWeightsBreakSquares) {}
};

}  // namespace harap
