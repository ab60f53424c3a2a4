#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Every shared surface mesh runs: fixed base, moved top slab, classic and hierarchical ARAP.

For each surface mesh of ../shared/meshes (MANIFEST.tsv, type "tri") this writes a scenario --
the bottom 10% of the bounding box along its longest axis fixed, the top 10% rotated by 30 degrees
about a perpendicular axis and moved by 0.1 box diagonals -- and runs `harap deform` on it with
each optimizer variant. A run passes when harap exits 0, reports `converged`, the final energy is
finite and the traced energy never increases within a level (relative slack 1e-9 for rounding)
wherever the constraints are fixed during the level: on every level of `classic` and
`hierarchical-fixed-targets` (targets_follow_rotations = false), and on the finest level of
`hierarchical`, whose coarse-level targets follow the cluster rotations at every iteration (the
energy being minimized changes, so it may rise there; the largest rise is reported).

    experiments/scripts/run_shared_meshes.py [--meshes cactus,teapot] [--markdown]
        [--harap build/harap] [--shared ../shared] [--set mesh.weld_duplicates=true]

Exit status: 0 all passed, 1 some run failed, 77 the shared folder is absent (ctest skips).
"""
import argparse
import json
import lzma
import math
import os
import struct
import subprocess
import sys
import tempfile
import time

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SKIP = 77
RELATIVE_SLACK = 1e-9
# Variant name -> (optimizer, extra --set options, whether coarse levels have fixed targets).
VARIANTS = {
    "classic": ("classic", [], True),
    "hierarchical": ("hierarchical", [], False),
    "hierarchical-fixed-targets": ("hierarchical", ["optimizer.targets_follow_rotations=false"], True),
}


def read_manifest(shared):
    path = os.path.join(shared, "meshes", "MANIFEST.tsv")
    with open(path, encoding="utf-8") as file:
        header = file.readline().rstrip("\n").split("\t")
        return [dict(zip(header, line.rstrip("\n").split("\t"))) for line in file if line.strip()]


def vertex_positions(path):
    """Vertex positions of an .obj.xz or binary/ASCII .ply.xz file (enough for a bounding box)."""
    data = lzma.decompress(open(path, "rb").read())
    if path.endswith(".obj.xz"):
        points = []
        for line in data.splitlines():
            if line.startswith(b"v "):
                x, y, z = line.split()[1:4]
                points.append((float(x), float(y), float(z)))
        return points
    end = data.index(b"end_header") + len(b"end_header")
    end = data.index(b"\n", end) + 1
    header = data[:end].decode("ascii", "replace").splitlines()
    fmt = header[1].split()[1]
    count, props, in_vertex, seen_vertex = 0, [], False, False
    for line in header:
        words = line.split()
        if words[:1] == ["element"]:
            in_vertex = words[1] == "vertex"
            if in_vertex:
                count, seen_vertex = int(words[2]), True
            elif not seen_vertex and int(words[2]) > 0:
                raise ValueError(f"{path}: elements before 'vertex' are not supported here")
        elif words[:1] == ["property"] and in_vertex:
            props.append((words[1], words[2]))
    if fmt == "ascii":
        lines = data[end:].splitlines()[:count]
        index = [name for _, name in props]
        return [tuple(float(line.split()[index.index(c)]) for c in "xyz") for line in lines]
    codes = {"float": "f", "float32": "f", "double": "d", "float64": "d", "uchar": "B",
             "uint8": "B", "char": "b", "int8": "b", "short": "h", "int16": "h", "ushort": "H",
             "uint16": "H", "int": "i", "int32": "i", "uint": "I", "uint32": "I"}
    layout = ("<" if fmt == "binary_little_endian" else ">") + "".join(codes[t] for t, _ in props)
    names = [name for _, name in props]
    record = struct.Struct(layout)
    picks = [names.index(c) for c in "xyz"]
    return [tuple(values[i] for i in picks)
            for values in record.iter_unpack(data[end:end + count * record.size])]


def write_scenario(folder, name, mesh_path):
    points = vertex_positions(mesh_path)
    lo = [min(p[d] for p in points) for d in range(3)]
    hi = [max(p[d] for p in points) for d in range(3)]
    extent = [hi[d] - lo[d] for d in range(3)]
    axis = max(range(3), key=lambda d: extent[d])
    bend = (axis + 1) % 3  # rotate about the next axis, move along the third
    shift = [0.0, 0.0, 0.0]
    shift[(axis + 2) % 3] = 0.1
    rotation_axis = [0.0, 0.0, 0.0]
    rotation_axis[bend] = 1.0
    letter = "xyz"[axis]
    text = (f'# Written by experiments/scripts/run_shared_meshes.py: base fixed, top bent.\n'
            f'mesh = "{mesh_path}"\n\n'
            f'[[handle]]\nname = "base"\n'
            f'select.slab = {{ axis = "{letter}", from = 0.0, to = 0.1 }}\n\n'
            f'[[handle]]\nname = "top"\n'
            f'select.slab = {{ axis = "{letter}", from = 0.9, to = 1.0 }}\n'
            f'rotate = {{ axis = {rotation_axis}, degrees = 30.0 }}\n'
            f'translate = {shift}\n')
    path = os.path.join(folder, f"{name}.toml")
    with open(path, "w", encoding="utf-8") as file:
        file.write(text)
    return path, letter


def largest_rise(report, levels):
    """Largest relative energy increase between consecutive iterations of one of `levels`
    (all levels if None)."""
    worst = 0.0
    previous = {}
    for entry in report.get("trace", []):
        level, energy = entry["level"], entry["energy"]
        if levels is not None and level not in levels:
            continue
        if level in previous:
            before = previous[level]
            worst = max(worst, (energy - before) / max(abs(before), 1e-300))
        previous[level] = energy
    return worst


def findings(report):
    checks = report.get("mesh_checks", {})
    short = {"unreferenced_vertices": "unref", "duplicate_vertices": "dup v",
             "zero_area_faces": "0-area", "duplicate_faces": "dup f",
             "non_manifold_edges": "nm e", "non_manifold_vertices": "nm v",
             "inconsistently_oriented_edges": "orient"}
    parts = [f"{label} {checks[key]['count']}" for key, label in short.items()
             if key in checks and checks[key]["count"]]
    components = checks.get("components", {})
    if components.get("count", 1) > 1:
        parts.append(f"{components['count']} comp ({components['without_handles']} free)")
    return ", ".join(parts) or "clean"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--harap", default=os.path.join(REPO, "build", "harap"))
    parser.add_argument("--shared", default=os.environ.get(
        "HARAP_SHARED", os.path.join(os.path.dirname(REPO), "shared")))
    parser.add_argument("--meshes", help="comma-separated names (file names without extension)")
    parser.add_argument("--variants", default=",".join(VARIANTS),
                        help="comma-separated: " + ", ".join(VARIANTS))
    parser.add_argument("--set", action="append", default=[], help="passed to harap --set")
    parser.add_argument("--threads", type=int, default=0)
    parser.add_argument("--out", help="folder for scenarios and reports (default: temporary)")
    parser.add_argument("--markdown", action="store_true", help="print a Markdown table")
    args = parser.parse_args()

    if not os.path.isfile(os.path.join(args.shared, "meshes", "MANIFEST.tsv")):
        print(f"skipped: no meshes/MANIFEST.tsv under {args.shared} (the shared data folder "
              f"beside the repository)")
        return SKIP
    rows = [row for row in read_manifest(args.shared) if row.get("type", "tri") == "tri"]
    if args.meshes:
        wanted = args.meshes.split(",")
        rows = [row for row in rows if row["file"].split(".")[0] in wanted]
        missing = set(wanted) - {row["file"].split(".")[0] for row in rows}
        if missing:
            print(f"unknown surface meshes: {', '.join(sorted(missing))}", file=sys.stderr)
            return 1
    out = args.out or tempfile.mkdtemp(prefix="harap-shared-meshes-")
    os.makedirs(out, exist_ok=True)

    results, failed = [], 0
    for row in rows:
        name = row["file"].split(".")[0]
        scenario, axis = write_scenario(out, name, os.path.join(args.shared, "meshes", row["file"]))
        for variant in args.variants.split(","):
            optimizer, settings, fixed_targets = VARIANTS[variant]
            report_path = os.path.join(out, f"{name}-{variant}.json")
            command = [args.harap, "deform", scenario, "--optimizer", optimizer, "--report",
                       report_path, "--trace", "-q"]
            if args.threads:
                command += ["--threads", str(args.threads)]
            for setting in settings + args.set:
                command += ["--set", setting]
            started = time.time()
            try:
                run = subprocess.run(command, capture_output=True, text=True)
            except OSError as error:
                run = subprocess.CompletedProcess(command, -1, "", str(error))
            wall = time.time() - started
            problems = []
            report = {}
            if run.returncode != 0:
                problems.append(f"exit {run.returncode}: {run.stderr.strip()[-300:]}")
            else:
                with open(report_path, encoding="utf-8") as file:
                    report = json.load(file)
                if not report["converged"]:
                    problems.append("not converged")
                if not math.isfinite(report["energy"]):
                    problems.append(f"energy {report['energy']}")
                checked = largest_rise(report, None if fixed_targets else {0})
                if checked > RELATIVE_SLACK:
                    problems.append(f"energy rose by {checked:.2e} (relative) within a level "
                                    f"with fixed constraints")
            failed += bool(problems)
            result = {
                "mesh": name, "optimizer": variant, "axis": axis,
                "vertices": row["vertices"], "faces": row["faces"],
                "findings": findings(report) if report else "-",
                "iterations": "/".join(str(level["iterations"]) for level in report["levels"])
                if report else "-",
                "energy": report.get("energy", float("nan")),
                "seconds": wall,
                "worst_increase": largest_rise(report, None) if report else float("nan"),
                "status": "ok" if not problems else "; ".join(problems),
            }
            results.append(result)
            print(f"{name:24} {variant:26} {result['status']:4} E={result['energy']:.6g} "
                  f"iterations {result['iterations']} ({wall:.1f} s) [{result['findings']}]",
                  flush=True)
    if args.markdown:
        print("\n| mesh | V | F | findings | optimizer | iterations (finest/.../coarsest) | "
              "energy | largest rise (any level) | wall s | status |\n"
              "|---|---:|---:|---|---|---|---:|---:|---:|---|")
        for r in results:
            print(f"| {r['mesh']} | {r['vertices']} | {r['faces']} | {r['findings']} | "
                  f"{r['optimizer']} | {r['iterations']} | {r['energy']:.6g} | "
                  f"{r['worst_increase']:.1e} | {r['seconds']:.1f} | {r['status']} |")
    print(f"{len(results) - failed} of {len(results)} runs passed; reports in {out}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
