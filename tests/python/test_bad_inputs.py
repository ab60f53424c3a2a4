# SPDX-License-Identifier: MIT
"""Bad input raises a harap.Error (a ValueError) naming the problem; nothing crashes the
interpreter. Messages are the library's, as the CLI prints them."""
import numpy as np
import pytest

import harap
from conftest import run_cli


def deform(cylinder, **changes):
    V, F, handles, targets = cylinder
    arguments = dict(V=V, F=F, handles=handles, targets=targets)
    options = changes.pop("kwargs", {})
    arguments.update(changes)
    return harap.deform(arguments["V"], arguments["F"], arguments["handles"],
                        arguments["targets"], optimizer="classic", max_iterations=2, **options)


def test_the_exception_hierarchy():
    for name in ("ConfigError", "InputError", "NumericalError", "InternalError"):
        assert issubclass(getattr(harap, name), harap.Error)
    assert issubclass(harap.Error, ValueError)
    assert harap.InputError.__module__ == "harap"


@pytest.mark.parametrize("V, message", [
    ("not an array", "V must hold real numbers"),
    (np.zeros((5, 3), dtype=complex), "V must hold real numbers"),
    (np.array([[1, 2, 3]], dtype=object), "V must hold real numbers"),
    (np.zeros((5, 2)), "V must be an (n, 3) array, got shape (5, 2)"),
    (np.zeros(9), "V must be an (n, 3) array, got shape (9,)"),
    (np.zeros((3, 3, 3)), "V must be an (n, 3) array, got shape (3, 3, 3)"),
    (np.zeros((0, 3)), "the mesh has no vertices"),
    ([[0, 0, 0], [1, 0]], "V: not convertible to an array"),
])
def test_bad_vertex_arrays(cylinder, V, message):
    with pytest.raises(harap.InputError) as error:
        deform(cylinder, V=V)
    assert message in str(error.value)


def test_non_finite_vertices(cylinder):
    V = cylinder[0].copy()
    V[7, 1] = np.nan
    with pytest.raises(harap.InputError, match="vertex 7 has a non-finite coordinate"):
        deform(cylinder, V=V)
    V[7, 1] = np.inf
    with pytest.raises(harap.InputError, match="vertex 7 has a non-finite coordinate"):
        deform(cylinder, V=V)


@pytest.mark.parametrize("F, message", [
    (np.zeros((4, 3)), "F must hold integers, got dtype float64"),
    (np.zeros((4, 5), dtype=int), "F must be an (m, 3) array of triangles or an (m, 4) array"),
    (np.zeros(12, dtype=int), "got shape (12,)"),
    (np.zeros((0, 3), dtype=int), "the mesh has no faces"),
    (np.array([[0, 1, 10**6]]), "element 0 references vertex 1000000, but the mesh has"),
    (np.array([[0, 1, -1]]), "element 0 references vertex -1"),
    (np.array([[0, 1, 2**40]]), "element 0 references vertex 1099511627776, which is out of"),
    (np.array([[0, 1, 1]]), "element 0 uses vertex 1 twice"),
])
def test_bad_element_arrays(cylinder, F, message):
    with pytest.raises(harap.InputError) as error:
        deform(cylinder, F=F)
    assert message in str(error.value)


def test_flat_tetrahedra_are_rejected():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [0, 0, 1]], dtype=float)
    T = np.array([[0, 1, 2, 4], [0, 1, 2, 3]])
    with pytest.raises(harap.InputError, match="tetrahedron 1 .* is flat"):
        harap.deform(V, T, [0], [[0, 0, 0]])


@pytest.mark.parametrize("handles, targets, message", [
    ([10**6], [[0, 0, 0]], "handle vertex 1000000 (row 0) is out of range"),
    ([-1], [[0, 0, 0]], "handle vertex -1 (row 0) is out of range"),
    ([2**40], [[0, 0, 0]], "handles: vertex 1099511627776 (row 0) is out of range"),
    ([1, 1], [[0, 0, 0], [0, 0, 0]], "handle vertex 1 appears twice (rows 0 and 1)"),
    ([1, 2], [[0, 0, 0]], "2 handle vertices but 1 target rows"),
    ([1], [[0, 0, np.nan]], "the target of handle vertex 1 (row 0) is not finite"),
    ([1.5], [[0, 0, 0]], "handles must hold integers, got dtype float64"),
    ([[1]], [[0, 0, 0]], "handles must be a 1-D array of vertex indices, got shape (1, 1)"),
    ([1], [0, 0, 0], "targets must be an (n, 3) array, got shape (3,)"),
])
def test_bad_handles(cylinder, handles, targets, message):
    with pytest.raises(harap.InputError) as error:
        deform(cylinder, handles=handles, targets=targets)
    assert message in str(error.value)


def test_bad_initial_positions(cylinder):
    V = cylinder[0]
    with pytest.raises(harap.InputError, match="initial positions have 3 rows"):
        deform(cylinder, kwargs={"initial": V[:3]})
    bad = V.copy()
    bad[4, 0] = np.nan
    with pytest.raises(harap.InputError, match="initial position of vertex 4 is not finite"):
        deform(cylinder, kwargs={"initial": bad})


