// SPDX-License-Identifier: MIT
// The compiled part of the Python package `harap` (harap._harap): converts numpy arrays to and
// from harap's types and calls the library (api/deform.h, api/library.h,
// api/session.h, io/). No algorithm lives here; python/harap/__init__.py is the
// public API.
//
// Threads and signals: a solve runs on a worker thread with the GIL released. The calling thread
// waits; after every iteration (and every 20 ms) it takes the GIL, runs Python's signal handlers
// (PyErr_CheckSignals works only on the main thread) and the per-iteration Python callback, so
// the callback runs on the caller's thread. A handler that raises (Ctrl-C: KeyboardInterrupt), a
// callback that raises or returns False ends the solve after its current iteration
// (CallbackAction::kStop); the exception is raised once the worker has finished.
#include <fmt/format.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <optional>
#include <thread>

#include "api/builtins.h"
#include "api/deform.h"
#include "api/library.h"
#include "api/presets.h"
#include "api/register.h"
#include "api/session.h"
#include "framework/error.h"
#include "framework/stiffness.h"
#include "io/builtin_meshes.h"
#include "io/mesh_io.h"
#include "io/mesh_writers.h"
#include "io/scenario.h"
#include "view/page_session.h"
#include "view/server.h"

namespace py = pybind11;

namespace harap {
namespace {

py::exception<Error>* g_error = nullptr;
py::exception<ConfigError>* g_config_error = nullptr;
py::exception<InputError>* g_input_error = nullptr;
py::exception<NumericalError>* g_numerical_error = nullptr;
py::exception<InternalError>* g_internal_error = nullptr;

// Options arrive from Python as (dotted key, TOML value literal) pairs, in order.
using Settings = std::vector<std::pair<std::string, std::string>>;

// A run config from settings; errors name "<options>" and the key, as config files name theirs.
// A `preset` key (the keyword `preset=`) is applied as a config file's top-level one is: its
// settings fill in what the others leave unset.
ConfigNode ConfigFromSettings(const Settings& settings) {
  ConfigNode config = ConfigNode::Parse("", "<options>");
  for (const auto& [key, literal] : settings) config.Set(key, literal);
  ApplyPreset(config, "");
  return config;
}

const Registries& BuiltinRegistries() {
  static const Registries registries = MakeBuiltinRegistries();
  return registries;
}

// numpy.asarray(object): lists, tuples and any array-like; arrays pass through unchanged.
py::array AsArray(py::handle object, const std::string& name) {
  py::object numpy = py::module_::import("numpy");
  try {
    return numpy.attr("asarray")(object);
  } catch (py::error_already_set& error) {
    throw InputError(fmt::format("{}: not convertible to an array ({})", name, error.what()));
  }
}

std::string ShapeText(const py::array& array) {
  std::string text = "(";
  for (py::ssize_t d = 0; d < array.ndim(); ++d) {
    text += fmt::format("{}{}", d ? ", " : "", array.shape(d));
  }
  return text + (array.ndim() == 1 ? ",)" : ")");
}

std::string DtypeText(const py::array& array) { return py::str(array.dtype()).cast<std::string>(); }

// An (n, 3) array of real numbers (any float or integer dtype, any memory layout: copied).
Positions ToPositions(py::handle object, const std::string& name) {
  const py::array array = AsArray(object, name);
  if (array.size() == 0 && array.ndim() <= 2 &&
      (array.ndim() < 2 || array.shape(1) == 3 || array.shape(1) == 0)) {
    return Positions(0, 3);
  }
  const char kind = array.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u') {
    throw InputError(
        fmt::format("{} must hold real numbers (a float or integer dtype), got dtype "
                    "{}",
                    name, DtypeText(array)));
  }
  if (array.ndim() != 2 || array.shape(1) != 3) {
    throw InputError(
        fmt::format("{} must be an (n, 3) array, got shape {}", name, ShapeText(array)));
  }
  if (array.shape(0) > INT_MAX) throw InputError(fmt::format("{}: too many rows", name));
  const auto values = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(array);
  if (!values) throw InputError(fmt::format("{}: cannot convert to float64", name));
  const auto view = values.unchecked<2>();
  Positions positions(static_cast<Index>(view.shape(0)), 3);
  for (py::ssize_t i = 0; i < view.shape(0); ++i) {
    for (int d = 0; d < 3; ++d) positions(static_cast<Index>(i), d) = view(i, d);
  }
  return positions;
}

// Stiffness factors: a 1-D array with one factor per element of `mesh`, or one per vertex
// (converted: each element the mean of its vertices'; framework/stiffness.h). None: empty.
std::vector<double> ToStiffness(py::handle object, const Mesh& mesh) {
  if (object.is_none()) return {};
  const py::array array = AsArray(object, "stiffness");
  const char kind = array.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u') {
    throw InputError(
        fmt::format("stiffness must hold real numbers, got dtype {}", DtypeText(array)));
  }
  const bool per_element = array.ndim() == 1 && array.shape(0) == mesh.num_elements();
  const bool per_vertex = array.ndim() == 1 && array.shape(0) == mesh.num_vertices();
  if (!per_element && !per_vertex) {
    throw InputError(
        fmt::format("stiffness must be a 1-D array with one factor per element ({}) "
                    "or per vertex ({}), got shape {}",
                    mesh.num_elements(), mesh.num_vertices(), ShapeText(array)));
  }
  const auto values = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(array);
  if (!values) throw InputError("stiffness: cannot convert to float64");
  const auto view = values.unchecked<1>();
  std::vector<double> factors(static_cast<size_t>(view.shape(0)));
  for (py::ssize_t k = 0; k < view.shape(0); ++k) factors[static_cast<size_t>(k)] = view(k);
  if (per_element) {
    ValidateStiffness(factors, mesh, "stiffness");
    return factors;
  }
  for (size_t v = 0; v < factors.size(); ++v) {
    if (!std::isfinite(factors[v]) || factors[v] <= 0.0) {
      throw InputError(
          fmt::format("stiffness: the factor of vertex {} is {}; factors must be finite and > 0", v,
                      factors[v]));
    }
  }
  return ElementStiffness(mesh, factors);
}

