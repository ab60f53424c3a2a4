#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Plots the levels of a mesh hierarchy (harap.hierarchy) of a planar disk: each level's
triangles, and how the vertices of the finest level map to the next coarser one.

    PYTHONPATH=build/python python3 examples/python/plot_hierarchy.py --out levels.png
"""
import numpy as np

import example_figure
import harap

plt = example_figure.pyplot()

parser = example_figure.parser(__doc__, "levels.png", "a smaller mesh (tests)")
parser.add_argument("--type", default="octree", help="octree or edge_collapse")
args = parser.parse_args()

V, F = harap.builtin_mesh("disk", vertices=1500 if args.small else 6000)
levels = harap.hierarchy(V, F, args.type, min_vertices=40)
shown = levels[:4]
figure, axes = plt.subplots(1, len(shown) + 1, figsize=(3.2 * (len(shown) + 1), 3.8))
for l, (level, ax) in enumerate(zip(shown, axes)):
    ax.triplot(level.vertices[:, 0], level.vertices[:, 1], level.elements, lw=0.3, color="k")
    ax.set_title(f"level {l}: {len(level.vertices)} vertices")
    ax.set_aspect("equal")
    ax.axis("off")
# The clusters: finest vertices coloured by the level-1 vertex that represents them (colours
# shuffled so that neighbouring clusters differ).
ax = axes[-1]
cluster = levels[0].to_coarser
shuffled = np.random.default_rng(0).permutation(len(levels[1].vertices))
ax.scatter(V[:, 0], V[:, 1], c=np.where(cluster >= 0, shuffled[cluster] % 20, -1), cmap="tab20",
           s=3)
ax.set_title("level 0 -> level 1 map")
ax.set_aspect("equal")
ax.axis("off")
example_figure.save(figure, args.out)
for l, level in enumerate(levels):
    print(f"level {l}: {len(level.vertices):6} vertices {len(level.elements):6} triangles")
print(f"wrote {args.out}")
