# SPDX-License-Identifier: MIT
"""The experiment report's Fig. 11 section (experiments/scripts/report.py): each case outside
the bottom-left quadrant says why, and pairs are compared at equal energy from their traces."""
import importlib.util

import pytest

from conftest import SOURCE_DIR

pytest.importorskip("matplotlib")


@pytest.fixture(scope="module")
def report():
    spec = importlib.util.spec_from_file_location(
        "harap_report", SOURCE_DIR / "experiments" / "scripts" / "report.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def run(energies_and_times, levels, hierarchy=0.0, solver="cholmod"):
    """A run's report: finest-level trace points (energy, t), levels as (iterations, seconds),
    finest first; its final energy and total time are the trace's last point."""
    trace = [{"level": 0, "energy": e, "t": t} for e, t in energies_and_times]
    return {
        "energy": energies_and_times[-1][0],
        "timings": {"total": energies_and_times[-1][1], "hierarchy": hierarchy},
        "trace": [{"level": 1, "energy": 9.0, "t": 0.01}] * (len(levels) > 1) + trace,
        "levels": [{"level": k, "vertices": 1000 // 4**k, "iterations": iterations, "seconds": seconds,
                    "solver": solver if k == 0 else "cholmod", "energy": 1.0}
                   for k, (iterations, seconds) in enumerate(levels)],
    }


def test_an_early_stop_at_a_higher_energy_is_compared_where_both_reached_it(report):
    # Classic passes the hierarchical run's final energy 1.1 at its third iteration, 0.9 s.
    classic = run([(3.0, 0.5), (1.5, 0.7), (1.1, 0.9), (1.0, 1.2)], [(4, 1.2)])
    hierarchical = run([(1.1, 0.6)], [(1, 0.3), (12, 0.1)], hierarchy=0.05)
    assert report.quadrant_of(hierarchical, classic) == 2  # top-left
    why = report.why_outside(hierarchical, classic)
    assert "convergence test held after 1 iteration from the up-sampled start" in why
    assert "the baseline's after 4, +10.00% apart" in why
    assert "600 ms (finest iteration 1) against 900 ms (iteration 3), faster" in why
    assert report.equal_energy_ratio(hierarchical, classic) == pytest.approx(0.6 / 0.9)


def test_a_slower_lower_run_names_the_hierarchy_cost_or_the_solver_switch(report):
    classic = run([(2.0, 0.02), (1.0, 0.03)], [(2, 0.03)])
    hierarchical = run([(0.9, 0.05)], [(1, 0.02), (8, 0.015), (20, 0.005)], hierarchy=0.004)
    assert report.quadrant_of(hierarchical, classic) == 1  # bottom-right
    why = report.why_outside(hierarchical, classic)
    assert "lower energy (-10.00%) after 1 finest-level iterations against 2" in why
    assert ("the baseline needed only 2 iterations (30 ms), and the run spent 4 ms building the "
            "hierarchy and 20 ms on its 2 coarse levels") in why
    assert "50 ms (finest iteration 1) against 30 ms (iteration 2), slower" in why
    switched = run([(1.5, 20.0), (0.5, 25.0)], [(2, 24.0), (3, 1.0)], solver="adaptive:cg>cholmod")
    classic = run([(1.0, 18.0)], [(19, 18.0)])
    why = report.why_outside(switched, classic)
    assert "stalled and was factored after all, on the critical path" in why
    assert "25 s (finest iteration 2) against 18 s (iteration 1), slower" in why


def test_an_unconverged_stop_and_a_missing_trace_are_said(report):
    classic = run([(3.0, 0.5), (1.0, 1.2)], [(2, 1.2)])
    capped = run([(1.5, 0.4)], [(1, 0.3), (5, 0.1)])
    capped["levels"][0]["converged"] = False
    assert "stopped unconverged after 1 iteration" in report.why_outside(capped, classic)
    untraced = dict(capped, trace=[])
    assert report.equal_energy_ratio(untraced, classic) is None
    assert "at equal energy" not in report.why_outside(untraced, classic)


def test_negative_energies_are_reached(report):
    classic = run([(-1.0, 0.5), (-2.0, 1.0)], [(2, 1.0)])
    hierarchical = run([(-1.5, 0.3)], [(1, 0.2), (4, 0.05)])
    assert report.equal_energy_ratio(hierarchical, classic) == pytest.approx(0.3 / 1.0)


def test_a_single_level_run_is_the_baseline_itself(report):
    classic = run([(2.0, 0.004), (1.0, 0.006)], [(2, 0.006)])
    same = run([(2.0, 0.005), (1.0, 0.007)], [(2, 0.007)])
    assert report.why_outside(same, classic) == (
        "one level (the mesh is the hierarchy's coarsest), so the baseline's own 2 iterations "
        "and energy; only the time differs (7 ms against 6 ms)")


def test_the_quadrant_section_counts_the_cases_faster_at_equal_energy(report):
    def planned(result, variant, scenario):
        result = dict(result, run={"status": "ok", "variant": variant, "parameters": {}},
                      mesh={"vertices": 1000}, status="ok", energy_type="spokes_and_rims")
        result["_plan"] = {"scenario": scenario, "variant": variant, "label": "",
                           "parameters": {}}
        return result

    runs = [planned(run([(3.0, 0.5), (1.1, 0.9), (1.0, 1.2)], [(3, 1.2)]), "classic", "a"),
            planned(run([(1.1, 0.6)], [(1, 0.3), (12, 0.1)]), "hierarchical", "a"),
            planned(run([(2.0, 0.1), (1.0, 0.2)], [(2, 0.2)]), "classic", "b"),
            planned(run([(0.95, 0.1)], [(1, 0.05), (5, 0.01)]), "hierarchical", "b")]
    text = "\n".join(report.quadrant_section(runs, "variant", "classic", ""))
    assert "- hierarchical: faster in 2 of 2 cases (100%)" in text
    assert "### Cases outside the bottom-left quadrant (1)" in text
    assert "**a** (hierarchical), 1,000 vertices, top-left (faster, higher). Why:" in text


def test_runs_timed_by_repetitions_are_said(report):
    once = run([(1.0, 2.0)], [(3, 2.0)])
    assert report.repetition_note([once, once]) == ""
    repeated = dict(run([(1.0, 0.01)], [(3, 0.01)]), repetitions={"count": 30})
    other = dict(run([(1.0, 0.2)], [(3, 0.2)]), repetitions={"count": 3})
    note = report.repetition_note([once, repeated, other])
    assert "2 of these 3 runs were shorter than `[run] min_time`" in note
    # A baseline in several pairs counts once.
    assert "2 of these 3 runs" in report.repetition_note([once, repeated, other, repeated])
    assert "median of 3–30 repetitions" in note
