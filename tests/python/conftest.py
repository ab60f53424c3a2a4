# SPDX-License-Identifier: MIT
"""Shared fixtures of the Python tests: small built-in meshes with handles, the CLI and the
shared data folder (tests needing it skip when it is absent)."""
import os
import pathlib
import subprocess
import threading
import time

import numpy as np
import pytest

import harap

SOURCE_DIR = pathlib.Path(os.environ.get("HARAP_SOURCE_DIR",
                                         pathlib.Path(__file__).resolve().parents[2]))
SHARED_DIR = pathlib.Path(os.environ.get("HARAP_SHARED_DIR", SOURCE_DIR.parent / "shared"))
EXECUTABLE = os.environ.get("HARAP_EXECUTABLE", str(SOURCE_DIR / "build" / "harap"))


def run_cli(*arguments):
    """Runs the harap command of this build; returns (exit code, stdout + stderr)."""
    process = subprocess.run([EXECUTABLE, *map(str, arguments)], capture_output=True, text=True)
    return process.returncode, process.stdout + process.stderr


@pytest.fixture
def cylinder():
    """A small capped cylinder (z in [0, 4]) with the bottom fixed and the top moved sideways:
    (V, F, handles, targets)."""
    V, F = harap.builtin_mesh("cylinder", vertices=600)
    bottom = np.flatnonzero(V[:, 2] < 0.05)
    top = np.flatnonzero(V[:, 2] > 3.95)
    handles = np.concatenate([bottom, top])
    targets = np.concatenate([V[bottom], V[top] + [0.6, 0.0, -0.2]])
    return V, F, handles, targets


@pytest.fixture
def shared_dir():
    if not (SHARED_DIR / "scenarios").is_dir():
        pytest.skip(f"shared data not found under {SHARED_DIR}")
    return SHARED_DIR


def ticks_while(call):
    """Runs `call()` while another Python thread counts millisecond ticks; returns the ticks and
    the call's seconds. A call that held the GIL throughout would leave (almost) no ticks."""
    ticks = []
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(1)
            time.sleep(0.001)

    counter = threading.Thread(target=count)
    counter.start()
    try:
        start = time.monotonic()
        call()
        seconds = time.monotonic() - start
    finally:
        stop.set()
        counter.join()
    return len(ticks), seconds
