# SPDX-License-Identifier: MIT
"""harap.hierarchy, harap.energy, harap.components and the mesh/scenario readers."""
import json
import re

import numpy as np
import pytest

import harap
from conftest import run_cli


def test_hierarchy_levels_are_nested(cylinder):
    V, F, _, _ = cylinder
    levels = harap.hierarchy(V, F, min_vertices=50)
    assert len(levels) > 2
    np.testing.assert_array_equal(levels[0].vertices, V)
    np.testing.assert_array_equal(levels[0].elements, F)
    for fine, coarse in zip(levels, levels[1:]):
        assert len(coarse.vertices) < len(fine.vertices)
        assert fine.to_coarser.shape == (len(fine.vertices),)
        assert fine.to_coarser.min() >= -1 and fine.to_coarser.max() < len(coarse.vertices)
        assert fine.in_cluster.dtype == bool and fine.in_cluster.any()
        assert coarse.elements.max() < len(coarse.vertices)
    assert levels[-1].to_coarser is None and levels[-1].in_cluster is None


def test_hierarchy_matches_the_cli(tmp_path):
    scenario = tmp_path / "s.toml"
    scenario.write_text('mesh = { builtin = "cylinder", vertices = 3000 }\n[[handle]]\n'
                        'select.slab = { axis = "z", from = 0.0, to = 0.1 }\n')
    for kind in ("octree", "edge_collapse"):
        code, output = run_cli("hierarchy", scenario, "--hierarchy", kind)
        assert code == 0, output
        rows = [line.split() for line in output.splitlines() if re.match(r"\s+\d+\s", line)]
        s = harap.load_scenario(scenario)
        levels = harap.hierarchy(s.V, s.F, kind)
        assert [(len(l.vertices), len(l.elements)) for l in levels] == \
            [(int(r[1]), int(r[2])) for r in rows]


def test_hierarchy_options_are_validated(cylinder):
    V, F, _, _ = cylinder
    with pytest.raises(harap.ConfigError, match="min_vertices"):
        harap.hierarchy(V, F, min_vertice=10)
    with pytest.raises(harap.ConfigError, match="unknown hierarchy 'quadtree'"):
        harap.hierarchy(V, F, "quadtree")


def test_energy_is_zero_at_rest_and_matches_deform(cylinder):
    V, F, handles, targets = cylinder
    rest = harap.energy("spokes_and_rims", V, F, V)
    assert rest.value == pytest.approx(0.0, abs=1e-10)  # cancellation in tr(UᵀAU) − 2tr(UᵀB) + c
    np.testing.assert_allclose(rest.gradient, 0.0, atol=1e-12)
    result = harap.deform(V, F, handles, targets, optimizer="classic", tolerance=1e-8)
    e = harap.energy("spokes_and_rims", V, F, result.positions)
    assert e.value == pytest.approx(result.energy, rel=1e-12)
    # Towards the constrained minimum the gradient on the free vertices vanishes: far smaller
    # than at the start (rest positions, handles at their targets).
    free = np.setdiff1d(np.arange(len(V)), handles)
    start = V.copy()
    start[handles] = targets
    at_start = np.abs(harap.energy("spokes_and_rims", V, F, start).gradient[free]).max()
    assert np.abs(e.gradient[free]).max() < 0.05 * at_start
    assert e.rotations.shape == (len(V), 3, 3) and not e.per_element


@pytest.mark.parametrize("name, options, mesh", [
    ("spokes", {}, "cylinder"), ("spokes_and_rims", {}, "cylinder"), ("elements", {}, "disk"),
    ("smooth_arap", {"lambda": 0.5}, "cylinder"),
])
def test_energy_gradient_matches_finite_differences(name, options, mesh):
    V, F = harap.builtin_mesh(mesh, vertices=200)
    rng = np.random.default_rng(1)
    planar = np.all(V[:, 2] == 0)
    U = V + 0.05 * rng.standard_normal(V.shape) * ([1, 1, 0] if planar else 1)
    e = harap.energy(name, V, F, U, **options)
    assert e.planar == planar
    direction = rng.standard_normal(V.shape) * ([1, 1, 0] if planar else 1)
    h = 1e-6
    plus = harap.energy(name, V, F, U + h * direction, **options).value
    minus = harap.energy(name, V, F, U - h * direction, **options).value
    assert (plus - minus) / (2 * h) == pytest.approx(np.sum(e.gradient * direction), rel=1e-5)


def test_energy_inputs_are_checked(cylinder):
    V, F, _, _ = cylinder
    with pytest.raises(harap.ConfigError, match="unknown energy 'spoke'; valid names"):
        harap.energy("spoke", V, F, V)
    with pytest.raises(harap.ConfigError, match="lambada"):
        harap.energy("smooth_arap", V, F, V, lambada=0.5)
    with pytest.raises(harap.InputError, match="positions have 3 rows"):
        harap.energy("spokes", V, F, V[:3])
    U = V.copy()
    U[2, 2] = np.nan
    with pytest.raises(harap.InputError, match="vertex 2 is not finite"):
        harap.energy("spokes", V, F, U)


