// SPDX-License-Identifier: MIT
#include "solvers/optimizers/admm_pd_optimizer.h"

namespace harap {

AdmmPdOptimizer::Options AdmmPdOptimizer::Options::FromConfig(const ConfigNode& node) {
  Options options;
  options.admm = ReadAdmmOptions(node, AdmmVariant::kProjectiveDynamics);
  node.RejectUnknownKeys();
  return options;
}

std::unique_ptr<Optimizer> AdmmPdOptimizer::Create(const ConfigNode& node) {
  return std::make_unique<AdmmPdOptimizer>(Options::FromConfig(node));
}

OptimizeResult AdmmPdOptimizer::Optimize(const DeformationProblem& problem,
                                         const ComponentFactory& factory,
                                         const Context& context) const {
  return OptimizeWithAdmm(problem, factory, context, options_.admm);
}

}  // namespace harap
