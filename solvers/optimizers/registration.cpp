// SPDX-License-Identifier: MIT
#include "solvers/optimizers/registration.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "framework/error.h"
#include "framework/mesh_topology.h"
#include "framework/stiffness.h"
#include "framework/vertex_normals.h"
#include "solvers/optimizers/coarse_constraints.h"
#include "solvers/optimizers/level_cascade.h"

namespace harap {

double RegistrationOptions::DataWeight(int stage) const {
  if (stages <= 1) return data_weight_end;
  const double t = static_cast<double>(stage) / (stages - 1);
  return data_weight_start * std::pow(data_weight_end / data_weight_start, t);
}

RegistrationOptions RegistrationOptions::FromConfig(OptionReader node) {
  RegistrationOptions options;
  options.data_weight_start =
      node.Get("data_weight_start", options.data_weight_start,
               "data weight in the first stage, per unit of vertex mass (area / diagonal^2)",
               Range::Above(0.0));
  options.data_weight_end =
      node.Get("data_weight_end", options.data_weight_end,
               "data weight in the last stage, per unit of vertex mass", Range::Above(0.0));
  options.stages = node.Get("stages", options.stages,
                            "stages of the data weight schedule (geometric from start to end)",
                            Range::AtLeast(1));
  options.max_updates =
      node.Get("max_updates", options.max_updates,
               "correspondence updates per stage and level at most", Range::AtLeast(1));
  options.tolerance =
      node.Get("tolerance", options.tolerance,
               "a stage ends when an update moves the vertices by less than this (RMS, relative "
               "to the bounding-box diagonal)",
               Range::AtLeast(0.0));
  options.inner_iterations =
      node.Get("inner_iterations", options.inner_iterations,
               "local/global iterations between correspondence updates", Range::AtLeast(1));
  options.point_to_plane =
      node.Get("point_to_plane", options.point_to_plane,
               "pull each vertex to the target's tangent plane at its closest point (where the "
               "target has normals), not to the point itself");
  options.symmetric =
      node.Get("symmetric", options.symmetric,
               "also pull each source vertex towards the target points it is nearest to");
  options.refine_stages = node.Get(
      "refine_stages", options.refine_stages,
      "stages (the last ones) run on the levels finer than the coarsest", Range::AtLeast(1));
  options.refactor_fraction =
      node.Get("refactor_fraction", options.refactor_fraction,
               "factor the system anew when the kept correspondences changed in more than this "
               "fraction of the vertices",
               Range::Closed(0.0, 1.0));
  options.max_distance =
      node.Get("max_distance", options.max_distance,
               "reject correspondences farther than this (relative to the source's bounding-box "
               "diagonal)",
               Range::Above(0.0));
  options.max_normal_angle =
      node.Get("max_normal_angle", options.max_normal_angle,
               "reject correspondences whose normals differ by more (degrees; targets with "
               "normals; 180: never)",
               Range::Closed(0.0, 180.0));
  options.reject_boundary = node.Get("reject_boundary", options.reject_boundary,
                                     "reject correspondences on the target mesh's boundary");
  options.landmark_weight = node.Get(
      "landmark_weight", options.landmark_weight,
      "weight of a landmark's pull, relative to the last stage's data weight", Range::Above(0.0));
  node.RejectUnknownKeys();
  return options;
}

namespace {

void CheckProblem(const RegistrationProblem& problem) {
  HARAP_CHECK(problem.source != nullptr && problem.target != nullptr,
              "a registration needs a source mesh and a target");
  const Mesh& source = *problem.source;
  if (source.planar) {
    throw InputError(
        "registration deforms a surface or a volume in space; the source is a planar mesh");
  }
  if (problem.target->num_points() == 0) throw InputError("the registration target is empty");
  const Constraints& landmarks = problem.landmarks;
  HARAP_CHECK(landmarks.targets.rows() == static_cast<Index>(landmarks.indices.size()),
              "landmark targets and indices differ in length");
  for (size_t k = 0; k < landmarks.indices.size(); ++k) {
    const Index v = landmarks.indices[k];
    if (v < 0 || v >= source.num_vertices()) {
      throw InputError(fmt::format("landmark {}: vertex {} is out of range (the source has {})",
                                   k + 1, v, source.num_vertices()));
    }
    if (!landmarks.targets.row(static_cast<Index>(k)).allFinite()) {
      throw InputError(fmt::format("landmark {} (vertex {}): the target is not finite", k + 1, v));
    }
  }
}

// The surface of one level's mesh, which meets the target: a triangle mesh's triangles, a
// tetrahedral mesh's boundary triangles. Interior vertices of a volume get no correspondence; the
// ARAP energy of the tetrahedra carries them along.
struct LevelSurface {
  Elements triangles;
  std::vector<char> on_surface;  // per vertex; empty: every vertex is on the surface
  std::vector<Index> vertices;   // the vertices on the surface, ascending; empty: every vertex
  Index num_surface_vertices = 0;

