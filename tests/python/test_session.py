# SPDX-License-Identifier: MIT
"""harap.Session: the interactive session (docs/session.md) from Python. Its solves agree with
harap.deform, warm solves are cheap, handle edits give a fresh session's result, every bad call
raises a harap.Error and leaves the session usable, and solves are interruptible without the
GIL."""
import os
import signal
import threading
import time

import numpy as np
import pytest

import harap
from conftest import ticks_while

OPTIONS = {"optimizer.tolerance": 1e-6, "hierarchy.min_vertices": 100}


def relative(a, b):
    return abs(a - b) / abs(b)


@pytest.fixture
def session(cylinder):
    """A hierarchical session on the small cylinder with its handles set and solved once."""
    V, F, handles, targets = cylinder
    s = harap.Session(V, F, options=OPTIONS)
    s.set_handles(handles, targets)
    s.solve()
    return s


@pytest.mark.parametrize("optimizer", ["hierarchical", "classic"])
def test_the_first_solve_equals_deform(cylinder, optimizer):
    V, F, handles, targets = cylinder
    s = harap.Session(V, F, optimizer=optimizer, options=OPTIONS)
    assert s.num_levels == (1 if optimizer == "classic" else 3)
    edit = s.set_handles(handles, targets)
    assert [level["level"] for level in edit["levels"]] == sorted(s.info["solved_levels"])
    assert edit["constraints"]["constrained_vertices"] == len(handles)
    result = s.solve()
    reference = harap.deform(V, F, handles, targets, optimizer=optimizer, options=OPTIONS)
    assert relative(result.energy, reference.energy) < 1e-10
    np.testing.assert_allclose(result.positions, reference.positions, rtol=0, atol=1e-9)
    assert result.positions.dtype == np.float64 and result.positions.shape == V.shape
    # The report has the one-shot report's keys, per level too.
    assert set(result.report) == set(reference.report)
    assert [set(level) for level in result.report["levels"]] == \
        [set(level) for level in reference.report["levels"]]
    assert [level["iterations"] for level in result.report["levels"]] == \
        [level["iterations"] for level in reference.report["levels"]]
    assert result.report["mesh_checks"]["components"] == \
        reference.report["mesh_checks"]["components"]
    np.testing.assert_array_equal(s.positions, result.positions)
    np.testing.assert_array_equal(s.handles, handles)
    np.testing.assert_array_equal(s.targets, targets)
    assert relative(s.energy(), result.energy) < 1e-12


def test_targets_default_to_the_current_positions(cylinder):
    V, F, handles, _ = cylinder
    s = harap.Session(V, F, options=OPTIONS)
    s.set_handles(handles)
    np.testing.assert_array_equal(s.targets, V[handles])
    assert s.solve().energy < 1e-12  # the rest pose


def test_a_warm_solve_with_unchanged_targets_is_cheap(session):
    energy = session.energy()
    result = session.solve()
    iterations = [level["iterations"] for level in result.report["levels"]]
    assert len(iterations) == 3 and max(iterations) <= 2
    assert result.energy <= energy * (1 + 1e-9)


def test_a_drag_warm_starts_every_frame(cylinder):
    V, F, handles, targets = cylinder
    s = harap.Session(V, F, options=OPTIONS)
    s.set_handles(handles)
    start = s.targets
    energies = []
    for t in np.linspace(0.25, 1.0, 4):
        s.set_targets(start + t * (targets - start))
        result = s.solve()
        assert result.report["converged"]
        energies.append(result.energy)
    assert energies == sorted(energies)  # moving further costs more
    one_shot = harap.deform(V, F, handles, targets, options=OPTIONS)
    # The last frame is at the one-shot pose; warm-started, it ends at or below its energy.
    assert energies[-1] <= one_shot.energy * 1.01