def test_planar_energy():
    V, F = harap.builtin_mesh("disk", vertices=100)
    U = V * [1.5, 1.0, 0.0]
    e = harap.energy("elements", V, F, U)
    assert e.planar and e.per_element and e.value > 0
    assert e.rotations.shape == (len(F), 3, 3)


def test_components_are_what_harap_list_prints():
    components = harap.components()
    code, output = run_cli("list")
    assert code == 0
    listed = {}
    kind = None
    for line in output.splitlines():
        if re.match(r"^[a-z]+:$", line):
            kind = line[:-1]
            listed[kind] = set()
        elif kind and re.match(r"^  [a-z_0-9]+ ", line):
            listed[kind].add(line.split()[0])
    for kind in ("optimizer", "energy", "solver", "hierarchy", "upsampler"):
        assert set(components[kind]) == listed[kind], kind
    # Level solvers (optimizer.inner), listed by `harap list` under "inner".
    assert set(components["level solver"]) == listed["inner"]
    assert "local_global" in components["level solver"]
    tolerance = components["optimizer"]["classic"]["options"]["tolerance"]
    assert isinstance(tolerance["default"], float) and tolerance["help"]
    assert "type" not in components["energy"]["spokes"]["options"]
    assert components["energy"]["smooth_arap"]["description"]
    assert "max_unknowns" in components["solver.small_systems"]
    assert "weld_duplicates" in components["mesh"]
    assert components["registration"]["max_distance"]["default"] == 0.1
    assert "cylinder" in components["builtin_meshes"]
    assert set(harap.presets()) == listed["presets"]


def test_mesh_round_trip(tmp_path):
    V, F = harap.builtin_mesh("plane", vertices=300)
    V = V + 1e-3 * np.sin(np.arange(V.size)).reshape(V.shape)  # not float-exact
    harap.write_mesh(tmp_path / "m.ply", V, F)
    V2, F2 = harap.read_mesh(tmp_path / "m.ply")
    np.testing.assert_array_equal(V2, V)
    np.testing.assert_array_equal(F2, F)
    assert F2.dtype == np.int64


def test_load_scenario_matches_the_cli_handles(tmp_path):
    scenario = tmp_path / "s.toml"
    scenario.write_text('mesh = { builtin = "cylinder", vertices = 800 }\n'
                        '[[handle]]\nname = "a"\nselect.slab = { axis = "z", from = 0.0, to = 0.1 }\n'
                        '[[handle]]\nname = "b"\nselect.slab = { axis = "z", from = 0.05, to = 0.2 }\n'
                        'translate = [0.1, 0.0, 0.0]\n')
    code, output = run_cli("deform", scenario, "--max-iterations", "1", "--quiet",
                           "--out-handles", tmp_path / "h.json")
    assert code == 0, output
    groups = json.loads((tmp_path / "h.json").read_text())["handles"]
    s = harap.load_scenario(scenario)
    assert [g["name"] for g in s.handle_groups] == [g["name"] for g in groups]
    for mine, cli in zip(s.handle_groups, groups):
        np.testing.assert_array_equal(mine["vertices"], cli["vertices"])
    # Merged: every selected vertex once, ascending; overlaps take the first handle's target.
    assert np.all(np.diff(s.handles) > 0)
    overlap = np.intersect1d(groups[0]["vertices"], groups[1]["vertices"])
    assert len(overlap) > 0
    row = np.searchsorted(s.handles, overlap)
    np.testing.assert_array_equal(s.targets[row], s.V[overlap])
    V, F, handles, targets = s
    assert V.shape[1] == 3 and F.shape[1] == 3 and len(handles) == len(targets)
    assert s.initial is None and not s.planar


def test_tetrahedral_hierarchy_and_energy(tmp_path):
    scenario = tmp_path / "tets.toml"
    scenario.write_text('mesh = { tetrahedralize = { builtin = "cylinder", vertices = 300 }, '
                        'max_volume = 0.01 }\n[[handle]]\n'
                        'select.slab = { axis = "z", from = 0.0, to = 0.05 }\n')
    s = harap.load_scenario(scenario)
    levels = harap.hierarchy(s.V, s.F, min_vertices=30)
    assert len(levels) > 1 and all(level.elements.shape[1] == 4 for level in levels)
    stretched = s.V * [1.0, 1.0, 1.2]
    e = harap.energy("elements", s.V, s.F, stretched)
    assert e.per_element and not e.planar and e.value > 0
    assert e.rotations.shape == (len(s.F), 3, 3)
    # A rigid motion costs nothing.
    c, r = np.cos(0.3), np.sin(0.3)
    rigid = s.V @ np.array([[c, -r, 0], [r, c, 0], [0, 0, 1]]).T + [1, 2, 3]
    assert harap.energy("elements", s.V, s.F, rigid).value < 1e-12
