# SPDX-License-Identifier: MIT
"""harap: hierarchical As-Rigid-As-Possible deformation, from Python with numpy arrays.

    import numpy as np, harap
    V, F = harap.builtin_mesh("cylinder", vertices=2000)
    bottom = np.flatnonzero(V[:, 2] < 0.05); top = np.flatnonzero(V[:, 2] > 3.95)
    handles = np.concatenate([bottom, top])
    targets = np.concatenate([V[bottom], V[top] + [0.5, 0.0, 0.0]])
    result = harap.deform(V, F, handles, targets, options={"optimizer.tolerance": 1e-6})
    result.positions            # (n, 3) float64
    result.report["energy"]     # the keys of `harap deform --report` (docs/report.md)

    session = harap.Session(V, F)  # interactive: set up once, then solve frame after frame
    session.set_handles(handles, targets); session.solve(); session.set_targets(targets + 0.1)

Every function calls harap's C++ library (the module harap._harap); options are validated as in
config files (an unknown key fails listing the valid ones), and C++ errors are raised as
harap.Error subclasses (ValueError) with the same messages.
"""

import json as _json
import math as _math
import numbers as _numbers
import pathlib as _pathlib
try:
    import tomllib as _tomllib  # Python 3.11
except ImportError:  # older Pythons: defaults stay TOML text
    _tomllib = None

import numpy as _np

from . import _harap
from ._harap import ConfigError, Error, InputError, InternalError, NumericalError

__all__ = [
    "deform", "DeformResult", "register", "RegisterResult", "Session", "read_mesh", "write_mesh", "load_scenario", "Scenario",
    "builtin_mesh", "view", "View", "hierarchy", "HierarchyLevel", "energy", "EnergyValue", "components",
    "presets",
    "Error", "ConfigError", "InputError", "NumericalError", "InternalError",
]


def _toml_literal(key, value):
    """A Python option value as the TOML literal a config file would hold."""
    if isinstance(value, bool) or isinstance(value, _np.bool_):
        return "true" if value else "false"
    if isinstance(value, _numbers.Integral):
        return str(int(value))
    if isinstance(value, _numbers.Real):
        value = float(value)
        if _math.isnan(value):
            return "nan"
        if _math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)  # shortest text that reads back to the same double
    if isinstance(value, str):
        # A TOML basic string; JSON's escapes are TOML's (ensure_ascii=False: no surrogates).
        return _json.dumps(value, ensure_ascii=False)
    raise ConfigError(f"<options>: option '{key}': unsupported value {value!r} "
                      f"(give a bool, number or string)")


def _settings(options, prefix=""):
    """Flattens {"optimizer.tolerance": 1e-6, "energy": {"lambda": 0.5}} into (dotted key,
    TOML literal) pairs, in order."""
    if options is None:
        return []
    if not isinstance(options, dict):
        raise ConfigError(f"options must be a dict of option keys to values, got {options!r}")
    pairs = []
    for key, value in options.items():
        if not isinstance(key, str):
            raise ConfigError(f"<options>: option keys must be strings, got {key!r}")
        full = f"{prefix}{key}"
        if isinstance(value, dict):
            pairs.extend(_settings(value, full + "."))
        else:
            pairs.append((full, _toml_literal(full, value)))
    return pairs


def _with_types(settings, **types):
    """Settings with `table.type` for each table named by a keyword (None: not set)."""
    pairs = [(f"{table}.type", _toml_literal(f"{table}.type", name))
             for table, name in types.items() if name is not None]
    return pairs + settings