def test_add_and_remove_handles_then_solve_equals_a_fresh_session(cylinder):
    V, F, handles, targets = cylinder
    s = harap.Session(V, F, options=OPTIONS)
    s.set_handles(handles, targets)
    s.solve()
    middle = np.flatnonzero(np.abs(V[:, 2] - 2.0) < 0.15)
    added = s.add_handles(middle, V[middle] + [0.3, 0.0, 0.0])
    assert added["levels"][0]["changed_rows"] >= len(middle)
    assert {level["route"] for level in added["levels"]} <= {"full", "numeric", "update", "partial", "none"}
    s.solve()
    removed = s.remove_handles(middle[::2])
    assert removed["constraints"]["constrained_vertices"] == \
        len(handles) + len(middle) - len(middle[::2])
    s.solve()
    # The same start for both: the edited session's positions, its solutions forgotten.
    start = s.positions
    s.set_positions(start)
    edited = s.solve()
    fresh = harap.Session(V, F, options=OPTIONS, initial=start)
    fresh.set_handles(s.handles, s.targets)
    reference = fresh.solve()
    assert relative(edited.energy, reference.energy) < 1e-10
    np.testing.assert_allclose(edited.positions, reference.positions, rtol=0, atol=1e-9)


def test_preview_places_the_handles(session, cylinder):
    _, _, handles, targets = cylinder
    session.set_targets(targets + [0.1, 0.0, 0.0])
    preview = session.preview()
    assert np.isnan(preview.energy) and np.isfinite(session.energy())
    np.testing.assert_allclose(preview.positions[handles], targets + [0.1, 0.0, 0.0], atol=1e-9)
    assert session.solve().report["converged"]


def test_solve_limits(session, cylinder):
    _, _, _, targets = cylinder
    session.set_targets(targets + [0.3, 0.0, 0.0])
    capped = session.solve(max_iterations=1)
    assert all(level["iterations"] <= 1 for level in capped.report["levels"])
    budget = session.solve(time_budget=1e-9)  # runs out at once: carried to the finest level
    assert np.isfinite(budget.energy)
    assert session.solve(tolerance=1e-9).report["converged"]


def test_frame_starts_and_the_report_of_the_setup(cylinder):
    V, F, handles, targets = cylinder
    energies = []
    for start in ("corrected", "upsampled", "previous"):
        s = harap.Session(V, F, options=OPTIONS, frame_start=start)
        s.set_handles(handles)
        s.set_targets(targets)
        energies.append(s.solve().energy)
        info = s.info
        assert info["optimizer"] == "hierarchical" and info["hierarchy"] == "octree"
        assert set(info["setup_timings"]) == {"hierarchy", "precompute"}
    # The first frame is the one-shot cascade whatever the start.
    assert max(energies) - min(energies) <= 1e-10 * min(energies)


