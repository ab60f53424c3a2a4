// SPDX-License-Identifier: MIT
#include "framework/data_term.h"

#include <cmath>
#include <utility>

#include "framework/error.h"

namespace harap {

double SoftTargets::Evaluate(const Positions& u) const {
  double sum = 0.0;
  for (size_t k = 0; k < vertices.size(); ++k) {
    sum += weights[k] * (u.row(vertices[k]) - targets.row(static_cast<Index>(k))).squaredNorm();
  }
  return sum;
}

EnergyWithDataTerm::EnergyWithDataTerm(std::unique_ptr<Energy> energy)
    : energy_(std::move(energy)) {
  HARAP_CHECK(energy_ != nullptr, "data term without an energy");
}

void EnergyWithDataTerm::Precompute(const Mesh& rest, const Context& context) {
  energy_->Precompute(rest, context);
  soft_ = SoftTargets();
  matrix_ = SparseMatrix();
}

void EnergyWithDataTerm::SetInputMesh(const Mesh& input, const Context& context) {
  energy_->SetInputMesh(input, context);
}

bool EnergyWithDataTerm::SetSoftTargets(SoftTargets soft) {
  const SparseMatrix& a = energy_->system_matrix();
  HARAP_CHECK(static_cast<Index>(soft.vertices.size()) == soft.targets.rows() &&
                  soft.vertices.size() == soft.weights.size(),
              "{} soft targets with {} positions and {} weights", soft.vertices.size(),
              soft.targets.rows(), soft.weights.size());
  for (size_t k = 0; k < soft.vertices.size(); ++k) {
    HARAP_CHECK(soft.vertices[k] >= 0 && soft.vertices[k] < a.rows(),
                "soft target vertex {} out of range (n = {})", soft.vertices[k], a.rows());
    HARAP_CHECK(std::isfinite(soft.weights[k]) && soft.weights[k] > 0.0,
                "soft target weight {} of vertex {}", soft.weights[k], soft.vertices[k]);
  }
  const bool changed = !soft_.SameWeights(soft);
  soft_ = std::move(soft);
  if (changed) {
    matrix_ = SparseMatrix();
    if (!soft_.empty()) {
      std::vector<Eigen::Triplet<double, Index>> diagonal;
      diagonal.reserve(soft_.vertices.size());
      for (size_t k = 0; k < soft_.vertices.size(); ++k) {
        diagonal.emplace_back(soft_.vertices[k], soft_.vertices[k], soft_.weights[k]);
      }
      SparseMatrix w(a.rows(), a.cols());
      w.setFromTriplets(diagonal.begin(), diagonal.end());
      matrix_ = a + w;
      matrix_.makeCompressed();
    }
  }
  return changed;
}

void EnergyWithDataTerm::MoveSoftTargets(const Positions& targets) {
  HARAP_CHECK(targets.rows() == soft_.targets.rows(), "{} targets for {} soft targets",
              targets.rows(), soft_.targets.rows());
  soft_.targets = targets;
}

const SparseMatrix& EnergyWithDataTerm::system_matrix() const {
  return soft_.empty() ? energy_->system_matrix() : matrix_;
}

double EnergyWithDataTerm::FitRotations(const Positions& u, Rotations& rotations,
                                        const Context& context) const {
  const double energy = energy_->FitRotations(u, rotations, context);
  return soft_.empty() ? energy : energy + soft_.Evaluate(u);
}

void EnergyWithDataTerm::AssembleRhs(const Rotations& rotations, Positions& rhs,
                                     const Context& context) const {
  energy_->AssembleRhs(rotations, rhs, context);
  for (size_t k = 0; k < soft_.vertices.size(); ++k) {
    rhs.row(soft_.vertices[k]) += soft_.weights[k] * soft_.targets.row(static_cast<Index>(k));
  }
}

double EnergyWithDataTerm::Evaluate(const Positions& u, const Rotations& rotations,
                                    const Context& context) const {
  const double energy = energy_->Evaluate(u, rotations, context);
  return soft_.empty() ? energy : energy + soft_.Evaluate(u);
}

void EnergyWithDataTerm::PrepareRotationDerivative(const Positions& u, const Rotations& rotations,
                                                   bool project,
                                                   std::vector<Eigen::Matrix3d>& curvature,
                                                   const Context& context) const {
  energy_->PrepareRotationDerivative(u, rotations, project, curvature, context);
}

void EnergyWithDataTerm::RotationDerivative(const Positions& v, const Rotations& rotations,
                                            const std::vector<Eigen::Matrix3d>& curvature,
                                            Rotations& d_rotations, const Context& context) const {
  energy_->RotationDerivative(v, rotations, curvature, d_rotations, context);
}

std::map<std::string, double> EnergyWithDataTerm::AuxiliaryMeasures(const Positions& u,
                                                                    const Rotations& rotations,
                                                                    const Context& context) const {
  std::map<std::string, double> measures = energy_->AuxiliaryMeasures(u, rotations, context);
  if (!soft_.empty()) measures["data_energy"] = soft_.Evaluate(u);
  return measures;
}

}  // namespace harap
