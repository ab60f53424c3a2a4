// SPDX-License-Identifier: MIT
#include "solvers/optimizers/wrapd_optimizer.h"

namespace harap {

WrapdOptimizer::Options WrapdOptimizer::Options::FromConfig(const ConfigNode& node) {
  Options options;
  options.admm = ReadAdmmOptions(node, AdmmVariant::kRotationAware);
  node.RejectUnknownKeys();
  return options;
}

std::unique_ptr<Optimizer> WrapdOptimizer::Create(const ConfigNode& node) {
  return std::make_unique<WrapdOptimizer>(Options::FromConfig(node));
}

OptimizeResult WrapdOptimizer::Optimize(const DeformationProblem& problem,
                                         const ComponentFactory& factory,
                                         const Context& context) const {
  return OptimizeWithAdmm(problem, factory, context, options_.admm);
}

}  // namespace harap
