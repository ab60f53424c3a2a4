# SPDX-License-Identifier: MIT
"""Callbacks, Ctrl-C and the GIL during harap.deform."""
import os
import signal
import threading
import time

import numpy as np
import pytest

import harap
from conftest import ticks_while


@pytest.fixture
def long_solve(cylinder):
    """Arguments of a solve that would run 100000 iterations (tolerance 0)."""
    V, F, handles, targets = cylinder
    return dict(V=V, F=F, handles=handles, targets=targets, optimizer="classic",
                options={"optimizer.tolerance": 0.0, "optimizer.max_iterations": 100000})


def run(arguments, **extra):
    arguments = dict(arguments, **extra)
    return harap.deform(arguments.pop("V"), arguments.pop("F"), arguments.pop("handles"),
                        arguments.pop("targets"), **arguments)


def test_callback_sees_every_iteration_on_the_calling_thread(cylinder):
    V, F, handles, targets = cylinder
    calls = []

    def callback(level, iteration, energy):
        calls.append((level, iteration, energy, threading.get_ident()))

    result = harap.deform(V, F, handles, targets, callback=callback, tolerance=1e-6,
                          options={"hierarchy.min_vertices": 100})
    trace = result.report["trace"]
    assert [(c[0], c[2]) for c in calls] == [(p["level"], p["energy"]) for p in trace]
    assert {c[3] for c in calls} == {threading.get_ident()}
    assert calls[-1][0] == 0 and calls[-1][1] == result.report["iterations"]
    assert len({c[0] for c in calls}) > 1  # coarse levels report too


def test_callback_returning_false_stops_after_that_iteration(long_solve):
    calls = []
    result = run(long_solve, callback=lambda level, iteration, energy:
                 calls.append(iteration) or iteration < 4)
    assert calls == [1, 2, 3, 4]
    assert result.stopped and not result.report["converged"]
    assert result.report["iterations"] == 4


def test_a_raising_callback_stops_the_solve_and_propagates(long_solve):
    calls = []

    def callback(level, iteration, energy):
        calls.append(iteration)
        if iteration == 3:
            raise RuntimeError("enough")

    with pytest.raises(RuntimeError, match="enough"):
        run(long_solve, callback=callback)
    assert calls == [1, 2, 3]


def test_sigint_from_the_callback_raises_keyboard_interrupt_at_once(long_solve):
    calls = []

    def callback(level, iteration, energy):
        calls.append(iteration)
        if iteration == 5:
            os.kill(os.getpid(), signal.SIGINT)

    with pytest.raises(KeyboardInterrupt):
        run(long_solve, callback=callback)
    # The callback runs on the main thread, where the signal's KeyboardInterrupt is raised.
    assert calls[-1] == 5


def test_sigint_from_another_thread_stops_within_one_iteration(long_solve):
    calls = []
    at_signal = []

    def interrupt():
        at_signal.append(len(calls))
        os.kill(os.getpid(), signal.SIGINT)

    timer = threading.Timer(0.3, interrupt)
    timer.start()
    start = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        run(long_solve, callback=lambda level, iteration, energy: calls.append(iteration))
    timer.join()
    assert at_signal, "the solve ended before the signal"
    # The iteration running when the signal came is the last one reported.
    assert len(calls) <= at_signal[0] + 1
    assert time.monotonic() - start < 5


def test_sigint_without_callback_stops_the_solve(long_solve):
    timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    start = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        run(long_solve)
    timer.join()
    # 100000 iterations would take far longer; stopping needs at most one more iteration.
    assert time.monotonic() - start < 5


def test_the_gil_is_released_during_a_solve(long_solve):
    options = {"optimizer.tolerance": 0.0, "optimizer.max_iterations": 3000}
    ticks, seconds = ticks_while(lambda: run(long_solve, options=options))
    # Held for the whole solve, the GIL would leave the counter at (almost) nothing.
    assert ticks > min(20, 100 * seconds)


def test_solves_from_several_python_threads_at_once(cylinder):
    V, F, handles, targets = cylinder
    reference = harap.deform(V, F, handles, targets, optimizer="classic", max_iterations=20,
                             threads=1).positions
    results = [None] * 3

    def solve(k):
        results[k] = harap.deform(V, F, handles, targets, optimizer="classic",
                                  max_iterations=20, threads=1).positions

    threads = [threading.Thread(target=solve, args=(k,)) for k in range(3)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    for positions in results:
        np.testing.assert_array_equal(positions, reference)