def _run_settings(options, optimizer, energy, solver, hierarchy, upsampler, tolerance,
                  max_iterations, preset=None):
    """The run config of deform and Session: the pieces' types, the options, and tolerance /
    max_iterations as optimizer options (as the command's flags set them); a preset's name as
    the config's top-level `preset` key, whose settings fill in what the rest leaves unset."""
    settings = _with_types(_settings(options), optimizer=optimizer, energy=energy,
                           solver=solver, hierarchy=hierarchy, upsampler=upsampler)
    if preset is not None:
        if not isinstance(preset, str):
            raise ConfigError(f"preset must be a string (harap.presets()), got {preset!r}")
        settings.append(("preset", _toml_literal("preset", preset)))
    if tolerance is not None:
        settings.append(("optimizer.tolerance", _toml_literal("optimizer.tolerance", tolerance)))
    if max_iterations is not None:
        settings.append(("optimizer.max_iterations",
                         _toml_literal("optimizer.max_iterations", max_iterations)))
    return settings


class DeformResult:
    """What harap.deform returns.

    positions: (n, 3) float64, the deformed vertices in the input's order.
    report:    a dict with the keys of `harap deform --report` (docs/report.md): energy,
               iterations, converged, timings, levels, trace (t, energy, level per iteration), ...
    stopped:   True if the callback returned False (the solve stopped early).
    """

    def __init__(self, positions, report, stopped):
        self.positions = positions
        self.report = report
        self.stopped = stopped

    @property
    def energy(self):
        return self.report["energy"]

    def __repr__(self):
        r = self.report
        return (f"DeformResult(energy={r['energy']:.9e}, iterations={r['iterations']}, "
                f"converged={r['converged']}, total={r['timings']['total']:.3f} s, "
                f"positions={self.positions.shape})")


def deform(V, F, handles, targets, *, optimizer="hierarchical", energy=None, solver=None,
           hierarchy=None, upsampler=None, options=None, tolerance=None, max_iterations=None,
           initial=None, planar=None, callback=None, threads=0, trace=True, stiffness=None,
           weights=None, preset=None):
    """Deforms the mesh (V, F) so that vertices `handles` reach `targets`, minimizing an ARAP
    energy, as `harap deform` does for a scenario file.

    V: (n, 3) rest positions; F: (m, 3) triangles or (m, 4) tetrahedra (0-based indices);
    handles: (k,) vertex indices; targets: (k, 3) their positions. Any float/integer dtype and
    memory layout is accepted (copied).
    optimizer, energy, solver, hierarchy, upsampler: registry names (harap.components(); None:
    harap's default, e.g. the energy `elements` for tetrahedra and planar meshes).
    options: any option by its config key, {"optimizer.tolerance": 1e-6, "solver.mode":
    "supernodal"} or nested {"optimizer": {"tolerance": 1e-6}}; tolerance / max_iterations set
    optimizer.tolerance / optimizer.max_iterations as the command's flags do.
    initial: (n, 3) start positions; planar: None decides as scenario files do (z = 0
    everywhere), True/False forces it.
    callback(level, iteration, energy): called after every iteration, on the calling thread (the
    solve itself runs on a worker thread without the GIL and waits for it); returning False stops
    the solve after that iteration, an exception stops it and propagates. Ctrl-C
    (KeyboardInterrupt) stops the solve within one iteration.
    threads: worker threads (0: all cores). trace: include the per-iteration trace in the report.
    stiffness: None, or (m,) factors > 0 multiplying each element's energy terms (a stiff region
    stays closer to rigid; docs/energies.md, "Stiffness"), or (n,) per-vertex factors (each
    element takes the mean of its vertices'); an array of length m is read per element.
    weights: None (every handle pins its vertex), or (k,) weights > 0, one per handle: a finite w
    makes that handle soft, a pull w ||u - t||^2 instead of a pin (docs/input.md, soft handles);
    inf keeps it hard. Hard and soft handles mix.
    preset: None, or a named option set as `harap deform --preset` takes (harap.presets():
    "fast", "hierarchical"; docs/solvers.md, Presets). It fills in only what the other
    keywords and options leave unset.

    Returns a DeformResult (positions, report, stopped).
    """
    settings = _run_settings(options, optimizer, energy, solver, hierarchy, upsampler, tolerance,
                             max_iterations, preset)
    positions, report, stopped = _harap.deform(V, F, handles, targets, settings, initial, planar,
                                               callback, int(threads), bool(trace), stiffness,
                                               weights)
    return DeformResult(positions, _json.loads(report), stopped)