# Bad calls: each raises a harap.Error subclass naming the problem; the session keeps its
# handles, targets and positions and still works afterwards.
BAD_CALLS = [
    ("set_handles", ([0, 0],), harap.InputError, "vertex 0 is given twice"),
    ("set_handles", ([],), harap.InputError, "no vertex indices given"),
    ("set_handles", (np.array([], dtype=np.int64),), harap.InputError, "no vertex indices"),
    ("set_handles", ([5000],), harap.InputError, "vertex index 5000 (entry 0) is out of range"),
    ("set_handles", ([-1],), harap.InputError, "vertex index -1 (entry 0) is out of range"),
    ("set_handles", ([2**40],), harap.InputError, "vertex 1099511627776 (row 0) is out of range"),
    ("set_handles", ([[1, 2]],), harap.InputError, "indices must be a 1-D array"),
    ("set_handles", ([1.0],), harap.InputError, "indices must hold integers, got dtype float64"),
    ("set_handles", ("abc",), harap.InputError, "indices must be a 1-D array"),
    ("set_handles", ([1, 2], [[0, 0, 0]]), harap.InputError, "1 targets for 2 handle vertices"),
    ("set_handles", ([1], [[0, np.nan, 0]]), harap.InputError, "target 0 is not finite"),
    ("set_handles", ([1], [[0, 0]]), harap.InputError, "targets must be an (n, 3) array"),
    ("set_targets", (np.zeros((2, 3)),), harap.InputError, "2 targets for 78 handle vertices"),
    ("set_targets", (np.zeros((78, 2)),), harap.InputError, "got shape (78, 2)"),
    ("set_targets", (np.zeros((78, 3, 1)),), harap.InputError, "got shape (78, 3, 1)"),
    ("set_targets", (np.full((78, 3), np.inf),), harap.InputError, "target 0 is not finite"),
    ("set_targets", (np.zeros((78, 3), dtype=complex),), harap.InputError, "real numbers"),
    ("set_targets", ([[0, 0, 0], [1, 2]],), harap.InputError, "not convertible to an array"),
    ("set_targets", (np.zeros((0, 3)),), harap.InputError, "0 targets for 78 handle vertices"),
    ("add_handles", ([0], [[0, 0, 0]]), harap.InputError, "vertex 0 is a handle already"),
    ("add_handles", ([300, 300], np.zeros((2, 3))), harap.InputError, "is given twice"),
    ("add_handles", ([300], np.zeros((2, 3))), harap.InputError, "2 targets for 1 handle"),
    ("add_handles", ([300], [[np.nan, 0, 0]]), harap.InputError, "target 0 is not finite"),
    ("add_handles", ([9999], [[0, 0, 0]]), harap.InputError, "out of range"),
    ("add_handles", ([], np.zeros((0, 3))), harap.InputError, "no vertex indices given"),
    ("remove_handles", ([300],), harap.InputError, "vertex 300 is not a handle"),
    ("remove_handles", ([],), harap.InputError, "no vertex indices given"),
    ("remove_handles", ([-3],), harap.InputError, "out of range"),
    ("remove_handles", ("every handle",), harap.InputError, "would remove every handle"),
    ("set_positions", (np.zeros((3, 3)),), harap.InputError, "3 positions for a mesh of 591"),
    ("set_positions", (np.full((591, 3), np.nan),), harap.InputError,
     "positions are not all finite"),
]
SOLVE_ARGUMENTS = [
    ({"tolerance": -1}, "tolerance must be a finite number >= 0"),
    ({"tolerance": float("nan")}, "tolerance must be a finite number >= 0"),
    ({"tolerance": "small"}, "tolerance must be a number or None"),
    ({"max_iterations": 0}, "max_iterations must be >= 1"),
    ({"max_iterations": 1.5}, "max_iterations must be an integer or None"),
    ({"time_budget": -1.0}, "time_budget must be a finite number > 0"),
    ({"time_budget": float("inf")}, "time_budget must be a finite number > 0"),
    ({"callback": 3}, "callback must be callable"),
]


def snapshot(s):
    return s.handles, s.targets, s.positions


def assert_usable(s, before):
    for old, new in zip(before, snapshot(s)):
        np.testing.assert_array_equal(old, new)
    handles, targets, _ = before
    s.set_targets(targets + [0.05, 0.0, 0.0])
    result = s.solve()
    assert result.report["converged"] and np.isfinite(result.energy)
    np.testing.assert_allclose(result.positions[handles], targets + [0.05, 0.0, 0.0],
                               atol=1e-9)


@pytest.mark.parametrize("method, arguments, error, message", BAD_CALLS)
def test_a_bad_call_raises_and_leaves_the_session_usable(session, method, arguments, error,
                                                         message):
    before = snapshot(session)
    if method == "remove_handles" and isinstance(arguments[0], str):
        arguments = (session.handles,)
    with pytest.raises(error) as raised:
        getattr(session, method)(*arguments)
    assert message in str(raised.value)
    assert isinstance(raised.value, harap.Error)
    assert_usable(session, before)