  LevelSurface() = default;
  explicit LevelSurface(const Mesh& mesh) {
    if (mesh.kind() != ElementKind::kTetrahedron) {
      triangles = mesh.elements;
      num_surface_vertices = mesh.num_vertices();
      return;
    }
    triangles = BoundaryTriangles(mesh.elements);
    on_surface.assign(static_cast<size_t>(mesh.num_vertices()), 0);
    for (Index t = 0; t < triangles.rows(); ++t) {
      for (int k = 0; k < 3; ++k) on_surface[static_cast<size_t>(triangles(t, k))] = 1;
    }
    for (Index v = 0; v < mesh.num_vertices(); ++v) {
      if (on_surface[static_cast<size_t>(v)]) vertices.push_back(v);
    }
    num_surface_vertices = static_cast<Index>(vertices.size());
  }
  bool Contains(Index v) const { return on_surface.empty() || on_surface[v]; }
};

// The correspondences of one level's vertices: where each is pulled and whether it was kept.
struct Correspondences {
  Positions targets;  // #vertices×3: the closest point, or the vertex itself when rejected
  CorrespondenceCounts counts;
  double kept_squared_sum = 0.0;
  double kept_max = 0.0;
  std::vector<double> distance;
  std::vector<char> kept;  // per vertex
};

// The symmetric correspondences look at about this many target points per source vertex at most
// (CorrespondenceFinder::AddBackward).
constexpr Index kSymmetricPointsPerVertex = 8;

class CorrespondenceFinder {
 public:
  CorrespondenceFinder(const ClosestPointSearch& target, const PointSearchFactory& point_search,
                       const RegistrationOptions& options, double diagonal)
      : target_(target),
        point_search_(options.symmetric ? point_search : PointSearchFactory()),
        max_distance_(options.max_distance * diagonal),
        min_cosine_(std::cos(options.max_normal_angle * M_PI / 180.0)),
        check_normals_(target.has_normals() && options.max_normal_angle < 180.0),
        reject_boundary_(options.reject_boundary),
        point_to_plane_(options.point_to_plane) {}

  void Find(const Positions& positions, const LevelSurface& surface, Correspondences& out,
            const Context& context) {
    Stopwatch clock;
    FindForward(positions, surface, out, context);
    seconds_ += clock.Seconds();
  }
  // Seconds spent finding correspondences since the last call.
  double TakeSeconds() { return std::exchange(seconds_, 0.0); }