// Per-handle-vertex weights (None: every handle hard): a 1-D real array of `count` values, each
// > 0; inf marks a hard handle (ScenarioFromArrays checks the values).
std::vector<double> ToWeights(py::handle object, size_t count) {
  if (object.is_none()) return {};
  const py::array array = AsArray(object, "weights");
  const char kind = array.dtype().kind();
  if ((kind != 'f' && kind != 'i' && kind != 'u') || array.ndim() != 1 ||
      static_cast<size_t>(array.shape(0)) != count) {
    throw InputError(fmt::format(
        "weights must be a 1-D array of real numbers, one per handle ({}), got dtype {} shape {}",
        count, DtypeText(array), ShapeText(array)));
  }
  const auto values = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(array);
  if (!values) throw InputError("weights: cannot convert to float64");
  return std::vector<double>(values.data(), values.data() + values.size());
}

// An integer array (any integer dtype and layout) as int64.
py::array_t<long long, py::array::c_style | py::array::forcecast> ToIntegers(
    const py::array& array, const std::string& name) {
  const char kind = array.dtype().kind();
  if (kind != 'i' && kind != 'u') {
    throw InputError(fmt::format("{} must hold integers, got dtype {}", name, DtypeText(array)));
  }
  auto values = py::array_t<long long, py::array::c_style | py::array::forcecast>::ensure(array);
  if (!values) throw InputError(fmt::format("{}: cannot convert to int64", name));
  return values;
}

Elements ToElements(py::handle object, const std::string& name) {
  const py::array array = AsArray(object, name);
  if (array.ndim() != 2 || (array.shape(1) != 3 && array.shape(1) != 4)) {
    throw InputError(
        fmt::format("{} must be an (m, 3) array of triangles or an (m, 4) array of "
                    "tetrahedra, got shape {}",
                    name, ShapeText(array)));
  }
  if (array.size() == 0) return Elements(0, array.shape(1));
  const auto values = ToIntegers(array, name);
  const auto view = values.unchecked<2>();
  Elements elements(static_cast<Index>(view.shape(0)), static_cast<Index>(view.shape(1)));
  for (py::ssize_t e = 0; e < view.shape(0); ++e) {
    for (py::ssize_t a = 0; a < view.shape(1); ++a) {
      const long long v = view(e, a);
      if (v < INT_MIN || v > INT_MAX) {
        throw InputError(
            fmt::format("{}: element {} references vertex {}, which is out of range", name, e, v));
      }
      elements(static_cast<Index>(e), static_cast<Index>(a)) = static_cast<Index>(v);
    }
  }
  return elements;
}

std::vector<Index> ToIndices(py::handle object, const std::string& name) {
  const py::array array = AsArray(object, name);
  if (array.size() == 0 && array.ndim() == 1) return {};
  if (array.ndim() != 1) {
    throw InputError(fmt::format("{} must be a 1-D array of vertex indices, got shape {}", name,
                                 ShapeText(array)));
  }
  const auto values = ToIntegers(array, name);
  const auto view = values.unchecked<1>();
  std::vector<Index> indices(static_cast<size_t>(view.shape(0)));
  for (py::ssize_t k = 0; k < view.shape(0); ++k) {
    const long long v = view(k);
    if (v < INT_MIN || v > INT_MAX) {
      throw InputError(fmt::format("{}: vertex {} (row {}) is out of range", name, v, k));
    }
    indices[static_cast<size_t>(k)] = static_cast<Index>(v);
  }
  return indices;
}

py::array_t<double> FromPositions(const Positions& positions) {
  py::array_t<double> array({static_cast<py::ssize_t>(positions.rows()), py::ssize_t{3}});
  auto view = array.mutable_unchecked<2>();
  for (Index i = 0; i < positions.rows(); ++i) {
    for (int d = 0; d < 3; ++d) view(i, d) = positions(i, d);
  }
  return array;
}

py::array_t<long long> FromElements(const Elements& elements) {
  py::array_t<long long> array(
      {static_cast<py::ssize_t>(elements.rows()), static_cast<py::ssize_t>(elements.cols())});
  auto view = array.mutable_unchecked<2>();
  for (Index e = 0; e < elements.rows(); ++e) {
    for (Index a = 0; a < elements.cols(); ++a) view(e, a) = elements(e, a);
  }
  return array;
}

template <class T>
py::array_t<long long> FromVector(const std::vector<T>& values) {
  py::array_t<long long> array(static_cast<py::ssize_t>(values.size()));
  auto view = array.mutable_unchecked<1>();
  for (size_t k = 0; k < values.size(); ++k) view(static_cast<py::ssize_t>(k)) = values[k];
  return array;
}

Mesh ToMesh(py::handle V, py::handle F) {
  Mesh mesh;
  mesh.vertices = ToPositions(V, "V");
  mesh.elements = ToElements(F, "F");
  return mesh;
}