def test_unknown_option_fails_listing_valid_keys_as_the_cli_does(cylinder, tmp_path):
    with pytest.raises(harap.ConfigError) as error:
        deform(cylinder, kwargs={"options": {"optimizer.tolerence": 1e-6}})
    message = str(error.value)
    assert "tolerence" in message and "tolerance" in message
    # The CLI's message for the same key, but for the name of the source.
    scenario = tmp_path / "s.toml"
    scenario.write_text('mesh = { builtin = "cylinder", vertices = 300 }\n[[handle]]\n'
                        'select.slab = { axis = "z", from = 0.0, to = 0.1 }\n')
    code, output = run_cli("deform", scenario, "--optimizer", "classic", "--set",
                           "optimizer.tolerence=1e-06")
    assert code == 1
    cli = output.strip().removeprefix("harap: error: ")
    assert cli.replace("<command line>", "<options>") == message


@pytest.mark.parametrize("arguments, message", [
    ({"energy": "spokes_and_rimz"}, "unknown energy 'spokes_and_rimz'; valid names: "),
    ({"solver": "nope"}, "unknown solver 'nope'"),
    ({"options": {"optimizer.tolerance": "small"}}, "optimizer.tolerance"),
    ({"options": {"optimizer.tolerance": [1, 2]}}, "unsupported value [1, 2]"),
    ({"options": {3: 1}}, "option keys must be strings"),
    ({"options": "tolerance=1"}, "options must be a dict"),
    ({"options": {"nonsense": 1}}, "nonsense"),
    ({"threads": -1}, "threads must be >= 0"),
    ({"callback": 42}, "callback must be callable"),
])
def test_bad_options(cylinder, arguments, message):
    with pytest.raises(harap.ConfigError) as error:
        deform(cylinder, kwargs=arguments)
    assert message in str(error.value)


def test_bad_files(tmp_path):
    with pytest.raises(harap.InputError, match="not found"):
        harap.read_mesh(tmp_path / "missing.obj")
    (tmp_path / "broken.obj").write_text("v 0 0 0\nf 1 2 3\n")
    with pytest.raises(harap.InputError, match="broken.obj"):
        harap.read_mesh(tmp_path / "broken.obj")
    with pytest.raises(harap.InputError, match="scenario file not found"):
        harap.load_scenario(tmp_path / "missing.toml")
    (tmp_path / "bad.toml").write_text('mesh = { builtin = "cube" }\n')
    with pytest.raises(harap.ConfigError, match="cube"):
        harap.load_scenario(tmp_path / "bad.toml")
    V, F = harap.builtin_mesh("disk", vertices=50)
    with pytest.raises(harap.InputError, match="writes binary PLY"):
        harap.write_mesh(tmp_path / "out.obj", V, F)
    with pytest.raises(harap.Error, match="cannot open the file for writing"):
        harap.write_mesh(tmp_path / "no" / "such" / "dir.ply", V, F)


def test_bad_builtin_mesh():
    with pytest.raises(harap.ConfigError, match="not one of: cylinder, plane, disk, rectangle"):
        harap.builtin_mesh("cube")
    with pytest.raises(harap.ConfigError, match="verticez"):
        harap.builtin_mesh("cylinder", verticez=10)


@pytest.mark.parametrize("seed", [1, 2])
def test_random_small_meshes_solve_or_fail_cleanly(seed):
    """Random tiny meshes (flat, tiny, huge, repeated positions, random triangles and
    tetrahedra, random handles): every call returns or raises an input/config error, never an
    internal error or a crash."""
    rng = np.random.default_rng(seed)
    succeeded = 0
    for _ in range(150):
        n = int(rng.integers(4, 14))
        V = rng.standard_normal((n, 3)) * rng.choice([1, 1e-20, 1e20])
        if rng.random() < 0.3:
            V[:, 2] = 0
        if rng.random() < 0.1:
            V[int(rng.integers(0, n))] = V[0]
        k = int(rng.choice([3, 4]))
        F = np.array([rng.permutation(n)[:k] for _ in range(int(rng.integers(1, 15)))])
        H = rng.permutation(n)[:int(rng.integers(0, 4))]
        T = V[H] + rng.standard_normal((len(H), 3)) * (rng.random() < 0.7)
        call = rng.integers(0, 3)
        try:
            if call == 0:
                harap.deform(V, F, H, T, optimizer=str(rng.choice(
                    ["classic", "hierarchical", "admm_pd", "wrapd"])), max_iterations=5)
            elif call == 1:
                harap.hierarchy(V, F, str(rng.choice(["octree", "edge_collapse"])),
                                min_vertices=2)
            else:
                harap.energy(str(rng.choice(["spokes", "spokes_and_rims", "elements",
                                             "smooth_arap"])), V, F,
                             V + rng.standard_normal(V.shape))
            succeeded += 1
        except (harap.InputError, harap.ConfigError, harap.NumericalError):
            pass
    assert succeeded > 30  # the generator makes valid problems too
