# SPDX-License-Identifier: MIT
"""harap.deform: results, report keys, and identity with `harap deform` on the same scenario."""
import json

import numpy as np
import pytest

import harap
from conftest import run_cli

# A small scenario the CLI and the Python module both run (generated mesh: no data needed).
CYLINDER_SCENARIO = """
mesh = { builtin = "cylinder", vertices = 1500 }
[[handle]]
name = "bottom"
select.slab = { axis = "z", from = 0.0, to = 0.02 }
[[handle]]
name = "top"
select.slab = { axis = "z", from = 0.98, to = 1.0 }
rotate = { axis = [1.0, 0.0, 0.0], degrees = 90.0 }
translate = [0.0, 0.35, -0.3]
"""

TET_SCENARIO = """
mesh = { tetrahedralize = { builtin = "cylinder", vertices = 300 }, max_volume = 0.01 }
[[handle]]
select.slab = { axis = "z", from = 0.0, to = 0.05 }
[[handle]]
select.slab = { axis = "z", from = 0.95, to = 1.0 }
translate = [0.2, 0.0, 0.0]
"""


def test_deform_moves_the_handles_and_reports(cylinder):
    V, F, handles, targets = cylinder
    result = harap.deform(V, F, handles, targets, options={"optimizer.tolerance": 1e-6,
                                                           "hierarchy.min_vertices": 100})
    assert result.positions.shape == V.shape
    assert result.positions.dtype == np.float64
    np.testing.assert_allclose(result.positions[handles], targets, atol=1e-12)
    report = result.report
    assert report["optimizer"] == "hierarchical"
    assert report["energy"] > 0
    assert report["converged"]
    assert len(report["levels"]) > 1
    assert report["trace"] and {"t", "energy", "level"} <= set(report["trace"][0])
    # Energies of the trace decrease on the finest level (local/global never increases it).
    finest = [p["energy"] for p in report["trace"] if p["level"] == 0]
    assert all(b <= a * (1 + 1e-12) for a, b in zip(finest, finest[1:]))
    assert result.energy == report["energy"]
    assert not result.stopped


def test_report_has_the_cli_report_keys(tmp_path):
    scenario = tmp_path / "cylinder.toml"
    scenario.write_text(CYLINDER_SCENARIO)
    code, output = run_cli("deform", scenario, "--optimizer", "hierarchical", "--report",
                           tmp_path / "r.json", "--trace", "--quiet")
    assert code == 0, output
    cli = json.loads((tmp_path / "r.json").read_text())
    s = harap.load_scenario(scenario)
    python = harap.deform(*s, optimizer="hierarchical").report

    def keys(value, prefix=""):
        if isinstance(value, dict):
            return {prefix + k for k in value} | set().union(
                *(keys(v, prefix + k + ".") for k, v in value.items()))
        if isinstance(value, list) and value and isinstance(value[0], dict):
            return keys(value[0], prefix + "[].")
        return set()

    # mesh_checks findings depend on the mesh only, which is the same.
    assert keys(python) == keys(cli)


@pytest.mark.parametrize("optimizer", ["classic", "hierarchical"])
def test_identical_to_the_cli_on_the_same_scenario(tmp_path, optimizer):
    scenario = tmp_path / "cylinder.toml"
    scenario.write_text(CYLINDER_SCENARIO)
    code, output = run_cli("deform", scenario, "--optimizer", optimizer, "--tolerance", "1e-6",
                           "--threads", "2", "--out", tmp_path / "out.ply")
    assert code == 0, output
    printed = next(line.split()[1] for line in output.splitlines() if line.startswith("energy "))
    s = harap.load_scenario(scenario)
    result = harap.deform(*s, optimizer=optimizer, tolerance=1e-6, threads=2)
    # The CLI prints the energy with 10 significant digits: equal to the last one.
    assert f"{result.energy:.9e}" == printed
    iterations = next(l.split()[1] for l in output.splitlines() if l.startswith("iterations"))
    assert result.report["iterations"] == int(iterations)
    cli_positions, _ = harap.read_mesh(tmp_path / "out.ply")
    np.testing.assert_allclose(result.positions, cli_positions, rtol=0, atol=1e-9)