std::optional<Positions> ToOptionalPositions(py::handle object, const std::string& name) {
  if (object.is_none()) return std::nullopt;
  return ToPositions(object, name);
}

void CheckThreads(int threads) {
  if (threads < 0)
    throw ConfigError(fmt::format("threads must be >= 0 (0: all cores), got {}", threads));
}

void CheckCallback(const py::object& callback) {
  if (!callback.is_none() && !PyCallable_Check(callback.ptr())) {
    throw ConfigError("callback must be callable as callback(level, iteration, energy) or None");
  }
}

// A solve on a worker thread, watched by the calling thread (see the top of the file). The
// worker reports every iteration (OnIteration, the optimizer's progress callback); the calling
// thread, woken by each report and at least every 20 ms, takes the GIL, runs Python's signal
// handlers and then the Python callback, if any, for that iteration, while the worker waits for
// its answer (without a callback the worker does not wait). A handler or callback that raises, or
// a callback returning False, makes the next answer kStop.
class WatchedSolve {
 public:
  explicit WatchedSolve(py::object callback) : callback_(std::move(callback)) {}

  // Worker thread.
  CallbackAction OnIteration(const IterationSummary& summary) {
    std::unique_lock lock(mutex_);
    if (stop_) return CallbackAction::kStop;
    if (!callback_.is_none()) {
      answered_.wait(lock, [&] { return !pending_; });  // one report at a time
      if (stop_) return CallbackAction::kStop;
      pending_ = summary;
      changed_.notify_all();
      answered_.wait(lock, [&] { return !pending_; });
    } else {
      ++iterations_;
      changed_.notify_all();
    }
    return stop_ ? CallbackAction::kStop : CallbackAction::kContinue;
  }

  // Calling thread, GIL held: runs `work` on the worker; raises the Python exception that stopped
  // it, else rethrows the exception `work` threw.
  template <class Work>
  void Run(Work&& work) {
    std::exception_ptr failure;
    {
      py::gil_scoped_release release;
      std::thread worker([&] {
        try {
          work();
        } catch (...) {
          failure = std::current_exception();
        }
        std::lock_guard lock(mutex_);
        done_ = true;
        changed_.notify_all();
      });
      Watch();
      worker.join();
    }
    if (python_error_) throw std::move(*python_error_);
    if (callback_failure_) std::rethrow_exception(callback_failure_);
    if (failure) std::rethrow_exception(failure);
  }

 private:
  // Calling thread, GIL released.
  void Watch() {
    std::unique_lock lock(mutex_);
    long long seen = iterations_;
    while (true) {
      changed_.wait_for(lock, std::chrono::milliseconds(20),
                        [&] { return done_ || pending_ || iterations_ != seen; });
      if (done_) return;
      seen = iterations_;
      const std::optional<IterationSummary> summary = pending_;
      lock.unlock();
      const bool stop = CheckSignalsAndCall(summary);
      lock.lock();
      if (stop) stop_ = true;
      if (summary) {
        pending_.reset();
        answered_.notify_all();
      }
    }
  }

  // Calling thread: takes the GIL; true if the solve must stop.
  bool CheckSignalsAndCall(const std::optional<IterationSummary>& summary) {
    py::gil_scoped_acquire acquire;
    if (python_error_ || callback_failure_) return true;
    if (PyErr_CheckSignals() != 0) {
      python_error_.emplace();  // fetches the handler's exception (KeyboardInterrupt)
      return true;
    }
    if (!summary) return false;
    try {
      const py::object answer = callback_(summary->level, summary->iteration, summary->energy);
      return answer.is(py::bool_(false));
    } catch (py::error_already_set& error) {
      python_error_.emplace(std::move(error));
    } catch (...) {
      callback_failure_ = std::current_exception();
    }
    return true;
  }

  py::object callback_;
  std::mutex mutex_;
  std::condition_variable changed_;   // worker → calling thread: an iteration, or done
  std::condition_variable answered_;  // calling thread → worker: pending_ handled
  std::optional<IterationSummary> pending_;
  long long iterations_ = 0;
  bool done_ = false;
  bool stop_ = false;
  // Only touched with the GIL held, on the calling thread.
  std::optional<py::error_already_set> python_error_;
  std::exception_ptr callback_failure_;
};

// harap._harap.deform: (positions, report JSON text, stopped by the callback).
py::tuple Deform(py::handle V, py::handle F, py::handle handles, py::handle targets,
                 const Settings& settings, py::handle initial, std::optional<bool> planar,
                 py::object callback, int threads, bool trace, py::handle stiffness,
                 py::handle weights) {
  CheckThreads(threads);
  CheckCallback(callback);
  const ConfigNode config = ConfigFromSettings(settings);
  Mesh mesh = ToMesh(V, F);
  const std::vector<Index> handle_vertices = ToIndices(handles, "handles");
  const Positions handle_targets = ToPositions(targets, "targets");
  const Scenario scenario = ScenarioFromArrays(
      std::move(mesh), handle_vertices, handle_targets, ToOptionalPositions(initial, "initial"),
      planar, "arrays V, F", ToWeights(weights, handle_vertices.size()));

  WatchedSolve solve(std::move(callback));
  DeformOptions options;
  options.threads = threads;
  options.stiffness = ToStiffness(stiffness, scenario.mesh);
  options.progress = [&](const IterationSummary& summary) { return solve.OnIteration(summary); };
  DeformOutcome outcome;
  solve.Run([&] { outcome = RunDeform(BuiltinRegistries(), scenario, config, options); });
  return py::make_tuple(FromPositions(outcome.result.positions),
                        DeformReportJson(scenario, outcome, trace),
                        outcome.result.stopped_by_callback);
}

