// SPDX-License-Identifier: MIT
#pragma once

#include <memory>
#include <string_view>

#include "framework/config.h"
#include "framework/optimizer.h"
#include "solvers/optimizers/local_global_solver.h"

namespace harap {

/// Classic single-level ARAP [Sorkine & Alexa 2007]: from the rest positions (constrained
/// vertices at their targets) alternate local step (best-fit rotations) and global step (one
/// solve with the matrix factored once) until the paper's convergence test holds. The paper's
/// baseline ("ARAP" in Table 1). The energy never increases from one iteration to the next.
class ClassicOptimizer final : public Optimizer {
 public:
  static constexpr std::string_view kName = "classic";

  struct Options {
    LocalGlobalOptions iterations;  ///< tolerance (1e-6), max_iterations (1000)
    static Options FromConfig(const ConfigNode& node);
  };

  explicit ClassicOptimizer(const Options& options) : options_(options) {}
  static std::unique_ptr<Optimizer> Create(const ConfigNode& node);

  OptimizeResult Optimize(const DeformationProblem& problem, const ComponentFactory& factory,
                          const Context& context) const override;

 private:
  Options options_;
};

/// Notes for the report about what constraint handling did (pinned components, isolated
/// vertices); shared by the optimizers.
std::vector<std::string> DescribeConstraintHandling(const ConstraintReport& report);

}  // namespace harap