@pytest.mark.parametrize("keywords, message", SOLVE_ARGUMENTS)
def test_bad_solve_arguments(session, keywords, message):
    before = snapshot(session)
    with pytest.raises(harap.ConfigError) as raised:
        session.solve(**keywords)
    assert message in str(raised.value)
    assert_usable(session, before)


def test_calls_before_handles_are_set(cylinder):
    V, F, handles, targets = cylinder
    s = harap.Session(V, F, options=OPTIONS)
    for call in (lambda: s.solve(), lambda: s.preview(), lambda: s.set_targets(targets)):
        with pytest.raises(harap.InputError, match="the session has no handles yet"):
            call()
    assert len(s.handles) == 0 and s.targets.shape == (0, 3)
    s.set_handles(handles, targets)
    assert s.solve().report["converged"]


@pytest.mark.parametrize("arguments, error, message", [
    ({"V": np.zeros((5, 2))}, harap.InputError, "V must be an (n, 3) array, got shape (5, 2)"),
    ({"V": "V"}, harap.InputError, "V must hold real numbers"),
    ({"nan_vertex": True}, harap.InputError, "vertex 7 has a non-finite coordinate"),
    ({"F": np.zeros((4, 3))}, harap.InputError, "F must hold integers, got dtype float64"),
    ({"F": np.array([[0, 1, 10**6]])}, harap.InputError, "element 0 references vertex 1000000"),
    ({"F": np.zeros((0, 3), dtype=int)}, harap.InputError, "the mesh has no faces"),
    ({"V": np.zeros((0, 3))}, harap.InputError, "the mesh has no vertices"),
    ({"optimizer": "admm_pd"}, harap.ConfigError, "is not one of: classic, hierarchical"),
    ({"optimizer": "nope"}, harap.ConfigError, "nope"),
    ({"options": {"optimizer.bogus": 1}}, harap.ConfigError, "unknown option 'optimizer.bogus'"),
    ({"options": {"optimizer.inner": "lbfgs"}}, harap.ConfigError, "inner"),
    ({"frame_start": "latest"}, harap.ConfigError, "valid are corrected, upsampled, previous"),
    ({"frame_start": 1}, harap.ConfigError, "frame_start must be a string"),
    ({"threads": -1}, harap.ConfigError, "threads must be >= 0"),
    ({"threads": 1.5}, harap.ConfigError, "threads must be an integer"),
    ({"initial": np.zeros((3, 3))}, harap.InputError, "initial"),
])
def test_bad_construction(cylinder, arguments, error, message):
    V, F, handles, targets = cylinder
    arguments = dict(arguments)
    if arguments.pop("nan_vertex", False):
        V = V.copy()
        V[7, 1] = np.nan
    V, F = arguments.pop("V", V), arguments.pop("F", F)
    with pytest.raises(error) as raised:
        harap.Session(V, F, **arguments)
    assert message in str(raised.value)


def test_arrays_of_any_layout_and_dtype_are_accepted(cylinder):
    V, F, handles, targets = cylinder

    def strided(array):
        """The same values in a non-contiguous view (every other row of a doubled array)."""
        view = np.repeat(array, 2, axis=0)[::2]
        assert not view.flags.c_contiguous and not view.flags.f_contiguous
        return view

    s = harap.Session(strided(V), np.asfortranarray(F.astype(np.int32)), options=OPTIONS)
    s.set_handles(strided(handles.astype(np.uint32)), strided(targets))
    reference = harap.deform(V, F, handles, targets, options=OPTIONS)
    assert relative(s.solve().energy, reference.energy) < 1e-10
    s.set_targets(np.asfortranarray(targets.astype(np.float32)))
    np.testing.assert_array_equal(s.targets, targets.astype(np.float32))
    assert s.solve().report["converged"]
    s.set_targets(targets.tolist())  # nested lists too
    np.testing.assert_array_equal(s.targets, targets)