class RegisterResult:
    """What harap.register returns.

    positions: (n, 3) float64, the registered source vertices in the input's order.
    distance:  (n,) float64, each vertex's distance to the target's closest point.
    report:    a dict with the keys of `harap register --report` (docs/registration.md):
               arap_energy, residual (rms, max), correspondences (kept, rejected by reason),
               correspondence_updates, levels, timings, ...
    stopped:   True if the callback returned False (the registration stopped early).
    """

    def __init__(self, positions, distance, report, stopped):
        self.positions = positions
        self.distance = distance
        self.report = report
        self.stopped = stopped

    def __repr__(self):
        r = self.report
        return (f"RegisterResult(residual_rms={r['residual']['rms']:.3e}, "
                f"kept={r['correspondences']['kept']}, "
                f"updates={r['correspondence_updates']}, total={r['timings']['total']:.3f} s)")


def register(V, F, target, *, target_faces=None, target_normals=None, landmarks=None,
             landmark_targets=None, hierarchical=True, energy=None, solver=None, hierarchy=None,
             upsampler=None, options=None, callback=None, threads=0, stiffness=None):
    """Deforms the mesh (V, F) onto a target with ARAP as the regularizer (non-rigid ICP, coarse
    to fine), as `harap register` does (docs/registration.md). F: (m, 3) triangles, or (m, 4)
    tetrahedra (the volume's boundary meets the target, the interior follows).

    target: (p, 3) points: a point cloud, or with target_faces (q, 3) the vertices of a target
    mesh. target_normals: (p, 3) normals of a point cloud (optional; used to reject
    correspondences whose normals disagree).
    landmarks: (k,) source vertex indices pulled towards landmark_targets (k, 3).
    hierarchical: False registers the input mesh alone (the flat baseline).
    energy, solver, hierarchy, upsampler, options: as for deform; registration options by their
    config key, e.g. {"registration.max_distance": 0.05, "registration.stages": 4}.
    callback(level, iteration, energy), threads, stiffness: as for deform.

    Returns a RegisterResult (positions, distance, report, stopped).
    """
    settings = _with_types(_settings(options),
                           optimizer="hierarchical" if hierarchical else "classic",
                           energy=energy, solver=solver, hierarchy=hierarchy, upsampler=upsampler)
    if (landmarks is None) != (landmark_targets is None):
        raise ConfigError("landmarks and landmark_targets go together")
    positions, distance, report, stopped = _harap.register_(
        V, F, target, target_faces, target_normals, landmarks, landmark_targets, settings,
        callback, int(threads), stiffness)
    return RegisterResult(positions, distance, _json.loads(report), stopped)


