#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Renders triangle meshes written by `harap deform --out` (binary PLY) side by side into one PNG,
headless, with matplotlib's mplot3d (Debian: python3-matplotlib).

    experiments/scripts/render_ply.py a.ply b.ply --titles "ARAP" "smooth ARAP" \
        --view 10 -60 --out docs/images/example.png

Faces are shaded flat (Lambert, one light from the camera's upper left) and drawn with the
painter's algorithm; faces turned away from the camera are culled, which is exact for closed
meshes and halves the work. All panels share the camera and the scale of the first mesh.
"""
import argparse
import sys

import numpy as np

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402


def read_ply(path):
    """Vertices (n×3 float) and triangles (m×3 int) of a binary little-endian PLY."""
    with open(path, "rb") as f:
        if f.readline().strip() != b"ply":
            sys.exit(f"{path}: not a PLY file")
        vertex_types, elements, current, fmt = [], {}, None, None
        while True:
            line = f.readline()
            if not line:
                sys.exit(f"{path}: header has no end_header")
            words = line.decode("ascii", "replace").split()
            if not words:
                continue
            if words[0] == "format":
                fmt = words[1]
            elif words[0] == "element":
                current = words[1]
                elements[current] = int(words[2])
            elif words[0] == "property" and current == "vertex":
                vertex_types.append(words[1])
            elif words[0] == "end_header":
                break
        if fmt != "binary_little_endian":
            sys.exit(f"{path}: only binary_little_endian PLY is supported, got {fmt}")
        sizes = {"double": "f8", "float64": "f8", "float": "f4", "float32": "f4"}
        if len(vertex_types) < 3 or any(t not in sizes for t in vertex_types):
            sys.exit(f"{path}: vertex properties {vertex_types} are not all float/double")
        vertex_dtype = np.dtype([(f"p{i}", "<" + sizes[t]) for i, t in enumerate(vertex_types)])
        n, m = elements.get("vertex", 0), elements.get("face", 0)
        raw = np.frombuffer(f.read(n * vertex_dtype.itemsize), dtype=vertex_dtype, count=n)
        vertices = np.stack([raw["p0"], raw["p1"], raw["p2"]], axis=1).astype(float)
        face_dtype = np.dtype([("count", "u1"), ("index", "<i4", (3,))])
        faces = np.frombuffer(f.read(m * face_dtype.itemsize), dtype=face_dtype, count=m)
        if m and not (faces["count"] == 3).all():
            sys.exit(f"{path}: only triangle faces are supported")
    return vertices, faces["index"].astype(np.int64)


def camera_axes(elevation, azimuth):
    """Unit vector towards the camera and the screen's up vector (matplotlib's convention)."""
    e, a = np.radians(elevation), np.radians(azimuth)
    towards = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    up = np.array([-np.sin(e) * np.cos(a), -np.sin(e) * np.sin(a), np.cos(e)])
    return towards, up


def draw(axes, vertices, faces, towards, up, color, centre, radius, zoom):
    corners = vertices[faces]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    lengths = np.linalg.norm(normals, axis=1)
    keep = lengths > 0
    normals[keep] /= lengths[keep, None]
    # Two-sided for open meshes would need both; harap's meshes are oriented, so cull.
    facing = normals @ towards
    keep &= facing > 0
    light = towards + 0.6 * up + 0.5 * np.cross(up, towards)
    light /= np.linalg.norm(light)
    shade = 0.25 + 0.75 * np.clip(normals[keep] @ light, 0.0, 1.0)
    colors = np.clip(np.outer(shade, color), 0.0, 1.0)
    collection = Poly3DCollection(corners[keep], facecolors=colors, edgecolors="none",
                                  linewidths=0.0, antialiased=False)
    axes.add_collection3d(collection)
    for set_limits, c in zip((axes.set_xlim, axes.set_ylim, axes.set_zlim), centre):
        set_limits(c - radius, c + radius)
    axes.set_box_aspect((1, 1, 1), zoom=zoom)
    axes.set_axis_off()


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("meshes", nargs="+", help="binary PLY files (harap deform --out)")
    parser.add_argument("--titles", nargs="*", default=None, help="one title per mesh")
    parser.add_argument("--view", nargs=2, type=float, default=(15.0, -60.0),
                        metavar=("ELEVATION", "AZIMUTH"), help="camera angles in degrees")
    parser.add_argument("--panel", type=float, default=3.2, help="panel size in inches")
    parser.add_argument("--zoom", type=float, default=1.5, help="magnification of each panel")
    parser.add_argument("--dpi", type=int, default=110)
    parser.add_argument("--up", choices=("x", "y", "z"), default="z",
                        help="the model's up axis (drawn vertically)")
    parser.add_argument("--out", required=True, help="PNG file to write")
    args = parser.parse_args()
    titles = args.titles or [""] * len(args.meshes)
    if len(titles) != len(args.meshes):
        sys.exit(f"{len(args.meshes)} meshes but {len(titles)} titles")

    towards, up = camera_axes(*args.view)
    meshes = [read_ply(path) for path in args.meshes]
    # A rotation (det +1) that takes the model's up axis to z.
    to_z_up = {"x": [[0, 1, 0], [0, 0, 1], [1, 0, 0]], "y": [[1, 0, 0], [0, 0, -1], [0, 1, 0]],
               "z": np.eye(3)}[args.up]
    meshes = [(vertices @ np.asarray(to_z_up, dtype=float).T, faces) for vertices, faces in meshes]
    lower = np.min([v.min(axis=0) for v, _ in meshes], axis=0)
    upper = np.max([v.max(axis=0) for v, _ in meshes], axis=0)
    centre, radius = 0.5 * (lower + upper), 0.5 * np.max(upper - lower)
    figure = plt.figure(figsize=(args.panel * len(meshes), args.panel * 1.05))
    palette = [np.array([0.55, 0.70, 0.90]), np.array([0.95, 0.70, 0.45])]
    for k, ((vertices, faces), title) in enumerate(zip(meshes, titles)):
        axes = figure.add_subplot(1, len(meshes), k + 1, projection="3d")
        axes.view_init(elev=args.view[0], azim=args.view[1])
        axes.set_proj_type("ortho")
        draw(axes, vertices, faces, towards, up, palette[min(k * 2 // len(meshes), 1)], centre,
             radius, args.zoom)
        axes.set_title(title, fontsize=9)
    figure.subplots_adjust(left=0, right=1, bottom=0, top=0.93, wspace=0)
    figure.savefig(args.out, dpi=args.dpi)


if __name__ == "__main__":
    main()