// harap._harap.register_: (positions, distance, report JSON text, stopped by the callback).
py::tuple RegisterArrays(py::handle V, py::handle F, py::handle target_points,
                         py::handle target_faces, py::handle target_normals,
                         py::handle landmark_vertices, py::handle landmark_points,
                         const Settings& settings, py::object callback, int threads,
                         py::handle stiffness) {
  CheckThreads(threads);
  CheckCallback(callback);
  const ConfigNode config = ConfigFromSettings(settings);
  const Mesh source = ToMesh(V, F);
  RegistrationTarget target;
  target.name = "arrays";
  if (!target_faces.is_none()) {
    target.mesh = ToMesh(target_points, target_faces);
  } else {
    target.points = ToPositions(target_points, "target");
    if (!target_normals.is_none()) target.normals = ToPositions(target_normals, "normals");
  }
  RegisterOptions options;
  options.threads = threads;
  options.stiffness = ToStiffness(stiffness, source);
  if (!landmark_vertices.is_none()) {
    options.landmarks.indices = ToIndices(landmark_vertices, "landmarks");
    options.landmarks.targets = ToPositions(landmark_points, "landmark_targets");
    if (options.landmarks.targets.rows() != static_cast<Index>(options.landmarks.indices.size())) {
      throw InputError(fmt::format("{} landmarks but {} landmark_targets",
                                   options.landmarks.indices.size(),
                                   options.landmarks.targets.rows()));
    }
  }
  WatchedSolve solve(std::move(callback));
  options.progress = [&](const IterationSummary& summary) { return solve.OnIteration(summary); };
  RegisterOutcome outcome;
  solve.Run([&] { outcome = RunRegister(BuiltinRegistries(), source, target, config, options); });
  py::array_t<double> distance(static_cast<py::ssize_t>(outcome.result.distance.size()));
  std::copy(outcome.result.distance.begin(), outcome.result.distance.end(),
            distance.mutable_data());
  return py::make_tuple(FromPositions(outcome.result.run.positions), distance,
                        RegisterReportJson("arrays", source, target, outcome),
                        outcome.result.run.stopped_by_callback);
}

// harap._harap.Session: a ConfiguredSession (api/session.h) driven from Python. The calls
// that compute (construction, handle edits, solves, the energy) run without the GIL; solves run
// as WatchedSolve does for deform (signals and the callback on the calling thread). The C++
// session checks every call before changing anything, so a call that raises leaves the session
// as it was. A session is not thread-safe: a call while another thread is inside one raises
// harap.Error instead of racing.
class PySession {
 public:
  PySession(py::handle V, py::handle F, const Settings& settings, py::handle initial,
            std::optional<bool> planar, int threads, const std::string& frame_start) {
    CheckThreads(threads);
    const ConfigNode config = ConfigFromSettings(settings);
    const SessionOptions::FrameStart start = SessionOptions::ParseFrameStart(frame_start);
    // Checks the arrays and decides `planar` as deform does (no handles yet: from V and initial).
    scenario_ = ScenarioFromArrays(ToMesh(V, F), {}, Positions(0, 3),
                                   ToOptionalPositions(initial, "initial"), planar, "arrays V, F");
    py::gil_scoped_release release;
    owned_ = MakeSession(BuiltinRegistries(), scenario_.mesh, config, threads, start);
    if (scenario_.initial) owned_->session().SetPositions(*scenario_.initial);
  }

  // `weights` as harap.deform's (ToWeights: None, or one per handle vertex; the session checks
  // the values and names a bad entry).
  std::string SetHandles(py::handle indices, py::handle targets, py::handle weights) {
    const Use use(*this);
    const std::vector<Index> handles = ToIndices(indices, "indices");
    const std::optional<Positions> positions = ToOptionalPositions(targets, "targets");
    const std::vector<double> handle_weights = ToWeights(weights, handles.size());
    return Edit([&] {
      if (handle_weights.empty()) {
        return positions ? session().SetHandles(handles, *positions)
                         : session().SetHandles(handles);
      }
      return positions ? session().SetHandles(handles, *positions, handle_weights)
                       : session().SetHandles(handles, handle_weights);
    });
  }

  std::string AddHandles(py::handle indices, py::handle targets) {
    const Use use(*this);
    const std::vector<Index> handles = ToIndices(indices, "indices");
    const Positions positions = ToPositions(targets, "targets");
    return Edit([&] { return session().AddHandles(handles, positions); });
  }

  std::string RemoveHandles(py::handle indices) {
    const Use use(*this);
    const std::vector<Index> handles = ToIndices(indices, "indices");
    return Edit([&] { return session().RemoveHandles(handles); });
  }

  void SetTargets(py::handle targets) {
    const Use use(*this);
    session().SetTargets(ToPositions(targets, "targets"));
  }

  void SetPositions(py::handle positions) {
    const Use use(*this);
    session().SetPositions(ToPositions(positions, "positions"));
  }

  // (positions, report JSON text, stopped by the callback), as deform returns.
  py::tuple Solve(double tolerance, int max_iterations, double time_budget, py::object callback,
                  bool trace) {
    const Use use(*this);
    SessionSolveOptions options;
    options.tolerance = tolerance;
    options.max_iterations = max_iterations;
    options.time_budget_seconds = time_budget;
    return Watch(std::move(callback), trace, [&] { return session().Solve(options); });
  }