 private:
  void FindForward(const Positions& positions, const LevelSurface& surface, Correspondences& out,
                   const Context& context) {
    target_.FindClosest(positions, closest_, context);
    const Positions normals =
        check_normals_ ? VertexNormals(positions, surface.triangles) : Positions(0, 3);
    out.targets.resize(positions.rows(), 3);
    out.distance.resize(positions.rows());
    out.kept.resize(positions.rows());
    out.counts = CorrespondenceCounts{};
    out.kept_squared_sum = 0.0;
    out.kept_max = 0.0;
    for (Index v = 0; v < positions.rows(); ++v) {
      const ClosestPoint& c = closest_[v];
      out.distance[v] = c.distance;
      bool kept = true;
      if (!surface.Contains(v)) {
        kept = false;  // inside a volume: no correspondence, not a rejection
      } else if (c.distance > max_distance_) {
        ++out.counts.too_far;
        kept = false;
      } else if (reject_boundary_ && c.feature == ClosestFeature::kBoundary) {
        ++out.counts.boundary;
        kept = false;
      } else if (check_normals_ && normals.row(v).squaredNorm() > 0.0 &&
                 c.normal.squaredNorm() > 0.0 && normals.row(v).dot(c.normal) < min_cosine_) {
        ++out.counts.normal_angle;
        kept = false;
      }
      out.kept[v] = kept ? 1 : 0;
      if (kept) {
        ++out.counts.kept;
        // Point-to-plane: the vertex's projection onto the target's tangent plane at c, so the
        // pull is along the normal only and the vertex may slide along the surface (the ARAP
        // term places it there); still a point target, so the system keeps its n×n form.
        const Eigen::Vector3d u = positions.row(v).transpose();
        const Eigen::Vector3d target =
            point_to_plane_ && c.normal.squaredNorm() > 0.0
                ? Eigen::Vector3d(u - c.normal * c.normal.dot(u - c.point))
                : c.point;
        out.targets.row(v) = target.transpose();
        out.kept_squared_sum += c.distance * c.distance;
        out.kept_max = std::max(out.kept_max, c.distance);
      } else {
        out.targets.row(v) = positions.row(v);  // the proximal pull: stay where you are
      }
    }
    if (point_search_) AddBackward(positions, surface, normals, out, context);
  }

  // The symmetric part: each target point pulls the source vertex nearest to it (with the same
  // rejections). A vertex with such points is pulled to the midpoint of its closest point and
  // their mean, i.e. by both terms λ‖u − c‖² + λ‖u − mean‖² (up to a constant), or to their mean
  // alone where its own correspondence was rejected. Target parts that no vertex reaches as its
  // closest point (a stretched limb, the far side of a bend) pull so too.
  void AddBackward(const Positions& positions, const LevelSurface& surface,
                   const Positions& normals, Correspondences& out, const Context& context) {
    // A volume's target points pull its surface vertices only.
    const std::vector<Index>& searched = surface.vertices;
    if (!searched.empty()) {
      surface_positions_.resize(static_cast<Index>(searched.size()), 3);
      for (size_t k = 0; k < searched.size(); ++k) {
        surface_positions_.row(static_cast<Index>(k)) = positions.row(searched[k]);
      }
    }
    const std::unique_ptr<ClosestPointSearch> source =
        point_search_(searched.empty() ? positions : surface_positions_);
    // Every k-th target point, so that a vertex gets about kSymmetricPointsPerVertex of them at
    // most: a coarse level's few vertices need no more to find their share of the target.
    const Index stride = std::max<Index>(
        1, target_.num_points() /
               (kSymmetricPointsPerVertex * std::max<Index>(1, surface.num_surface_vertices)));
    if (stride != sample_stride_) {
      sample_stride_ = stride;
      const Index count = (target_.num_points() + stride - 1) / stride;
      sample_points_.resize(count, 3);
      sample_normals_.resize(target_.point_normals().rows() > 0 ? count : 0, 3);
      for (Index k = 0; k < count; ++k) {
        sample_points_.row(k) = target_.points().row(k * stride);
        if (sample_normals_.rows() > 0) {
          sample_normals_.row(k) = target_.point_normals().row(k * stride);
        }
      }
    }
    const Positions& target_points = sample_points_;
    const Positions& target_normals = sample_normals_;
    source->FindClosest(target_points, nearest_vertex_, context);
    sums_.setZero(positions.rows(), 3);
    counts_.assign(positions.rows(), 0);
    for (Index p = 0; p < target_points.rows(); ++p) {
      const ClosestPoint& c = nearest_vertex_[p];
      const Index v = searched.empty() ? c.element : searched[static_cast<size_t>(c.element)];
      if (c.distance > max_distance_) continue;
      if (check_normals_ && target_normals.rows() > 0 && normals.row(v).squaredNorm() > 0.0 &&
          normals.row(v).dot(target_normals.row(p)) < min_cosine_) {
        continue;
      }
      sums_.row(v) += target_points.row(p);
      ++counts_[v];
    }
    for (Index v = 0; v < positions.rows(); ++v) {
      if (counts_[v] == 0) continue;
      const Eigen::RowVector3d mean = sums_.row(v) / counts_[v];
      out.targets.row(v) =
          out.kept[v] ? Eigen::RowVector3d(0.5 * (out.targets.row(v) + mean)) : mean;
      out.kept[v] = 1;
    }
  }

