# SPDX-License-Identifier: MIT
"""harap.register: a known answer from arrays (mesh and point cloud), landmarks, and refusals."""
import numpy as np
import pytest

import harap


@pytest.fixture(scope="module")
def bend():
    """A cylinder and its ARAP bend (the known answer)."""
    V, F = harap.builtin_mesh("cylinder", vertices=1500)
    bottom = np.flatnonzero(V[:, 2] < 0.05)
    top = np.flatnonzero(V[:, 2] > 0.95)
    turn = np.array([[1, 0, 0], [0, np.cos(0.6), -np.sin(0.6)], [0, np.sin(0.6), np.cos(0.6)]])
    handles = np.concatenate([bottom, top])
    targets = np.vstack([V[bottom], V[top] @ turn.T + [0.0, 0.2, 0.0]])
    answer = harap.deform(V, F, handles, targets, threads=2).positions
    return V, F, answer


def mean_error(U, answer):
    return float(np.linalg.norm(U - answer, axis=1).mean())


def test_register_to_a_mesh_and_to_points(bend):
    V, F, answer = bend
    rest_error = mean_error(V, answer)
    for target in (dict(target=answer, target_faces=F), dict(target=answer)):
        result = harap.register(V, F, **target, threads=2)
        assert result.positions.shape == V.shape
        assert result.distance.shape == (len(V),)
        assert np.all(result.distance >= 0)
        assert mean_error(result.positions, answer) < 0.35 * rest_error
        report = result.report
        assert report["mode"] == "hierarchical"
        assert report["correspondences"]["kept"] > 0.9 * len(V)
        assert report["residual"]["rms_relative"] < 0.005
        assert not result.stopped
        assert "RegisterResult(" in repr(result)


def test_flat_registration_is_one_level(bend):
    V, F, answer = bend
    result = harap.register(V, F, answer, target_faces=F, hierarchical=False, threads=2,
                            options={"registration.stages": 2})
    assert len(result.report["levels"]) == 1
    assert result.report["mode"] == "flat"
    assert result.report["registration"]["stages"] == 2


def test_landmarks_pull_their_vertices(bend):
    V, F, _ = bend
    far = V + [5.0, 0.0, 0.0]  # beyond max_distance: the landmarks act first
    landmarks = np.array([0, len(V) // 2, len(V) - 1])
    result = harap.register(V, F, far, landmarks=landmarks, landmark_targets=far[landmarks],
                            threads=2)
    assert mean_error(result.positions, far) < 0.05


def test_refusals(bend):
    V, F, answer = bend
    with pytest.raises(harap.ConfigError, match="go together"):
        harap.register(V, F, answer, landmarks=[0])
    bad = answer.copy()
    bad[3, 1] = np.nan
    with pytest.raises(harap.InputError, match="not finite"):
        harap.register(V, F, bad)
    with pytest.raises(harap.InputError, match="out of range"):
        harap.register(V, F, answer, landmarks=[len(V)], landmark_targets=[[0.0, 0.0, 0.0]])
    with pytest.raises(harap.ConfigError, match="stagez"):
        harap.register(V, F, answer, options={"registration.stagez": 3})