  py::tuple Preview(py::object callback, bool trace) {
    const Use use(*this);
    return Watch(std::move(callback), trace, [&] { return session().Preview(); });
  }

  double Energy() {
    const Use use(*this);
    py::gil_scoped_release release;
    return session().CurrentEnergy();
  }

  py::array_t<double> positions() {
    const Use use(*this);
    return FromPositions(session().positions());
  }
  py::array_t<long long> handles() {
    const Use use(*this);
    return FromVector(session().handles());
  }
  py::array_t<double> targets() {
    const Use use(*this);
    return FromPositions(session().targets());
  }
  // One per handle (inf: hard); all inf when every handle is hard.
  py::array_t<double> weights() {
    const Use use(*this);
    const std::vector<double>& weights = session().weights();
    py::array_t<double> array(static_cast<py::ssize_t>(session().handles().size()));
    auto view = array.mutable_unchecked<1>();
    for (py::ssize_t k = 0; k < array.shape(0); ++k) {
      view(k) = weights.empty() ? Constraints::kHardWeight : weights[static_cast<size_t>(k)];
    }
    return array;
  }
  int num_levels() {
    const Use use(*this);
    return session().num_levels();
  }

  // What the session resolved and its setup: names, solved levels, H and P seconds, the config.
  py::dict Info() {
    const Use use(*this);
    const RegistryComponentFactory& factory = owned_->factory();
    py::dict info;
    info["optimizer"] = owned_->optimizer();
    info["energy"] = owned_->energy_name();
    info["solver"] = owned_->solver_name();
    info["hierarchy"] = factory.made_hierarchy() ? py::object(py::str(factory.hierarchy_name()))
                                                 : py::object(py::none());
    info["upsampler"] = factory.made_upsampler() ? py::object(py::str(factory.upsampler_name()))
                                                 : py::object(py::none());
    info["solved_levels"] = session().solved_levels();
    info["threads"] = owned_->threads();
    info["planar"] = scenario_.mesh.planar;
    info["setup_timings"] = py::dict(py::arg("hierarchy") = session().setup_timings().hierarchy,
                                     py::arg("precompute") = session().setup_timings().precompute);
    info["mesh_summary"] = owned_->mesh_summary();
    info["config"] = owned_->resolved_config();
    return info;
  }

 private:
  // Marks the session in use for one call (the GIL serializes the marking itself).
  class Use {
   public:
    explicit Use(PySession& owner) : owner_(owner) {
      if (owner_.busy_) {
        throw Error(
            "this harap.Session is in use by another thread (a session is not "
            "thread-safe: give each thread its own)");
      }
      owner_.busy_ = true;
    }
    ~Use() { owner_.busy_ = false; }
    Use(const Use&) = delete;
    Use& operator=(const Use&) = delete;

   private:
    PySession& owner_;
  };

  DeformationSession& session() { return owned_->session(); }

  template <class Work>
  std::string Edit(Work&& work) {
    HandleEditResult edit;
    {
      py::gil_scoped_release release;
      edit = work();
    }
    return HandleEditJson(edit);
  }

  template <class Work>
  py::tuple Watch(py::object callback, bool trace, Work&& work) {
    CheckCallback(callback);
    WatchedSolve solve(std::move(callback));
    std::vector<TraceEntry> entries;
    session().set_iteration_callback([&](const IterationSummary& summary) {
      entries.push_back(
          {summary.seconds, summary.energy, summary.level, summary.inverted_elements});
      return solve.OnIteration(summary);
    });
    // The callback refers to this frame's locals: unset it however the solve ends.
    struct Unset {
      DeformationSession& session;
      ~Unset() { session.set_iteration_callback({}); }
    } unset{session()};
    OptimizeResult result;
    solve.Run([&] { result = work(); });
    // The report's handles: the session's current ones, as one group.
    scenario_.handles.assign(1, ScenarioHandle{});
    scenario_.handles[0].name = "handles";
    scenario_.handles[0].vertices = session().handles();
    const bool stopped = result.stopped_by_callback;
    const DeformOutcome outcome =
        SessionOutcome(*owned_, scenario_, std::move(result), std::move(entries));
    return py::make_tuple(FromPositions(outcome.result.positions),
                          DeformReportJson(scenario_, outcome, trace), stopped);
  }

  Scenario scenario_;  // the input mesh (for the report) and the initial positions
  std::unique_ptr<ConfiguredSession> owned_;
  bool busy_ = false;
};

py::tuple ReadMeshArrays(const std::string& path) {
  Mesh mesh;
  {
    py::gil_scoped_release release;
    mesh = ReadMesh(path);
  }
  return py::make_tuple(FromPositions(mesh.vertices), FromElements(mesh.elements));
}

void WriteMeshArrays(const std::string& path, py::handle V, py::handle F) {
  Mesh mesh = ToMesh(V, F);
  ValidateMesh(mesh, path);
  const std::string extension = std::filesystem::path(path).extension().string();
  if (extension != ".ply" && extension != ".PLY") {
    throw InputError(
        fmt::format("{}: write_mesh writes binary PLY (double coordinates) only; "
                    "name the file .ply",
                    path));
  }
  py::gil_scoped_release release;
  WritePly(path, mesh.vertices, mesh.elements);
}

