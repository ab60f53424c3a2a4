// SPDX-License-Identifier: MIT
// What the session tests share: a small bending problem, optimizer configs, comparisons.
#pragma once

#include <catch2/catch.hpp>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "api/session.h"
#include "tests/support/test_factory.h"
#include "tests/support/test_meshes.h"

namespace harap::testing {

// A bent tube of 30 × 16 = 480 vertices: fast, and enough for a three-level octree hierarchy.
struct SmallBentTube : BentTube {
  SmallBentTube() : BentTube(30, 16, 2.0, M_PI / 3, Eigen::Vector3d(0.0, 0.5, -0.4)) {}
};

inline constexpr const char* kClassic =
    "[optimizer]\ntype = \"classic\"\ntolerance = 0\nmax_iterations = 25\n";
inline constexpr const char* kHierarchical =
    "[optimizer]\ntype = \"hierarchical\"\ntolerance = 0\nmax_iterations = 20\n"
    "[hierarchy]\nmin_vertices = 60\n";

inline bool Close(double a, double b, double relative) {
  return std::abs(a - b) <= relative * std::max(std::abs(a), std::abs(b));
}

inline std::unique_ptr<ConfiguredSession> Session(
    const TestSetup& setup, const Mesh& mesh,
    SessionOptions::FrameStart start = SessionOptions::FrameStart::kCorrected) {
  return MakeSession(setup.registries, mesh, setup.config, 2, start);
}

/// Solver tables for every route of CHOLMOD's Refactor() (the default solver's), and "" for the
/// default one.
inline std::vector<std::string> RefactorRouteSolvers() {
  std::vector<std::string> solvers = {""};
#ifdef HARAP_HAVE_CHOLMOD
  for (const char* route : {"auto", "partial", "update", "numeric"}) {
    solvers.push_back(std::string("[solver]\ntype = \"cholmod\"\nrefactor = \"") + route + "\"\n");
  }
#endif
  return solvers;
}

/// The same solve: per level iterations and energies (within `relative`), and positions.
inline void CheckSameSolve(const OptimizeResult& result, const OptimizeResult& expected,
                           double relative) {
  REQUIRE(result.levels.size() == expected.levels.size());
  for (size_t l = 0; l < result.levels.size(); ++l) {
    INFO("level " << result.levels[l].level);
    CHECK(result.levels[l].iterations == expected.levels[l].iterations);
    CHECK(Close(result.levels[l].energy, expected.levels[l].energy, relative));
  }
  CHECK(Close(result.energy, expected.energy, relative));
  CHECK((result.positions - expected.positions).cwiseAbs().maxCoeff() < 1e-8);
}

}  // namespace harap::testing