  const ClosestPointSearch& target_;
  PointSearchFactory point_search_;  // empty: no symmetric part
  double max_distance_, min_cosine_;
  bool check_normals_, reject_boundary_, point_to_plane_;
  std::vector<ClosestPoint> closest_, nearest_vertex_;
  double seconds_ = 0.0;
  Positions sums_;
  std::vector<Index> counts_;
  Index sample_stride_ = 0;  // of sample_points_ (0: none yet)
  Positions sample_points_, sample_normals_;
  Positions surface_positions_;  // a volume's surface vertices (AddBackward)
};

// The data weight of a vertex whose correspondence was rejected when the system was factored,
// relative to a kept one's: small, so it hardly holds the vertex back, and > 0, so the weights
// stay valid soft targets.
constexpr double kUnweightedFactor = 1e-3;

// `total` += the solves of `part`.
void AddSolves(const SolveStatistics& part, SolveStatistics& total) {
  total.solves += part.solves;
  total.iterations += part.iterations;
  total.max_relative_residual = std::max(total.max_relative_residual, part.max_relative_residual);
  total.last_relative_residual = part.last_relative_residual;
  total.seconds += part.seconds;
  total.residuals_computed += part.residuals_computed;
}

// The data term's mass of each vertex of level `level`: the barycentric area (a third of the
// area of the (surface) triangles around it) of the input vertices it stands for, over the squared
// bounding-box diagonal. The ARAP energies scale as an integral over the surface of squared
// strains (cotangent weights), so with these masses the data term is an integral too and the
// balance of the two does not depend on the mesh's resolution; on a coarse level each vertex
// pulls with its cluster's summed mass, so the coarse problem approximates the fine one. A
// vertex without area gets the smallest positive mass (its weight must be > 0).
std::vector<double> VertexMasses(const MeshHierarchy* hierarchy, const Mesh& input,
                                 const LevelSurface& surface, int level, Index level_vertices) {
  const double diagonal = BoundingBoxDiagonal(input);
  std::vector<double> input_mass(input.num_vertices(), 0.0);
  const Elements& triangles = surface.triangles;
  for (Index f = 0; f < triangles.rows(); ++f) {
    const Eigen::Vector3d a = input.vertices.row(triangles(f, 0));
    const Eigen::Vector3d b = input.vertices.row(triangles(f, 1));
    const Eigen::Vector3d c = input.vertices.row(triangles(f, 2));
    const double third = (b - a).cross(c - a).norm() / 6.0 / (diagonal * diagonal);
    for (int k = 0; k < 3; ++k) input_mass[triangles(f, k)] += third;
  }
  std::vector<double> masses(level_vertices, 0.0);
  for (Index v = 0; v < input.num_vertices(); ++v) {
    const Index c = hierarchy == nullptr ? v : hierarchy->MapFinestVertex(v, level);
    if (c != kNoVertex) masses[c] += input_mass[v];
  }
  double smallest = std::numeric_limits<double>::infinity();
  for (double mass : masses) {
    if (mass > 0.0) smallest = std::min(smallest, mass);
  }
  for (double& mass : masses) {
    if (!(mass > 0.0)) mass = std::isfinite(smallest) ? smallest : 1.0;
  }
  return masses;
}

// The registration's pass down the levels: each level runs the stages of correspondence
// updates from the up-sampled result of the coarser one.
class RegistrationPass final : public LevelCascade::Pass {
 public:
  RegistrationPass(const RegistrationProblem& problem, const RegistrationOptions& options,
                   LevelCascade& cascade, const ComponentFactory& factory, const Context& context)
      : problem_(problem),
        options_(options),
        cascade_(cascade),
        factory_(factory),
        context_(context),
        diagonal_(BoundingBoxDiagonal(*problem.source)),
        finder_(*problem.target, problem.make_point_search, options, diagonal_),
        input_surface_(*problem.source),
        landmark_input_(SoftLandmarks(problem, options, input_surface_)) {}