py::dict ScenarioDict(const Scenario& scenario) {
  const Constraints merged = scenario.MergedConstraints();
  py::list groups;
  for (const ScenarioHandle& handle : scenario.handles) {
    py::dict group;
    group["name"] = handle.name;
    group["vertices"] = FromVector(handle.vertices);
    group["targets"] = FromPositions(handle.targets);
    groups.append(group);
  }
  py::dict result;
  result["V"] = FromPositions(scenario.mesh.vertices);
  result["F"] = FromElements(scenario.mesh.elements);
  result["handles"] = FromVector(merged.indices);
  result["targets"] = FromPositions(merged.targets);
  result["initial"] = scenario.initial ? py::object(FromPositions(*scenario.initial)) : py::none();
  result["planar"] = scenario.mesh.planar;
  result["handle_groups"] = groups;
  result["mesh_source"] = scenario.mesh_source;
  result["notes"] = scenario.notes;
  return result;
}

py::dict LoadScenarioArrays(const std::string& path) {
  Scenario scenario;
  {
    py::gil_scoped_release release;
    scenario = LoadScenario(path);
  }
  return ScenarioDict(scenario);
}

py::tuple BuiltinMeshArrays(const Settings& settings) {
  const ConfigNode config = ConfigFromSettings(settings);
  const Mesh mesh = MakeBuiltinMesh(config);
  return py::make_tuple(FromPositions(mesh.vertices), FromElements(mesh.elements), mesh.planar);
}

py::list HierarchyLevels(py::handle V, py::handle F, const Settings& settings,
                         std::optional<bool> planar, int threads) {
  CheckThreads(threads);
  const ConfigNode config = ConfigFromSettings(settings);
  const Scenario scenario =
      ScenarioFromArrays(ToMesh(V, F), {}, Positions(0, 3), std::nullopt, planar, "arrays V, F");
  MeshHierarchy hierarchy;
  {
    py::gil_scoped_release release;
    hierarchy = BuildHierarchy(BuiltinRegistries(), scenario.mesh, config, threads);
  }
  py::list levels;
  for (const HierarchyLevel& level : hierarchy.levels) {
    py::dict entry;
    entry["vertices"] = FromPositions(level.mesh.vertices);
    entry["elements"] = FromElements(level.mesh.elements);
    entry["coarse_vertex"] = level.coarse_vertex.empty()
                                 ? py::object(py::none())
                                 : py::object(FromVector(level.coarse_vertex));
    entry["in_cluster"] = level.in_cluster.empty() ? py::object(py::none())
                                                   : py::object(FromVector(level.in_cluster));
    levels.append(entry);
  }
  return levels;
}

py::tuple EnergyValue(py::handle V, py::handle F, py::handle U, const Settings& settings,
                      std::optional<bool> planar, int threads) {
  CheckThreads(threads);
  const ConfigNode config = ConfigFromSettings(settings);
  const Positions u = ToPositions(U, "U");
  // The scenario builder checks the mesh and decides `planar` as for a scenario whose start
  // configuration is U.
  const Scenario scenario =
      ScenarioFromArrays(ToMesh(V, F), {}, Positions(0, 3), u, planar, "arrays V, F");
  EnergyEvaluation evaluation;
  {
    py::gil_scoped_release release;
    evaluation = EvaluateEnergy(BuiltinRegistries(), scenario.mesh, u, config, threads);
  }
  py::array_t<double> rotations(
      {static_cast<py::ssize_t>(evaluation.rotations.size()), py::ssize_t{3}, py::ssize_t{3}});
  auto view = rotations.mutable_unchecked<3>();
  for (size_t s = 0; s < evaluation.rotations.size(); ++s) {
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j)
        view(static_cast<py::ssize_t>(s), i, j) = evaluation.rotations[s](i, j);
    }
  }
  return py::make_tuple(evaluation.value, FromPositions(evaluation.gradient), rotations,
                        evaluation.per_element, scenario.mesh.planar);
}

py::list OptionList(const std::vector<OptionInfo>& options) {
  py::list list;
  for (const OptionInfo& option : options) {
    list.append(py::make_tuple(option.key, option.default_value, option.help));
  }
  return list;
}

py::dict Components() {
  const ComponentCatalog catalog = DescribeComponents(BuiltinRegistries());
  py::list components;
  for (const ComponentDescription& component : catalog.components) {
    components.append(py::make_tuple(component.kind, component.name, component.description,
                                     OptionList(component.options)));
  }
  py::dict result;
  result["components"] = components;
  result["small_systems"] = OptionList(catalog.small_systems_options);
  result["mesh"] = OptionList(catalog.mesh_options);
  result["registration"] = OptionList(catalog.registration_options);
  result["builtin_meshes"] = catalog.builtin_meshes;
  return result;
}

py::list PresetList() {
  py::list list;
  for (const Preset& preset : Presets()) {
    list.append(py::make_tuple(preset.name, preset.description, preset.settings,
                               preset.hierarchical_settings, preset.local_global_settings));
  }
  return list;
}

