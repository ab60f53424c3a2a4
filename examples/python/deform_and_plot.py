#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Deforms a mesh given as numpy arrays with classic and hierarchical ARAP and plots energy
against time (the report's per-iteration trace) with matplotlib.

    PYTHONPATH=build/python python3 examples/python/deform_and_plot.py --out energy.png
"""
import numpy as np

import example_figure
import harap

plt = example_figure.pyplot()

parser = example_figure.parser(__doc__, "energy.png", "a 3K-vertex mesh (tests)")
args = parser.parse_args()

# A capped cylinder along z (height 4): the bottom ring is held, the top ring turned 90 degrees
# about x and moved sideways, like experiments/scenarios/cylinder-bend.toml.
V, F = harap.builtin_mesh("cylinder", vertices=3000 if args.small else 40000)
bottom = np.flatnonzero(V[:, 2] < 0.08)
top = np.flatnonzero(V[:, 2] > 3.92)
center = V[top].mean(axis=0)
angle = np.pi / 2
rotation = np.array([[1, 0, 0],
                     [0, np.cos(angle), -np.sin(angle)],
                     [0, np.sin(angle), np.cos(angle)]])
handles = np.concatenate([bottom, top])
targets = np.concatenate([V[bottom], (V[top] - center) @ rotation.T + center + [0, 1.4, -1.2]])

figure, axes = plt.subplots(figsize=(6, 4))
for optimizer in ("classic", "hierarchical"):
    result = harap.deform(V, F, handles, targets, optimizer=optimizer, tolerance=1e-6)
    report = result.report
    trace = [p for p in report["trace"] if p["level"] == 0]  # the input mesh's iterations
    axes.semilogy([p["t"] for p in trace], [p["energy"] for p in trace], label=optimizer)
    print(f"{optimizer:>12}: energy {report['energy']:.6e}, {report['iterations']} iterations, "
          f"{report['timings']['total']:.3f} s")
axes.set_xlabel("time [s] (precomputation included)")
axes.set_ylabel("ARAP energy")
axes.set_title(f"cylinder bend, {len(V)} vertices")
axes.legend()
example_figure.save(figure, args.out)
print(f"wrote {args.out}")