  int updates() const { return updates_; }
  const Correspondences& last() const { return correspondences_; }

  bool Solves(int /*l*/) const override { return true; }
  LevelState& Start(int l, const LevelState* coarser, bool& from_rotations) override {
    if (coarser == nullptr) {
      state_.positions = cascade_.LevelMesh(l).vertices;
      return state_;
    }
    LevelState coarse_state = std::move(state_);
    state_ = LevelState();
    from_rotations = cascade_.Upsample(l, coarse_state, state_, context_);
    return state_;
  }
  void Prepare(int l) override {
    // The first stage's system, so that even a run stopped above this level can fit its
    // rotations here.
    level_ = l;
    const Mesh& mesh = cascade_.LevelMesh(l);
    surface_ = l == 0 ? input_surface_ : LevelSurface(mesh);
    masses_ = VertexMasses(cascade_.hierarchical() ? &cascade_.hierarchy() : nullptr,
                           cascade_.LevelMesh(0), input_surface_, l, mesh.num_vertices());
    landmarks_ = l == 0 ? LevelConstraints::Exact(landmark_input_, false).soft
                        : cascade_.MapConstraints(l, landmark_input_).soft;
    finder_.Find(state_.positions, surface_, correspondences_, context_);
    Constrain(l, FirstStage(l));
  }
  LevelSolveRequest Request(int /*l*/, bool from_rotations, bool /*finishing*/) override {
    LevelSolveRequest request;
    request.start_from_rotations = from_rotations;
    request.max_iterations = options_.inner_iterations;
    request.tolerance = 0.0;  // the updates decide when to stop
    request.diagonal = diagonal_;
    return request;
  }
  LevelSolveResult Solve(LevelSolver& solver, LevelState& state, const LevelSolveRequest& request,
                         const Context& context) override;

 private:
  // The landmarks as soft constraints of the input mesh: each pulls like `landmark_weight`
  // vertices of mean mass in the last stage.
  static Constraints SoftLandmarks(const RegistrationProblem& problem,
                                   const RegistrationOptions& options,
                                   const LevelSurface& surface) {
    Constraints landmarks = problem.landmarks;
    const std::vector<double> input_masses =
        VertexMasses(nullptr, *problem.source, surface, 0, problem.source->num_vertices());
    const double mean_mass = std::accumulate(input_masses.begin(), input_masses.end(), 0.0) /
                             static_cast<double>(input_masses.size());
    landmarks.weights.assign(landmarks.indices.size(),
                             options.landmark_weight * options.data_weight_end * mean_mass);
    return landmarks;
  }
  // The level's soft targets: every vertex at its correspondence with λ_stage m_v, then the
  // landmarks.
  SoftTargets LevelSoftTargets(int stage) const {
    SoftTargets soft;
    const Index n = correspondences_.targets.rows();
    soft.vertices.resize(n);
    soft.weights.resize(n);
    for (Index v = 0; v < n; ++v) {
      soft.vertices[v] = v;
      soft.weights[v] =
          options_.DataWeight(stage) * masses_[v] * (weighted_[v] ? 1.0 : kUnweightedFactor);
    }
    soft.targets = SoftTargetRows();
    soft.vertices.insert(soft.vertices.end(), landmarks_.vertices.begin(),
                         landmarks_.vertices.end());
    soft.weights.insert(soft.weights.end(), landmarks_.weights.begin(), landmarks_.weights.end());
    return soft;
  }
  // The coarsest level runs every stage; finer ones, which start from its alignment, only the
  // last `refine_stages`.
  int FirstStage(int l) const {
    if (l == cascade_.num_levels() - 1) return 0;
    return std::max(0, options_.stages - options_.refine_stages);
  }
  // Whether the kept correspondences differ from the weighted vertices in more than
  // `refactor_fraction` of the vertices.
  bool KeptSetChanged() const {
    Index changed = 0;
    for (size_t v = 0; v < weighted_.size(); ++v)
      changed += weighted_[v] != correspondences_.kept[v];
    return changed > options_.refactor_fraction * static_cast<double>(weighted_.size());
  }
  Positions SoftTargetRows() const {
    Positions rows(correspondences_.targets.rows() + landmarks_.targets.rows(), 3);
    rows << correspondences_.targets, landmarks_.targets;
    return rows;
  }
  // Factors level l's system for `stage`, with full weights on the vertices whose
  // correspondences are kept now.
  void Constrain(int l, int stage) {
    weighted_ = correspondences_.kept;
    LevelConstraints constraints;
    constraints.mean_target.resize(0, 3);
    constraints.soft = LevelSoftTargets(stage);
    cascade_.solver(l).Constrain(constraints, factory_, context_);
  }

