#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Drags a handle with an interactive session (harap.Session): set up once, then move the
targets over N frames and solve each frame warm-started; a third of the way a handle ring is
added in the middle, two thirds of the way it is removed again (handle edits without
refactoring). Prints per-frame time and energy, next to a one-shot harap.deform of the same
frame, and plots both with matplotlib if it is installed. (A session follows the shape of its
previous frame; the one-shot runs start from rest each time and may buckle into another shape,
so the energies of late frames can differ either way: docs/session.md.)

    PYTHONPATH=build/python python3 examples/python/drag_session.py --frames 30 --out drag.png
"""
import argparse
import os
import time

import numpy as np

import harap

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--frames", type=int, default=30, help="frames to the end pose")
parser.add_argument("--vertices", type=int, default=40000, help="vertices of the cylinder")
parser.add_argument("--out", default=None, help="the figure (PNG; needs matplotlib)")
parser.add_argument("--small", action="store_true", help="3K vertices, 10 frames (tests)")
args = parser.parse_args()
if args.small:
    args.vertices, args.frames = 3000, 10

# A capped cylinder along z (height 4): the bottom ring is held, the top ring turns up to 90
# degrees about x and moves sideways (experiments/scenarios/cylinder-bend.toml's motion).
V, F = harap.builtin_mesh("cylinder", vertices=args.vertices)
bottom = np.flatnonzero(V[:, 2] < 0.08)
top = np.flatnonzero(V[:, 2] > 3.92)
middle = np.flatnonzero(np.abs(V[:, 2] - 2.0) < 0.04)  # the ring added mid-way
center = V[top].mean(axis=0)


def top_targets(t):
    """The top ring at fraction t of the motion: angle and translation grow linearly."""
    angle = t * np.pi / 2
    rotation = np.array([[1, 0, 0],
                         [0, np.cos(angle), -np.sin(angle)],
                         [0, np.sin(angle), np.cos(angle)]])
    return (V[top] - center) @ rotation.T + center + t * np.array([0.0, 1.4, -1.2])


options = {"optimizer.tolerance": 1e-6}
clock = time.perf_counter()
session = harap.Session(V, F, options=options)  # hierarchy and precomputation, once
setup = time.perf_counter() - clock
clock = time.perf_counter()
session.set_handles(np.concatenate([bottom, top]))  # held where they are
constrain = time.perf_counter() - clock
print(f"{len(V)} vertices, {session.num_levels} levels: setup {setup:.3f} s, "
      f"constrain {constrain:.3f} s")
print(f"{'frame':>5} {'session s':>10} {'energy':>14} {'iters':>6} {'one-shot s':>11} "
      f"{'energy':>14}")

frames = []
for frame in range(1, args.frames + 1):
    t = frame / args.frames
    note = ""
    clock = time.perf_counter()
    if frame == args.frames // 3 + 1:
        # Hold the middle ring where the last frame left it.
        edit = session.add_handles(middle, session.positions[middle])
        note = f"  added {len(middle)} handles in {edit['seconds']:.4f} s"
    if frame == 2 * args.frames // 3 + 1:
        edit = session.remove_handles(middle)
        note = f"  removed them in {edit['seconds']:.4f} s"
    handles = session.handles
    targets = session.targets
    is_top = np.isin(handles, top)
    targets[is_top] = top_targets(t)[np.searchsorted(top, handles[is_top])]
    session.set_targets(targets)
    result = session.solve()
    seconds = time.perf_counter() - clock

    # The same frame from scratch (every phase again), for comparison.
    clock = time.perf_counter()
    one_shot = harap.deform(V, F, handles, targets, options=options, trace=False)
    one_shot_seconds = time.perf_counter() - clock
    frames.append((frame, seconds, result.energy, one_shot_seconds, one_shot.energy))
    print(f"{frame:>5} {seconds:>10.4f} {result.energy:>14.6e} "
          f"{result.report['iterations']:>6} {one_shot_seconds:>11.4f} "
          f"{one_shot.energy:>14.6e}{note}")

session_total = sum(f[1] for f in frames)
one_shot_total = sum(f[3] for f in frames)
print(f"{args.frames} frames: session {session_total:.3f} s, one-shot {one_shot_total:.3f} s "
      f"({session_total / one_shot_total:.2f} of it; setup {setup + constrain:.3f} s not counted)")
preview = session.preview()
print(f"preview of the last frame: {preview.report['timings']['total']:.4f} s, "
      f"energy {session.energy():.6e}")

if args.out:
    try:
        import matplotlib
        matplotlib.use("Agg")  # files only, no display needed
        import matplotlib.pyplot as plt
    except ImportError:
        print("no figure: matplotlib is not installed (Debian: python3-matplotlib)")
    else:
        frame, seconds, energy, one_seconds, one_energy = np.array(frames).T
        figure, (top_axes, bottom_axes) = plt.subplots(2, 1, figsize=(6, 6), sharex=True)
        top_axes.semilogy(frame, seconds, "o-", label="session (warm)")
        top_axes.semilogy(frame, one_seconds, "s-", label="one-shot deform")
        top_axes.set_ylabel("seconds per frame")
        top_axes.legend()
        bottom_axes.plot(frame, energy, "o-", label="session (warm)")
        bottom_axes.plot(frame, one_energy, "s-", label="one-shot deform")
        bottom_axes.set_xlabel("frame")
        bottom_axes.set_ylabel("ARAP energy")
        top_axes.set_title(f"cylinder drag, {len(V)} vertices")
        figure.tight_layout()
        os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
        figure.savefig(args.out, dpi=100)
        print(f"wrote {args.out}")
