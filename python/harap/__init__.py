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

Every function calls harap's C++ library (the module harap._harap); options are validated as in
config files (an unknown key fails listing the valid ones), and C++ errors are raised as
harap.Error subclasses (ValueError) with the same messages.
"""

import json as _json
import math as _math
import numbers as _numbers
try:
    import tomllib as _tomllib  # Python 3.11
except ImportError:  # older Pythons: defaults stay TOML text
    _tomllib = None

import numpy as _np

from . import _harap
from ._harap import ConfigError, Error, InputError, InternalError, NumericalError

__all__ = [
    "deform", "DeformResult", "read_mesh", "write_mesh", "load_scenario", "Scenario",
    "builtin_mesh", "hierarchy", "HierarchyLevel", "energy", "EnergyValue", "components",
    "Error", "ConfigError", "InputError", "NumericalError", "InternalError",
]
# harap.Session (the interactive session, issue 21) is added here once it is merged.


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
           initial=None, planar=None, callback=None, threads=0, trace=True):
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

    Returns a DeformResult (positions, report, stopped).
    """
    settings = _with_types(_settings(options), optimizer=optimizer, energy=energy,
                           solver=solver, hierarchy=hierarchy, upsampler=upsampler)
    if tolerance is not None:
        settings.append(("optimizer.tolerance", _toml_literal("optimizer.tolerance", tolerance)))
    if max_iterations is not None:
        settings.append(("optimizer.max_iterations",
                         _toml_literal("optimizer.max_iterations", max_iterations)))
    positions, report, stopped = _harap.deform(V, F, handles, targets, settings, initial, planar,
                                               callback, int(threads), bool(trace))
    return DeformResult(positions, _json.loads(report), stopped)


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


def components():
    """Every registered piece with its options, defaults and help (what `harap list` prints):

        {"optimizer": {"classic": {"description": ..., "options": {"tolerance":
            {"default": 1e-06, "help": ...}, ...}}, ...},
         "energy": {...}, "solver": {...}, "hierarchy": {...}, "upsampler": {...},
         "solver.small_systems": {option: {default, help}}, "mesh": {option: {default, help}},
         "builtin_meshes": [names]}
    """
    data = _harap.components()
    result = {kind: {} for kind in ("optimizer", "energy", "solver", "hierarchy", "upsampler")}
    for kind, name, description, options in data["components"]:
        result.setdefault(kind, {})[name] = {"description": description,
                                             "options": _options(options)}
    result["solver.small_systems"] = _options(data["small_systems"])
    result["mesh"] = _options(data["mesh"])
    result["builtin_meshes"] = list(data["builtin_meshes"])
    return result