  const RegistrationProblem& problem_;
  const RegistrationOptions& options_;
  LevelCascade& cascade_;
  const ComponentFactory& factory_;
  const Context& context_;
  double diagonal_;
  CorrespondenceFinder finder_;
  LevelSurface input_surface_;  // of the input mesh
  LevelSurface surface_;        // of the level being solved
  Constraints landmark_input_;  // the problem's landmarks, soft (SoftLandmarks)
  LevelState state_;
  std::vector<double> masses_;  // per level vertex (VertexMasses)
  SoftTargets landmarks_;       // landmark_input_ on the level being solved
  Correspondences correspondences_;
  Positions previous_positions_;  // before the last update's solve (its motion)
  int level_ = 0;                 // the level being solved (Prepare)
  // Per vertex: whether the current factorization gives it the full data weight.
  std::vector<char> weighted_;
  int updates_ = 0;
};

LevelSolveResult RegistrationPass::Solve(LevelSolver& solver, LevelState& state,
                                         const LevelSolveRequest& request, const Context& context) {
  LevelSolveResult total;
  LevelSolveRequest step = request;
  int level_updates = 0, refactorizations = 0;
  const double motion_tolerance = options_.tolerance * diagonal_;
  for (int stage = FirstStage(level_); stage < options_.stages && !total.stopped_by_callback;
       ++stage) {
    if (stage > FirstStage(level_)) {
      finder_.Find(state.positions, surface_, correspondences_, context);
      Constrain(level_, stage);
    }
    for (int update = 0; update < options_.max_updates; ++update) {
      if (update > 0) {
        finder_.Find(state.positions, surface_, correspondences_, context);
        if (KeptSetChanged()) {
          Constrain(level_, stage);
          ++refactorizations;
        } else {
          solver.MoveSoftTargets(SoftTargetRows());
        }
      }
      previous_positions_ = state.positions;
      const LevelSolveResult run = solver.Solve(state, step, context);
      step.start_from_rotations = false;  // later solves start from positions
      ++level_updates;
      total.iterations += run.iterations;
      total.energy = run.energy;
      AddSolves(run.linear_solves, total.linear_solves);
      total.notes.insert(total.notes.end(), run.notes.begin(), run.notes.end());
      total.weights = run.weights;
      if (run.stopped_by_callback) {
        total.stopped_by_callback = true;
        break;
      }
      const double rms_motion = std::sqrt((state.positions - previous_positions_).squaredNorm() /
                                          std::max<Index>(1, state.positions.rows()));
      if (rms_motion < motion_tolerance) {
        total.converged = stage + 1 == options_.stages;
        break;
      }
    }
  }
  // The correspondences of the result, for the report.
  finder_.Find(state.positions, surface_, correspondences_, context);
  updates_ += level_updates;
  const Index kept = std::max<Index>(1, correspondences_.counts.kept);
  total.measures["correspondence_updates"] = level_updates;
  total.measures["refactorizations"] = refactorizations;
  total.measures["correspondence_seconds"] = finder_.TakeSeconds();
  total.measures["kept_fraction"] = static_cast<double>(correspondences_.counts.kept) /
                                    std::max<Index>(1, surface_.num_surface_vertices);
  total.measures["residual_rms"] = std::sqrt(correspondences_.kept_squared_sum / kept);
  return total;
}

}  // namespace

RegistrationResult Register(const RegistrationProblem& problem, const RegistrationOptions& options,
                            const LevelSolver& level_solver, const ComponentFactory& factory,
                            const Context& context) {
  CheckProblem(problem);
  ValidateStiffness(problem.stiffness, *problem.source, "the stiffness");
  Stopwatch total;
  RegistrationResult result;
  const Mesh& source = *problem.source;
  // The one renumbering (level_cascade.h): the registration runs in the level numbering, the
  // source and its landmarks mapped in here, the positions and distances out at the end.
  LevelCascade cascade(source, context);
  const RegistrationProblem level_problem{&cascade.LevelMesh(0),
                                          problem.target,
                                          cascade.ToLevel(problem.landmarks),
                                          problem.make_point_search,
                                          {}};

  Stopwatch clock;
  if (options.hierarchical) {
    context.ReportPhase("building the hierarchy");
    cascade.SetHierarchy(factory.MakeHierarchy()->Build(source, context), factory.MakeUpsampler());
  } else {
    cascade.SetSingleLevel();
  }
  result.run.timings.hierarchy = clock.Seconds();

  // P of every level (C happens per stage, in the pass).
  for (int l = 0; l < cascade.num_levels(); ++l) {
    context.ReportPhase(fmt::format("precomputing level {}", l));
    Stopwatch setup;
    std::unique_ptr<LevelSolver> solver = level_solver.CreateAnother();
    const std::vector<double> stiffness = cascade.LevelStiffness(l, problem.stiffness);
    solver->Precompute(
        LevelSetup{&cascade.LevelMesh(l), l > 0 ? &source : nullptr, l, false, &stiffness}, factory,
        context);
    if (!solver->accepts_soft_targets()) {
      throw ConfigError(
          "registration needs a level solver with soft targets (optimizer.inner = "
          "\"local_global\")");
    }
    result.run.timings.precompute += solver->precompute_seconds();
    cascade.set_solver(l, std::move(solver), setup.Seconds());
  }
  const int coarsest = cascade.num_levels() - 1;
  cascade.TakeRotationSite(coarsest);

  Stopwatch solve_clock;
  RegistrationPass pass(level_problem, options, cascade, factory, context);
  std::vector<std::string> notes;
  LevelState& state = cascade.Run(coarsest, pass, context, result.run, notes);
  for (int l = 0; l < cascade.num_levels(); ++l) {
    result.run.timings.constrain += cascade.solver(l).constrain_seconds();
  }
  result.run.timings.solve = solve_clock.Seconds();

  const LevelSolver& finest = cascade.solver(0);
  result.run.measures = finest.AuxiliaryMeasures(state, context);
  const auto data = result.run.measures.find("data_energy");
  result.arap_energy = result.run.energy - (data == result.run.measures.end() ? 0.0 : data->second);
  result.run.constraints = finest.constraint_report();
  result.run.notes = std::move(notes);
  const Correspondences& last = pass.last();
  result.distance.resize(last.distance.size());
  const std::vector<Index>& to_input = cascade.finest_ordering().old_vertex;
  for (size_t k = 0; k < last.distance.size(); ++k) result.distance[to_input[k]] = last.distance[k];
  result.correspondences = last.counts;
  result.residual_rms = std::sqrt(last.kept_squared_sum / std::max<Index>(1, last.counts.kept));
  result.residual_max = last.kept_max;
  result.correspondence_updates = pass.updates();
  cascade.ToInput(state.positions, result.run.positions, context);
  result.run.timings.total = total.Seconds();
  return result;
}

}  // namespace harap