// The handle groups the page drags one by one: as given (`group_sizes` consecutive rows of
// `vertices`, named `group_names`), or, with no sizes, each connected set of handle vertices
// (edges of the mesh's elements) with one weight one group. Vertices ascending in each group, as
// a scenario's. `weights`: empty (all hard) or one per vertex, the same in each given group.
std::vector<ScenarioHandle> HandleGroups(const Mesh& mesh, const std::vector<Index>& vertices,
                                         const Positions& targets,
                                         const std::vector<int>& group_sizes,
                                         const std::vector<std::string>& group_names,
                                         const std::vector<double>& weights) {
  const auto weight = [&](size_t k) {
    return weights.empty() ? Constraints::kHardWeight : weights[k];
  };
  std::vector<int> group_of(vertices.size(), 0);
  int num_groups = 0;
  if (!group_sizes.empty()) {
    size_t row = 0;
    for (const int size : group_sizes) {
      for (int i = 0; i < size && row < vertices.size(); ++i) {
        if (weight(row) != weight(row - i)) {
          throw InputError(fmt::format(
              "handle group {} mixes weights ({} and {}): a group the page drags has one weight",
              num_groups + 1, weight(row - i), weight(row)));
        }
        group_of[row++] = num_groups;
      }
      ++num_groups;
    }
    if (row != vertices.size()) throw InputError("the handle groups' sizes do not add up");
  } else if (!vertices.empty()) {
    std::vector<Index> row_of(static_cast<size_t>(mesh.num_vertices()), -1);
    for (size_t k = 0; k < vertices.size(); ++k) row_of[vertices[k]] = static_cast<Index>(k);
    std::vector<Index> parent(vertices.size());
    for (size_t k = 0; k < parent.size(); ++k) parent[k] = static_cast<Index>(k);
    const auto find = [&](Index k) {
      while (parent[k] != k) k = parent[k] = parent[parent[k]];
      return k;
    };
    for (Eigen::Index e = 0; e < mesh.elements.rows(); ++e) {
      for (Eigen::Index a = 0; a < mesh.elements.cols(); ++a) {
        for (Eigen::Index b = a + 1; b < mesh.elements.cols(); ++b) {
          const Index ra = row_of[mesh.elements(e, a)], rb = row_of[mesh.elements(e, b)];
          if (ra >= 0 && rb >= 0 && weight(ra) == weight(rb)) parent[find(ra)] = find(rb);
        }
      }
    }
    std::vector<int> number(vertices.size(), -1);
    for (size_t k = 0; k < vertices.size(); ++k) {
      const Index root = find(static_cast<Index>(k));
      if (number[root] < 0) number[root] = num_groups++;
      group_of[k] = number[root];
    }
  }
  std::vector<ScenarioHandle> groups(static_cast<size_t>(num_groups));
  std::vector<std::vector<size_t>> rows(groups.size());
  for (size_t k = 0; k < vertices.size(); ++k) rows[group_of[k]].push_back(k);
  for (size_t g = 0; g < groups.size(); ++g) {
    std::sort(rows[g].begin(), rows[g].end(),
              [&](size_t a, size_t b) { return vertices[a] < vertices[b]; });
    groups[g].name = g < group_names.size() ? group_names[g] : fmt::format("handle {}", g + 1);
    if (!rows[g].empty()) groups[g].weight = weight(rows[g].front());
    groups[g].targets.resize(static_cast<Eigen::Index>(rows[g].size()), 3);
    for (size_t i = 0; i < rows[g].size(); ++i) {
      groups[g].vertices.push_back(vertices[rows[g][i]]);
      groups[g].targets.row(static_cast<Eigen::Index>(i)) =
          targets.row(static_cast<Eigen::Index>(rows[g][i]));
    }
  }
  std::erase_if(groups, [](const ScenarioHandle& group) { return group.vertices.empty(); });
  return groups;
}

// harap._harap.View: the page of `harap view` (view/server.h) served from a thread of its own
// until stop(); each page that connects solves in a session of its own, as with `harap view`.
class PyView {
 public:
  PyView(py::handle V, py::handle F, py::handle handles, py::handle targets, py::handle weights,
         const std::vector<int>& group_sizes, const std::vector<std::string>& group_names,
         const Settings& settings, std::optional<bool> planar, int threads, const std::string& host,
         int port, const std::string& assets, int display_vertices) {
    CheckThreads(threads);
    if (port < 0 || port > 65535)
      throw InputError(fmt::format("port must be in 0..65535 (0: any free port), got {}", port));
    if (display_vertices < 3)
      throw InputError(
          fmt::format("display_vertices must be at least 3, got {}", display_vertices));
    source_ = std::make_unique<view::ViewSource>();
    source_->run_config = ConfigFromSettings(settings);
    const std::vector<Index> vertices = ToIndices(handles, "handles");
    const Positions positions = ToPositions(targets, "targets");
    const std::vector<double> handle_weights = ToWeights(weights, vertices.size());
    source_->scenario = ScenarioFromArrays(ToMesh(V, F), vertices, positions, std::nullopt, planar,
                                           "arrays V, F", handle_weights);
    source_->scenario.handles = HandleGroups(source_->scenario.mesh, vertices, positions,
                                             group_sizes, group_names, handle_weights);
    // The exported scenario needs a mesh file: arrays have none.
    source_->mesh_toml =
        "# The mesh came from Python arrays: write it with harap.write_mesh and name the file\n"
        "# here (mesh = \"FILE\") for harap deform.\n";
    source_->threads = threads;
    source_->display_vertices = display_vertices;
    view::ServerOptions options;
    options.host = host;
    options.port = static_cast<uint16_t>(port);
    options.assets = assets;
    options.stop_on_signals = false;  // Ctrl-C stays Python's KeyboardInterrupt
    server_ = std::make_unique<view::Server>(options, BuiltinRegistries(), *source_);
    thread_ = std::thread([this] { server_->Run(); });
  }
  ~PyView() {
    if (thread_.joinable()) {
      server_->Stop();
      thread_.join();
    }
  }
  PyView(const PyView&) = delete;
  PyView& operator=(const PyView&) = delete;