def test_preset_is_the_cli_preset(tmp_path):
    scenario = tmp_path / "cylinder.toml"
    scenario.write_text(CYLINDER_SCENARIO)
    code, output = run_cli("deform", scenario, "--preset", "fast", "--tolerance", "1e-6",
                           "--threads", "2", "--report", tmp_path / "r.json", "--quiet")
    assert code == 0, output
    cli = json.loads((tmp_path / "r.json").read_text())
    s = harap.load_scenario(scenario)
    result = harap.deform(*s, preset="fast", tolerance=1e-6, threads=2)
    assert result.energy == cli["energy"]
    assert result.report["config"] == cli["config"]
    assert result.report["levels"][0]["solver"].startswith("adaptive")
    assert "anderson = 5" in result.report["config"]


def test_preset_fills_in_only_what_the_call_leaves_unset(cylinder):
    V, F, handles, targets = cylinder
    config = harap.deform(V, F, handles, targets, preset="fast",
                          options={"optimizer.anderson": 0}).report["config"]
    assert "anderson = 0" in config and "anderson = 5" not in config
    assert "coarse_tolerance_factor = " in config
    # Another optimizer than the preset's takes none of its hierarchical settings.
    classic = harap.deform(V, F, handles, targets, optimizer="classic", preset="fast")
    assert classic.report["optimizer"] == "classic"
    assert "adaptive" not in classic.report["config"]


def test_presets_are_listed_and_unknown_names_list_them(cylinder):
    presets = harap.presets()
    assert set(presets) == {"fast", "hierarchical"}
    assert presets["fast"]["settings"]["optimizer.type"] == "hierarchical"
    assert presets["fast"]["local_global_settings"]["optimizer.anderson"] == 5
    V, F, handles, targets = cylinder
    with pytest.raises(harap.ConfigError, match="unknown preset 'fastest'; valid presets: fast, "
                       "hierarchical"):
        harap.deform(V, F, handles, targets, preset="fastest")
    with pytest.raises(harap.ConfigError, match="preset must be a string"):
        harap.Session(V, F, preset=5)
    session = harap.Session(V, F, preset="fast")
    session.set_handles(handles, targets)
    assert session.solve().report["levels"][0]["solver"].startswith("adaptive")


def test_tetrahedra_identical_to_the_cli(tmp_path):
    scenario = tmp_path / "tets.toml"
    scenario.write_text(TET_SCENARIO)
    code, output = run_cli("deform", scenario, "--optimizer", "hierarchical", "--report",
                           tmp_path / "r.json", "--quiet")
    assert code == 0, output
    cli = json.loads((tmp_path / "r.json").read_text())
    s = harap.load_scenario(scenario)
    assert s.F.shape[1] == 4
    result = harap.deform(*s, **s.deform_arguments())
    assert result.report["energy_type"] == "elements"
    assert result.report["mesh"]["element_kind"] == "tetrahedron"
    assert f"{result.energy:.9e}" == f"{cli['energy']:.9e}"


def test_planar_meshes_are_detected_as_in_scenarios():
    V, F = harap.builtin_mesh("rectangle", vertices=400)
    left = np.flatnonzero(V[:, 0] < 0.05)
    right = np.flatnonzero(V[:, 0] > 3.95)
    handles = np.concatenate([left, right])
    targets = np.concatenate([V[left], V[right] + [0.0, 1.0, 0.0]])
    result = harap.deform(V, F, handles, targets)
    assert result.report["mesh"]["planar"]
    assert result.report["energy_type"] == "elements"
    assert np.all(result.positions[:, 2] == 0.0)
    forced = harap.deform(V, F, handles, targets, planar=False)
    assert not forced.report["mesh"]["planar"]
    assert forced.report["energy_type"] == "spokes_and_rims"


def test_pieces_and_options_are_passed_like_config_keys(cylinder):
    V, F, handles, targets = cylinder
    result = harap.deform(V, F, handles, targets, optimizer="classic", energy="spokes",
                          solver="eigen_ldlt", options={"optimizer": {"max_iterations": 3}})
    report = result.report
    assert (report["optimizer"], report["energy_type"], report["solver"]) == \
        ("classic", "spokes", "eigen_ldlt")
    assert report["iterations"] == 3
    assert "max_iterations = 3" in report["config"]
    result = harap.deform(V, F, handles, targets, hierarchy="octree", upsampler="positions",
                          max_iterations=2, options={"hierarchy.min_vertices": 100})
    assert result.report["upsampler"] == "positions"
    assert all(level["iterations"] <= 2 for level in result.report["levels"])


def test_initial_positions_start_the_solve(cylinder):
    V, F, handles, targets = cylinder
    first = harap.deform(V, F, handles, targets, optimizer="classic", tolerance=1e-8)
    # Started from the solution, classic converges again in far fewer iterations, lower still.
    again = harap.deform(V, F, handles, targets, optimizer="classic", tolerance=1e-8,
                         initial=first.positions)
    assert again.report["iterations"] < first.report["iterations"] / 3
    assert again.energy <= first.energy