def _limit(name, value, *, integer=False, positive=False):
    """A solve limit given to Session.solve: None, or a finite number >= 0 (an integer >= 1)."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, _numbers.Real) or (
            integer and not isinstance(value, _numbers.Integral)):
        kind = "an integer" if integer else "a number"
        raise ConfigError(f"{name} must be {kind} or None, got {value!r}")
    if integer:
        value = int(value)
        if value < 1 or value > 2**31 - 1:
            raise ConfigError(f"{name} must be >= 1, got {value}")
        return value
    value = float(value)
    if not _math.isfinite(value) or value < 0 or (positive and value == 0):
        bound = "> 0" if positive else ">= 0"
        raise ConfigError(f"{name} must be a finite number {bound}, got {value!r}")
    return value


def _session_property(name, doc):
    """A read-only property returning self._session.<name>()."""
    return property(lambda self: getattr(self._session, name)(), doc=doc)


class Session:
    """An interactive deformation session (docs/session.md): the hierarchy and every level's
    precomputation are built once here; set_handles() constrains (factors every level);
    set_targets() moves the handles without refactoring; solve() is warm-started from the last
    solution; add_handles()/remove_handles() update the factorizations instead of refactoring
    where that is cheaper; preview() is the paper's coarse approximation.

        session = harap.Session(V, F, options={"optimizer.tolerance": 1e-6})
        session.set_handles(handles)             # targets: where they are now
        for t in np.linspace(0, 1, 10):
            session.set_targets(rest + t * offset)
            result = session.solve()             # result.positions, result.report

    V, F and the keywords optimizer ("hierarchical" or "classic"), energy, solver, hierarchy,
    upsampler, options, tolerance, max_iterations, initial, planar, threads and preset are those
    of harap.deform (planar is decided from V and initial: handle targets come later).
    frame_start: where the finer levels start a frame, "corrected" (default), "upsampled" or
    "previous" (docs/session.md).

    Every call checks its input before changing anything: a call that raises harap.Error leaves
    the session as it was. Arrays are accepted as by deform. Not thread-safe: a call while
    another thread is inside one raises harap.Error (solves release the GIL).
    """

    def __init__(self, V, F, *, optimizer="hierarchical", energy=None, solver=None,
                 hierarchy=None, upsampler=None, options=None, tolerance=None,
                 max_iterations=None, initial=None, planar=None, threads=0,
                 frame_start="corrected", preset=None):
        settings = _run_settings(options, optimizer, energy, solver, hierarchy, upsampler,
                                 tolerance, max_iterations, preset)
        if not isinstance(frame_start, str):
            raise ConfigError(f"frame_start must be a string, got {frame_start!r}")
        if isinstance(threads, bool) or not isinstance(threads, _numbers.Integral):
            raise ConfigError(f"threads must be an integer (0: all cores), got {threads!r}")
        self._session = _harap.Session(V, F, settings, initial, planar, int(threads),
                                       frame_start)
        # What view() serves (copies: the caller may change its arrays afterwards).
        self._view_source = (_np.array(V, dtype=_np.float64), _np.array(F), settings, planar,
                             int(threads))

    def set_handles(self, indices, targets=None, weights=None):
        """Makes `indices` (k,) the handles (unique, in range, at least one) with `targets`
        (k, 3), or, if None, their current positions (the last solution or the start). Factors
        every level (the C phase). Returns the edit summary (see add_handles).
        weights: None (every handle pins its vertex), or (k,) weights > 0 as in harap.deform: a
        finite w makes that handle soft (a pull w ||u - t||^2), inf keeps it hard. Soft handles
        move with set_targets() like hard ones, without refactoring; other soft vertices or
        weights refactor the rows they change, as add_handles does (docs/session.md, "Soft
        handles")."""
        return _json.loads(self._session.set_handles(indices, targets, weights))

    def set_targets(self, targets):
        """Moves the handles, hard and soft: (k, 3), one row per handle in the order of
        `handles`. No refactoring."""
        self._session.set_targets(targets)

    def add_handles(self, indices, targets):
        """Adds hard handles: vertices that are not handles yet, with their (k, 3) targets;
        updates every level's factorization on the rows that changed. Returns the edit summary: {"seconds",
        "levels": [{"level", "constrained_vertices", "changed_rows", "factored", "route"
        ("full", "numeric", "update", "partial", "none"), "seconds"}] (finest first),
        "constraints", "notes"}."""
        return _json.loads(self._session.add_handles(indices, targets))

    def remove_handles(self, indices):
        """Frees handles (each must be one; at least one must stay); the others keep their order
        and targets. Returns the edit summary (see add_handles)."""
        return _json.loads(self._session.remove_handles(indices))

    def set_positions(self, positions):
        """Sets the (n, 3) positions the next solve starts from and forgets the previous
        solutions (the next solve starts like harap.deform from `positions`)."""
        self._session.set_positions(positions)

    def solve(self, tolerance=None, max_iterations=None, time_budget=None, callback=None,
              trace=True):
        """Minimizes the energy for the current handles and targets, warm-started from the
        previous solution. tolerance / max_iterations (per level): None takes the session's
        options; time_budget: seconds for the whole solve (None: no limit; when it runs out on a
        coarse level the solution is carried to the finest level with one iteration there).
        callback, Ctrl-C and the GIL as in harap.deform. Returns a DeformResult whose report has
        harap.deform's keys (energy, iterations, converged, timings, levels, trace, ...)."""
        tolerance = _limit("tolerance", tolerance)
        max_iterations = _limit("max_iterations", max_iterations, integer=True)
        time_budget = _limit("time_budget", time_budget, positive=True)
        positions, report, stopped = self._session.solve(
            -1.0 if tolerance is None else tolerance,
            -1 if max_iterations is None else max_iterations,
            0.0 if time_budget is None else time_budget, callback, bool(trace))
        return DeformResult(positions, _json.loads(report), stopped)

    def preview(self, callback=None, trace=True):
        """The paper's coarse approximation for live feedback: the coarsest level solved
        (warm-started), up-sampled to the finest level and one global solve there. The report's
        energy is NaN (not evaluated; energy() gives it). Returns a DeformResult."""
        positions, report, stopped = self._session.preview(callback, bool(trace))
        report = _json.loads(report)
        # JSON has no NaN (the report writes null): the finest level's energy is not evaluated.
        for entry in [report] + report["levels"]:
            if entry["energy"] is None:
                entry["energy"] = _math.nan
        return DeformResult(positions, report, stopped)

    def energy(self):
        """The energy of the current positions, rotations fitted to them."""
        return self._session.energy()

    # Read-only views of the C++ session's state, each a fresh copy.
    positions = _session_property(
        "positions", "(n, 3) float64: the last solution (or the start), a copy.")
    handles = _session_property(
        "handles", "(k,) int64: the handle vertices, in the order targets use.")
    targets = _session_property("targets", "(k, 3) float64: the handles' targets.")
    weights = _session_property(
        "weights", "(k,) float64: the handles' weights (inf: hard, finite: soft).")
    num_levels = _session_property("num_levels", "The hierarchy's levels (1 for classic).")
    info = _session_property(
        "info", "What the session resolved: optimizer, energy, solver, hierarchy, upsampler, "
        "solved_levels (coarsest first), threads, planar, setup_timings {hierarchy, precompute} "
        "(seconds), mesh_summary, config (TOML).")

    def view(self, *, port=8080, host="127.0.0.1", open=False, display_vertices=200000,
             assets=None):
        """Serves the page of `harap view` (docs/view.md) for this session's mesh, handles (each
        connected set of handle vertices one group to drag) and targets, with its options;
        returns a running harap.View (see harap.view). The page solves in a session of its own:
        dragging there does not change this one."""
        V, F, settings, planar, threads = self._view_source
        return _start_view(V, F, self.handles, self.targets, self.weights, None, None, settings,
                           planar, threads, port, host, open, display_vertices, assets)

    def __repr__(self):
        info = self.info
        return (f"Session({len(self.positions)} vertices, {info['optimizer']}, "
                f"{self.num_levels} levels, {len(self.handles)} handles)")


class View:
    """A running `harap view` server (harap.view, Session.view): its page at `url`, served from
    a thread of this process until stop() (or the end of a `with` block, or of the process).

        with harap.view(V, F, [bottom, top]) as page:
            print(page.url)       # open it in a browser (over SSH: forward the port)
            page.wait()           # until Ctrl-C
    """

    def __init__(self, server, host):
        self._server = server
        self.port = server.port()
        shown = f"[{host}]" if ":" in host else host
        self.url = f"http://{shown}:{self.port}/"

    @property
    def running(self):
        return self._server.running()

    def stop(self):
        """Stops serving; open pages are closed after their current message."""
        self._server.stop()

    def wait(self):
        """Blocks until Ctrl-C (KeyboardInterrupt), then stops serving."""
        import time
        try:
            while self.running:
                time.sleep(0.2)
        except KeyboardInterrupt:
            pass
        finally:
            self.stop()

    def __enter__(self):
        return self

    def __exit__(self, *exception):
        self.stop()

    def __repr__(self):
        return f"View({self.url}, {'running' if self.running else 'stopped'})"


def _assets_folder(assets):
    """The page's files: `assets`, or share/harap/view of the build tree (beside python/) or of
    the installation (the prefix of lib/pythonX.Y/site-packages)."""
    if assets is not None:
        return str(assets)
    here = _pathlib.Path(__file__).resolve().parent
    for prefix in (here.parents[1], here.parents[3]):
        folder = prefix / "share" / "harap" / "view"
        if (folder / "index.html").is_file():
            return str(folder)
    raise InputError(f"the page's files (share/harap/view) are not beside {here}: build the "
                     "harap_view_assets target, install harap (cmake --install), or pass assets=")


def _rest_positions(V, indices):
    """V[indices] after checking the indices (numpy's IndexError would not name the problem)."""
    indices = _np.asarray(indices)
    if indices.size and (not _np.issubdtype(indices.dtype, _np.integer) or indices.min() < 0
                         or indices.max() >= len(V)):
        raise InputError(f"handles: indices must be integers in 0..{len(V) - 1}")
    return V[indices.astype(_np.int64)]


def _start_view(V, F, handles, targets, weights, group_sizes, group_names, settings, planar,
                threads, port, host, open_browser, display_vertices, assets):
    if isinstance(port, bool) or not isinstance(port, _numbers.Integral):
        raise ConfigError(f"port must be an integer (0: any free port), got {port!r}")
    if isinstance(display_vertices, bool) or not isinstance(display_vertices, _numbers.Integral):
        raise ConfigError(f"display_vertices must be an integer, got {display_vertices!r}")
    if not isinstance(host, str):
        raise ConfigError(f"host must be a string, got {host!r}")
    server = _harap.View(V, F, handles, targets, weights, group_sizes or [], group_names or [],
                         settings, planar, int(threads), host, int(port), _assets_folder(assets),
                         int(display_vertices))
    page = View(server, host)
    if host not in ("127.0.0.1", "::1"):
        import warnings
        warnings.warn(f"harap.view listens on {host}: anyone who reaches this address can drive "
                      "the session and read the mesh", stacklevel=3)
    if open_browser:
        import webbrowser
        webbrowser.open(page.url)
    return page


def view(V, F, handles=None, targets=None, *, optimizer="hierarchical", energy=None,
         solver=None, hierarchy=None, upsampler=None, options=None, tolerance=None,
         max_iterations=None, planar=None, threads=0, port=8080, host="127.0.0.1", open=False,
         display_vertices=200000, assets=None, weights=None, preset=None):
    """Serves the page of `harap view` (docs/view.md) for a mesh: drag its handles in a browser
    while harap solves. Returns a running harap.View (url, stop(), wait(); a context manager).

    handles: None (add them in the page), an index array (k,) whose connected sets of vertices
    become the groups the page drags, or a list of index arrays, one group each. targets: like
    handles, (k, 3) or a list of (k_i, 3) (None: where the vertices are). port 0 picks a free
    port; host 127.0.0.1 (default) accepts this machine only; open=True opens a browser. The
    page draws at most display_vertices vertices (a larger surface is decimated for the display,
    never for the solve). weights: None (every handle pins), or one weight per handle vertex
    (in the order of handles; for a list of groups, of the groups concatenated) as in
    harap.deform: a finite weight makes the vertex a soft handle; each group the page drags has
    one weight (connected handle vertices with other weights become groups of their own). The
    other keywords are harap.deform's.
    """
    settings = _run_settings(options, optimizer, energy, solver, hierarchy, upsampler,
                             tolerance, max_iterations, preset)
    V_array = _np.asarray(V, dtype=_np.float64)
    group_sizes = group_names = None
    if handles is None:
        handles = _np.zeros(0, dtype=_np.int64)
        targets = _np.zeros((0, 3))
    elif isinstance(handles, (list, tuple)) and handles and _np.ndim(handles[0]) == 1:
        groups = [_np.asarray(group) for group in handles]
        if targets is None:
            targets = [_rest_positions(V_array, group) for group in groups]
        if not isinstance(targets, (list, tuple)) or len(targets) != len(groups):
            raise InputError(f"targets: one (k, 3) array per handle group ({len(groups)}), got "
                             f"{type(targets).__name__}")
        group_sizes = [len(group) for group in groups]
        group_names = [f"handle {i + 1}" for i in range(len(groups))]
        handles = _np.concatenate(groups) if groups else _np.zeros(0, dtype=_np.int64)
        targets = _np.concatenate([_np.asarray(t, dtype=_np.float64).reshape(-1, 3)
                                   for t in targets])
    elif targets is None:
        targets = _rest_positions(V_array, handles)
    return _start_view(V, F, handles, targets, weights, group_sizes, group_names, settings,
                       planar, threads, port, host, open, display_vertices, assets)


def read_mesh(path):
    """Reads a mesh file (OBJ, PLY, OFF, STL, TetGen .node/.ele, MEDIT .mesh; also .xz) as
    (V, F): (n, 3) float64 and (m, 3) or (m, 4) int64."""
    return _harap.read_mesh(str(path))


def write_mesh(path, V, F):
    """Writes binary PLY with double coordinates (tetrahedra as their boundary triangles)."""
    _harap.write_mesh(str(path), V, F)


class Scenario:
    """A scenario file's mesh and handles as arrays (harap.load_scenario).

    V, F: the rest mesh (after `refine` / `tetrahedralize`); handles: the constrained vertex
    indices, ascending (all handles merged; a vertex selected twice takes the first handle's
    target); targets: their (k, 3) positions; initial: start positions or None; planar: the
    scenario's decision; handle_groups: [{name, vertices, targets}] per [[handle]]; notes.
    Unpacks as V, F, handles, targets = scenario.
    """

    def __init__(self, data):
        self.__dict__.update(data)

    def __iter__(self):
        return iter((self.V, self.F, self.handles, self.targets))

    def deform_arguments(self):
        """Keyword arguments carrying initial and planar: deform(*s, **s.deform_arguments())."""
        return {"initial": self.initial, "planar": self.planar}

    def __repr__(self):
        return (f"Scenario({self.mesh_source}: {len(self.V)} vertices, {len(self.F)} elements, "
                f"{len(self.handles)} handle vertices)")


def load_scenario(path):
    """Loads a scenario TOML file (../shared/scenarios/FORMAT.md, docs/input.md) as a Scenario."""
    return Scenario(_harap.load_scenario(str(path)))


def builtin_mesh(name, **parameters):
    """A built-in mesh as (V, F): "cylinder", "plane", "disk", "rectangle" with their parameters
    (vertices=..., aspect=..., ...; docs/input.md), as `mesh = { builtin = ... }` in scenarios."""
    settings = [("builtin", _toml_literal("builtin", name))] + _settings(parameters)
    V, F, _planar = _harap.builtin_mesh(settings)
    return V, F


class HierarchyLevel:
    """One level of a mesh hierarchy (finest first).

    vertices: (n_l, 3) rest positions; elements: (m_l, 3 or 4) indices into them;
    to_coarser: (n_l,) the vertex of the next coarser level representing each vertex (-1: none),
    None on the coarsest level; in_cluster: (n_l,) bool, True where to_coarser is the vertex's own
    cluster (False: the closest surviving substitute), None on the coarsest level.
    """

    def __init__(self, data):
        self.vertices = data["vertices"]
        self.elements = data["elements"]
        self.to_coarser = data["coarse_vertex"]
        self.in_cluster = None if data["in_cluster"] is None else data["in_cluster"].astype(bool)

    def __repr__(self):
        return f"HierarchyLevel({len(self.vertices)} vertices, {len(self.elements)} elements)"


def hierarchy(V, F, type="octree", *, planar=None, threads=0, **options):
    """The levels of the mesh hierarchy `type` ("octree", "edge_collapse") with its options
    (e.g. min_vertices=500), as `harap hierarchy` builds them: a list of HierarchyLevel."""
    settings = _with_types(_settings(options, "hierarchy."), hierarchy=type)
    return [HierarchyLevel(level)
            for level in _harap.hierarchy(V, F, settings, planar, int(threads))]


class EnergyValue:
    """harap.energy's result: value E(U) = min_R E(U, R); gradient (n, 3) = dE/dU =
    2 (A U - B(R)) at the fitted rotations; rotations (s, 3, 3), one per vertex or per element
    (per_element); planar: whether the mesh was treated as planar."""

    def __init__(self, value, gradient, rotations, per_element, planar):
        self.value = value
        self.gradient = gradient
        self.rotations = rotations
        self.per_element = per_element
        self.planar = planar

    def __float__(self):
        return float(self.value)

    def __repr__(self):
        return f"EnergyValue({self.value:.9e})"


def energy(name, V_rest, F, U, *, planar=None, threads=0, **options):
    """The energy `name` (see harap.components()["energy"]) of the deformed positions U (n, 3)
    of the rest mesh (V_rest, F), with the energy's options as keywords (a key that is a Python
    keyword: **{"lambda": 0.5}). Returns an EnergyValue (value, gradient, rotations).

    Contract (docs/energies.md): E(U, R) = tr(U^T A U) - 2 tr(U^T B(R)) + c; the rotations are
    fitted to U (the local step), so E(U) = min_R E(U, R) and dE/dU = 2 (A U - B(R)).
    """
    settings = _with_types(_settings(options, "energy."), energy=name)
    return EnergyValue(*_harap.energy(V_rest, F, U, settings, planar, int(threads)))


def _default_value(literal):
    if _tomllib is None:
        return literal
    try:
        return _tomllib.loads("value = " + literal)["value"]
    except _tomllib.TOMLDecodeError:
        return literal


def _options(entries):
    return {key: {"default": _default_value(default), "help": help}
            for key, default, help in entries}


def presets():
    """The named option sets the keyword `preset=` (and `harap deform --preset`) takes:

        {"fast": {"description": ..., "settings": {"optimizer.type": "hierarchical", ...},
                  "hierarchical_settings": {...}, "local_global_settings": {...}}, ...}

    settings apply to any run; hierarchical_settings only when the optimizer is "hierarchical";
    local_global_settings only when, besides, its level solver is local_global (the default).
    Each fills in only what the call leaves unset (docs/solvers.md, Presets).
    """
    def table(pairs):
        return {key: _default_value(literal) for key, literal in pairs}
    return {name: {"description": description, "settings": table(settings),
                   "hierarchical_settings": table(hierarchical),
                   "local_global_settings": table(local_global)}
            for name, description, settings, hierarchical, local_global in _harap.presets()}


def components():
    """Every registered piece with its options, defaults and help (what `harap list` prints):

        {"optimizer": {"classic": {"description": ..., "options": {"tolerance":
            {"default": 1e-06, "help": ...}, ...}}, ...},
         "energy": {...}, "solver": {...}, "hierarchy": {...}, "upsampler": {...},
         "level solver": {...} (optimizer.inner; options in the optimizer table),
         "solver.small_systems": {option: {default, help}}, "mesh": {option: {default, help}},
         "registration": {option: {default, help}},
         "builtin_meshes": [names]}
    """
    data = _harap.components()
    result = {kind: {} for kind in ("optimizer", "energy", "solver", "hierarchy", "upsampler")}
    for kind, name, description, options in data["components"]:
        result.setdefault(kind, {})[name] = {"description": description,
                                             "options": _options(options)}
    result["solver.small_systems"] = _options(data["small_systems"])
    result["mesh"] = _options(data["mesh"])
    result["registration"] = _options(data["registration"])
    result["builtin_meshes"] = list(data["builtin_meshes"])
    return result