  int port() const { return server_->port(); }
  bool running() const { return thread_.joinable(); }
  /// Stops serving: open pages are closed after their current message.
  void Stop() {
    if (!thread_.joinable()) return;
    py::gil_scoped_release release;
    server_->Stop();
    thread_.join();
  }

 private:
  std::unique_ptr<view::ViewSource> source_;
  std::unique_ptr<view::Server> server_;
  std::thread thread_;
};

}  // namespace
}  // namespace harap

PYBIND11_MODULE(_harap, m) {
  using namespace harap;
  m.doc() = "harap's compiled core; use the package `harap` (python/harap/__init__.py).";

  // C++ errors become Python exceptions with the same messages: harap.Error (a ValueError) and
  // one subclass per harap::Error subclass. Never destroyed: they live as long as the module.
  g_error = new py::exception<Error>(m, "Error", PyExc_ValueError);
  g_config_error = new py::exception<ConfigError>(m, "ConfigError", g_error->ptr());
  g_input_error = new py::exception<InputError>(m, "InputError", g_error->ptr());
  g_numerical_error = new py::exception<NumericalError>(m, "NumericalError", g_error->ptr());
  g_internal_error = new py::exception<InternalError>(m, "InternalError", g_error->ptr());
  for (const char* name :
       {"Error", "ConfigError", "InputError", "NumericalError", "InternalError"}) {
    m.attr(name).attr("__module__") = "harap";
  }
  py::register_exception_translator([](std::exception_ptr pointer) {
    try {
      if (pointer) std::rethrow_exception(pointer);
    } catch (const ConfigError& e) {
      (*g_config_error)(e.what());
    } catch (const InputError& e) {
      (*g_input_error)(e.what());
    } catch (const NumericalError& e) {
      (*g_numerical_error)(e.what());
    } catch (const InternalError& e) {
      (*g_internal_error)(e.what());
    } catch (const Error& e) {
      (*g_error)(e.what());
    }
  });

  m.def("register_", &RegisterArrays, py::arg("V"), py::arg("F"), py::arg("target"),
        py::arg("target_faces"), py::arg("target_normals"), py::arg("landmarks"),
        py::arg("landmark_targets"), py::arg("settings"), py::arg("callback"), py::arg("threads"),
        py::arg("stiffness"));
  m.def("deform", &Deform, py::arg("V"), py::arg("F"), py::arg("handles"), py::arg("targets"),
        py::arg("settings"), py::arg("initial"), py::arg("planar"), py::arg("callback"),
        py::arg("threads"), py::arg("trace"), py::arg("stiffness"), py::arg("weights"));
  m.def("read_mesh", &ReadMeshArrays, py::arg("path"));
  m.def("write_mesh", &WriteMeshArrays, py::arg("path"), py::arg("V"), py::arg("F"));
  m.def("load_scenario", &LoadScenarioArrays, py::arg("path"));
  m.def("builtin_mesh", &BuiltinMeshArrays, py::arg("settings"));
  m.def("hierarchy", &HierarchyLevels, py::arg("V"), py::arg("F"), py::arg("settings"),
        py::arg("planar"), py::arg("threads"));
  m.def("energy", &EnergyValue, py::arg("V"), py::arg("F"), py::arg("U"), py::arg("settings"),
        py::arg("planar"), py::arg("threads"));
  m.def("components", &Components);
  m.def("presets", &PresetList);
  py::class_<PyView>(m, "View")
      .def(py::init<py::handle, py::handle, py::handle, py::handle, py::handle,
                    const std::vector<int>&, const std::vector<std::string>&, const Settings&,
                    std::optional<bool>, int, const std::string&, int, const std::string&, int>(),
           py::arg("V"), py::arg("F"), py::arg("handles"), py::arg("targets"), py::arg("weights"),
           py::arg("group_sizes"), py::arg("group_names"), py::arg("settings"), py::arg("planar"),
           py::arg("threads"), py::arg("host"), py::arg("port"), py::arg("assets"),
           py::arg("display_vertices"))
      .def("port", &PyView::port)
      .def("running", &PyView::running)
      .def("stop", &PyView::Stop);
  py::class_<PySession>(m, "Session")
      .def(py::init<py::handle, py::handle, const Settings&, py::handle, std::optional<bool>, int,
                    const std::string&>(),
           py::arg("V"), py::arg("F"), py::arg("settings"), py::arg("initial"), py::arg("planar"),
           py::arg("threads"), py::arg("frame_start"))
      .def("set_handles", &PySession::SetHandles, py::arg("indices"), py::arg("targets"),
           py::arg("weights"))
      .def("add_handles", &PySession::AddHandles, py::arg("indices"), py::arg("targets"))
      .def("remove_handles", &PySession::RemoveHandles, py::arg("indices"))
      .def("set_targets", &PySession::SetTargets, py::arg("targets"))
      .def("set_positions", &PySession::SetPositions, py::arg("positions"))
      .def("solve", &PySession::Solve, py::arg("tolerance"), py::arg("max_iterations"),
           py::arg("time_budget"), py::arg("callback"), py::arg("trace"))
      .def("preview", &PySession::Preview, py::arg("callback"), py::arg("trace"))
      .def("energy", &PySession::Energy)
      .def("positions", &PySession::positions)
      .def("handles", &PySession::handles)
      .def("targets", &PySession::targets)
      .def("weights", &PySession::weights)
      .def("num_levels", &PySession::num_levels)
      .def("info", &PySession::Info);
}
