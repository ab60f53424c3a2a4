// SPDX-License-Identifier: MIT
#pragma once

// The `harap register` subcommand's command line (CLI11: included by main.cpp only; the work is
// in api/register.h).

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <fstream>
#include <optional>
#include <string>

#include "api/builtins.h"
#include "api/register.h"
#include "cli/interrupt.h"
#include "cli/output_checks.h"
#include "cli/piece_flags.h"
#include "cli/progress.h"
#include "framework/error.h"
#include "io/file_reading.h"
#include "io/mesh_io.h"
#include "io/mesh_writers.h"

namespace harap {

struct RegisterCommandArguments : PieceFlags {
  std::string source, target;
  std::string out, report, landmarks, answer;
  int threads = 0;
  bool quiet = false;
};

inline CLI::App* AddRegisterCommand(CLI::App& app, RegisterCommandArguments& a) {
  CLI::App* command = app.add_subcommand(
      "register",
      "deform a source mesh onto a target mesh or point cloud with ARAP as the regularizer "
      "(non-rigid ICP, coarse to fine; docs/registration.md)");
  command
      ->add_option("source", a.source,
                   "the mesh to deform: a triangle surface, or a tetrahedral volume (its boundary "
                   "meets the target)")
      ->required();
  command
      ->add_option("target", a.target,
                   "the target: a mesh file, or a point cloud (.xyz/.pts/.txt with x y z [nx ny "
                   "nz] per line, or a PLY without faces)")
      ->required();
  command->add_option("--out", a.out,
                      "write the registered mesh (.ply also stores each vertex's distance to "
                      "the target as the property `distance`)");
  command->add_option("--report", a.report, "write a JSON report");
  command->add_option("--landmarks", a.landmarks,
                      "file of landmarks, one `vertex x y z` per line (soft targets)");
  command->add_option("--answer", a.answer,
                      "a mesh with the source's vertices where they should end (e.g. from harap "
                      "known-answer): the report and summary give each vertex's error");
  command->add_option("--config", a.config_file,
                      "TOML file with the run config tables and [registration]");
  command->add_option("--optimizer", a.optimizer,
                      "hierarchical (default: coarse to fine) or classic (the input mesh alone)");
  command->add_option("--energy", a.energy, "energy name (default spokes_and_rims)");
  command->add_option("--solver", a.solver, "linear solver name (default cholmod)");
  command->add_option("--hierarchy", a.hierarchy, "hierarchy name (default octree)");
  command->add_option("--upsampler", a.upsampler, "upsampler name (default rotations)");
  command->add_option("--set", a.settings,
                      "set an option, e.g. registration.max_distance=0.05 (repeatable)");
  command->add_option("--threads", a.threads, "worker threads (default: all cores)");
  command->add_flag("--quiet,-q", a.quiet, "print nothing on success");
  return command;
}

inline int RunRegisterCommand(const RegisterCommandArguments& a) {
  // Wrong output names fail now, not after the registration.
  if (!a.report.empty()) CheckWritable(a.report, "--report");
  if (!a.out.empty()) CheckWritable(a.out, "--out");
  const ConfigNode config = a.BuildConfig();
  ProgressDisplay progress(stderr, ProgressOptions::For(stderr, a.quiet));
  progress.Phase("reading the source and the target");
  const Mesh source = ReadMesh(a.source);
  if (!a.out.empty()) CheckMeshOutputFormat(a.out, source.kind());
  const RegistrationTarget target = ReadRegistrationTarget(a.target);
  std::optional<Mesh> answer;
  if (!a.answer.empty()) {
    answer = ReadMesh(a.answer);
    if (answer->num_vertices() != source.num_vertices()) {
      throw InputError(fmt::format("--answer {}: {} vertices, the source {} has {}", a.answer,
                                   answer->num_vertices(), a.source, source.num_vertices()));
    }
  }
  RegisterOptions options;
  options.threads = a.threads;
  if (!a.landmarks.empty()) options.landmarks = ReadLandmarks(a.landmarks);
  const InterruptGuard interrupt;
  progress.Follow(options, InterruptGuard::Requested);
  RegisterOutcome outcome = RunRegister(MakeBuiltinRegistries(), source, target, config, options);
  outcome.interrupted = InterruptGuard::Requested();
  progress.Phase("writing the results");
  std::optional<AnswerComparison> comparison;
  if (answer) {
    comparison =
        AnswerComparison{a.answer, CompareWithAnswer(outcome.result.run.positions, answer->vertices,
                                                     BoundingBoxDiagonal(source), a.answer)};
  }
  if (!a.report.empty()) {
    std::ofstream file(a.report);
    file << RegisterReportJson(a.source, source, target, outcome,
                               comparison ? &*comparison : nullptr)
         << "\n";
    if (!file) throw InputError(fmt::format("{}: cannot write the report", a.report));
  }
  if (!a.out.empty()) {
    if (DetectFormat(a.out).extension == "ply") {
      WritePly(a.out, outcome.result.run.positions, source.elements,
               {{"distance", outcome.result.distance}});
    } else {
      WriteMesh(a.out, outcome.result.run.positions, source.elements);
    }
  }
  progress.Finish();
  if (!a.quiet) {
    const RegistrationResult& r = outcome.result;
    const double diagonal = BoundingBoxDiagonal(source);
    fmt::print(
        "registered {} ({} vertices) onto {} ({} {}), {}: {} correspondence updates, {} "
        "iterations, {:.3f} s\n",
        a.source, source.num_vertices(), a.target, target.num_points(),
        target.mesh ? "vertices" : "points", outcome.mode, r.correspondence_updates,
        r.run.total_iterations, r.run.timings.total + outcome.target_seconds);
    fmt::print(
        "  kept {} of {} correspondences (rejected: {} too far, {} normal angle, {} boundary); "
        "residual RMS {:.3g} ({:.3g}% of the diagonal), max {:.3g}; ARAP energy {:.6g}\n",
        r.correspondences.kept,
        r.correspondences.kept + r.correspondences.too_far + r.correspondences.normal_angle +
            r.correspondences.boundary,
        r.correspondences.too_far, r.correspondences.normal_angle, r.correspondences.boundary,
        r.residual_rms, 100.0 * r.residual_rms / diagonal, r.residual_max, r.arap_energy);
    if (comparison) {
      const AnswerErrors& e = comparison->errors;
      fmt::print(
          "  against the answer: mean error {:.3g}% of the diagonal, max {:.3g}% (vertex "
          "{}), RMS {:.3g}%\n",
          100.0 * e.mean / e.diagonal, 100.0 * e.max / e.diagonal, e.worst_vertex,
          100.0 * e.rms / e.diagonal);
    }
    if (r.correspondences.kept == 0) {
      fmt::print(
          "  no correspondence within registration.max_distance ({} of the diagonal): the "
          "source was left where it was; align it roughly first or raise max_distance\n",
          outcome.options.max_distance);
    }
  }
  return outcome.interrupted ? 130 : 0;
}

}  // namespace harap