def test_tetrahedra_as_deform(tmp_path):
    scenario = tmp_path / "tets.toml"
    scenario.write_text("""
mesh = { tetrahedralize = { builtin = "cylinder", vertices = 300 }, max_volume = 0.01 }
[[handle]]
select.slab = { axis = "z", from = 0.0, to = 0.05 }
[[handle]]
select.slab = { axis = "z", from = 0.95, to = 1.0 }
translate = [0.2, 0.0, 0.0]
""")
    V, F, handles, targets = harap.load_scenario(scenario)
    assert F.shape[1] == 4
    s = harap.Session(V, F, options=OPTIONS)
    s.set_handles(handles, targets)
    result = s.solve()
    reference = harap.deform(V, F, handles, targets, options=OPTIONS)
    assert result.report["energy_type"] == "elements"
    assert result.report["mesh"]["element_kind"] == "tetrahedron"
    assert relative(result.energy, reference.energy) < 1e-10


def test_planar_meshes_as_deform():
    V, F = harap.builtin_mesh("rectangle", vertices=400)
    left = np.flatnonzero(V[:, 0] < 0.05)
    right = np.flatnonzero(V[:, 0] > 3.95)
    handles = np.concatenate([left, right])
    targets = np.concatenate([V[left], V[right] + [0.0, 1.0, 0.0]])
    s = harap.Session(V, F, optimizer="classic")
    assert s.info["planar"] and s.info["energy"] == "elements"
    s.set_handles(handles, targets)
    result = s.solve()
    reference = harap.deform(V, F, handles, targets, optimizer="classic")
    assert relative(result.energy, reference.energy) < 1e-10
    assert np.all(result.positions[:, 2] == 0.0)
    with pytest.raises(harap.InputError, match="the mesh is planar"):
        s.set_targets(targets + [0.0, 0.0, 0.5])
    assert s.solve().report["converged"]
    assert not harap.Session(V, F, optimizer="classic", planar=False).info["planar"]


# Interrupts, callbacks and the GIL, as for harap.deform (test_interrupts.py).

@pytest.fixture
def long_session(cylinder):
    """A classic session whose solve would run 100000 iterations (tolerance 0)."""
    V, F, handles, targets = cylinder
    s = harap.Session(V, F, optimizer="classic",
                      options={"optimizer.tolerance": 0.0, "optimizer.max_iterations": 100000})
    s.set_handles(handles, targets)
    return s


def test_callback_sees_every_iteration_on_the_calling_thread(cylinder):
    V, F, handles, targets = cylinder
    s = harap.Session(V, F, options=OPTIONS)
    s.set_handles(handles, targets)
    calls = []
    result = s.solve(callback=lambda level, iteration, energy:
                     calls.append((level, energy, threading.get_ident())))
    assert [(c[0], c[1]) for c in calls] == \
        [(p["level"], p["energy"]) for p in result.report["trace"]]
    assert {c[2] for c in calls} == {threading.get_ident()}
    assert len({c[0] for c in calls}) == 3


def test_callback_returning_false_stops_and_the_session_goes_on(long_session):
    calls = []
    result = long_session.solve(callback=lambda level, iteration, energy:
                                calls.append(iteration) or iteration < 4)
    assert calls == [1, 2, 3, 4]
    assert result.stopped and result.report["iterations"] == 4
    np.testing.assert_array_equal(long_session.positions, result.positions)
    again = long_session.solve(max_iterations=3)
    assert again.report["iterations"] == 3 and not again.stopped
    assert again.energy < result.energy


def test_a_raising_callback_propagates(long_session):
    def callback(level, iteration, energy):
        if iteration == 3:
            raise RuntimeError("enough")

    with pytest.raises(RuntimeError, match="enough"):
        long_session.solve(callback=callback)
    assert long_session.solve(max_iterations=2).report["iterations"] == 2