def test_arrays_of_any_layout_and_dtype_give_the_same_result(cylinder):
    V, F, handles, targets = cylinder
    reference = harap.deform(V, F, handles, targets, optimizer="classic", max_iterations=5)
    # Fortran order, a strided view, int32 faces, float32-exact handles as a list.
    strided = np.zeros((len(V), 6))
    strided[:, ::2] = V
    result = harap.deform(strided[:, ::2], np.asfortranarray(F.astype(np.int32)),
                          list(handles), np.asfortranarray(targets), optimizer="classic",
                          max_iterations=5)
    np.testing.assert_array_equal(result.positions, reference.positions)


def test_no_handles_keeps_the_rest_state(cylinder):
    V, F, _, _ = cylinder
    result = harap.deform(V, F, [], np.zeros((0, 3)), optimizer="classic")
    assert result.energy < 1e-10  # rounding only
    np.testing.assert_allclose(result.positions, V, atol=1e-9)


def test_stiffness_arrays_per_element_and_per_vertex(cylinder, tmp_path):
    V, F, handles, targets = cylinder
    options = {"optimizer.tolerance": 1e-8, "hierarchy.min_vertices": 100}
    plain = harap.deform(V, F, handles, targets, options=options)
    ones = harap.deform(V, F, handles, targets, options=options, stiffness=np.ones(len(F)))
    assert ones.report["energy"] == plain.report["energy"]
    # A uniform factor scales the energy and leaves the solution.
    scaled = harap.deform(V, F, handles, targets, options=options,
                          stiffness=np.full(len(V), 3, dtype=np.int32))
    assert scaled.report["energy"] == pytest.approx(3 * plain.report["energy"], rel=1e-6)
    np.testing.assert_allclose(scaled.positions, plain.positions, atol=1e-5)
    # The same region stiffened from Python and from a scenario's [[stiffness]] gives one result.
    middle = (V[:, 2] >= 1.5) & (V[:, 2] <= 2.5)
    vertex_factors = np.where(middle, 50.0, 1.0)
    stiff = harap.deform(V, F, handles, targets, options=options, stiffness=vertex_factors)
    assert stiff.report["energy"] > plain.report["energy"]
    for bad, message in [(np.ones(7), "one factor per element"),
                         (np.zeros(len(F)), "stiffness factor of element 0"),
                         (np.full(len(V), np.nan), "the factor of vertex 0"),
                         (np.ones((len(F), 2)), "1-D array"),
                         (np.array(["a"] * len(F)), "real numbers")]:
        with pytest.raises(harap.InputError, match=message):
            harap.deform(V, F, handles, targets, stiffness=bad)


def test_soft_handles_by_weight():
    """weights=: a finite weight pulls instead of pinning; a very large one is the pin."""
    V, F = harap.builtin_mesh("cylinder", vertices=800)
    bottom = np.flatnonzero(V[:, 2] < 0.05)
    top = np.flatnonzero(V[:, 2] > 0.95)
    handles = np.concatenate([bottom, top])
    targets = np.vstack([V[bottom], V[top] + [0.3, 0.0, 0.0]])
    options = {"optimizer.tolerance": 1e-13, "optimizer.max_iterations": 20000}
    hard = harap.deform(V, F, handles, targets, optimizer="classic", options=options)
    stiff = np.where(np.arange(len(handles)) < len(bottom), np.inf, 1e9)
    near_hard = harap.deform(V, F, handles, targets, optimizer="classic", options=options,
                             weights=stiff)
    assert abs(near_hard.energy - hard.energy) <= 1e-6 * hard.energy
    soft = harap.deform(V, F, handles, targets, optimizer="classic", options=options,
                        weights=np.where(np.isinf(stiff), np.inf, 1e-2))
    gap = np.linalg.norm(soft.positions[top] - targets[len(bottom):], axis=1).max()
    assert gap > 1e-3  # a weak pull does not reach the targets
    assert np.allclose(soft.positions[bottom], V[bottom])  # the hard ones do
    with pytest.raises(harap.InputError, match="weight of handle vertex"):
        harap.deform(V, F, handles, targets, weights=np.full(len(handles), -1.0))
    with pytest.raises(harap.InputError, match="one per handle"):
        harap.deform(V, F, handles, targets, weights=np.ones(3))