def test_sigint_stops_a_solve_with_keyboard_interrupt(long_session):
    calls = []

    def callback(level, iteration, energy):
        calls.append(iteration)
        if iteration == 5:
            os.kill(os.getpid(), signal.SIGINT)

    with pytest.raises(KeyboardInterrupt):
        long_session.solve(callback=callback)
    assert calls[-1] == 5
    # Without a callback, from another thread.
    timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    start = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        long_session.solve()
    timer.join()
    assert time.monotonic() - start < 5
    assert long_session.solve(max_iterations=2).report["iterations"] == 2


def test_the_gil_is_released_during_a_solve(long_session):
    ticks, seconds = ticks_while(lambda: long_session.solve(max_iterations=3000))
    # Held for the whole solve, the GIL would leave the counter at (almost) nothing.
    assert ticks > min(20, 100 * seconds)


def test_a_call_from_another_thread_during_a_solve_is_refused(long_session):
    solving, tried = threading.Event(), threading.Event()
    outcome = []

    def other_thread():
        solving.wait(10)
        try:
            long_session.set_targets(long_session.targets)
            outcome.append("accepted")
        except harap.Error as error:
            outcome.append(str(error))
        tried.set()

    thread = threading.Thread(target=other_thread)
    thread.start()
    # The solve goes on (the GIL released between iterations) until the other thread has tried.
    result = long_session.solve(callback=lambda level, iteration, energy:
                                solving.set() or not tried.is_set())
    thread.join()
    assert result.stopped
    assert len(outcome) == 1 and "in use by another thread" in outcome[0]
    long_session.set_targets(long_session.targets)
    assert long_session.solve(max_iterations=1).report["iterations"] == 1


@pytest.mark.parametrize("optimizer", ["hierarchical", "classic"])
def test_soft_handles_in_a_session(cylinder, optimizer):
    """set_handles(weights=): the session solves what harap.deform solves with those weights;
    set_targets moves soft targets without refactoring; bad weights raise and change nothing."""
    V, F, handles, targets = cylinder
    top = np.arange(len(handles)) >= np.count_nonzero(V[handles, 2] < 0.05)
    weights = np.where(top, 10.0, np.inf)
    s = harap.Session(V, F, optimizer=optimizer, options=OPTIONS)
    edit = s.set_handles(handles, targets, weights=weights)
    assert edit["constraints"]["constrained_vertices"] == np.count_nonzero(~top)
    np.testing.assert_array_equal(s.weights, weights)
    result = s.solve()
    reference = harap.deform(V, F, handles, targets, optimizer=optimizer, options=OPTIONS,
                             weights=weights)
    assert relative(result.energy, reference.energy) < 1e-9
    np.testing.assert_allclose(result.positions, reference.positions, rtol=0, atol=1e-8)
    # The soft ones are pulled, not pinned.
    assert np.linalg.norm(result.positions[handles[top]] - targets[top], axis=1).max() > 1e-4

    moved = targets + np.where(top[:, None], [0.2, 0.1, 0.0], 0.0)
    s.set_targets(moved)
    assert np.isfinite(s.preview().positions).all()  # no raise in the middle of a drag
    s.set_positions(V)
    again = s.solve()
    fresh = harap.Session(V, F, optimizer=optimizer, options=OPTIONS)
    fresh.set_handles(handles, moved, weights=weights)
    assert relative(again.energy, fresh.solve().energy) < 1e-9

    for bad, message in [(np.full(len(handles), np.nan), "weight 0 is nan"),
                         (np.where(top, 0.0, np.inf), "must be > 0"),
                         (np.ones(3), "one per handle")]:
        with pytest.raises(harap.InputError, match=message):
            s.set_handles(handles, moved, weights=bad)
    np.testing.assert_array_equal(s.weights, weights)
    # Targets default to where the vertices are; all-hard weights are hard handles.
    s.set_handles(handles[:5], weights=np.full(5, 2.0))
    np.testing.assert_array_equal(s.targets, s.positions[handles[:5]])
    s.set_handles(handles, moved, weights=np.full(len(handles), np.inf))
    assert np.isinf(s.weights).all()
