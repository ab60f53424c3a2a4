#!/usr/bin/env python3
"""Registration with a known answer (docs/registration.md, docs/results.md "Registration").

For each scenario: deform its mesh with harap.deform (the answer U), then register the rest mesh
to targets made from U, without correspondences:
  mesh      the deformed mesh itself (closest points on its triangles)
  points    points sampled uniformly on the deformed surface (2 per source vertex), with normals
  damaged   those points with 10% removed (a contiguous patch) and 1% outliers added uniformly in
            the bounding box, grown by 10%
each hierarchically and flat (one level), side by side. Reports the mean and largest vertex error
|u_v - U_v| relative to the rest mesh's bounding-box diagonal, the residual and the time.

    python3 experiments/scripts/registration_known_answer.py [--out results/registration.json]
        [--scenarios ../shared/scenarios/cow-stretch.toml ...] [--threads 2] [--flat-updates N]

Needs the Python module (build/python on PYTHONPATH, or an installed harap).
"""
import argparse
import json
import os
import sys
import time

import numpy as np

here = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(here, "..", "..", "build", "python"))
import harap  # noqa: E402

DEFAULT_SCENARIOS = ["cactus-small", "cow-stretch", "armadillo-bend-43k"]


def sample_surface(V, F, count, rng):
    """`count` points uniformly on the triangles (area-weighted), with the triangles' normals."""
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    cross = np.cross(b - a, c - a)
    area = 0.5 * np.linalg.norm(cross, axis=1)
    faces = rng.choice(len(F), size=count, p=area / area.sum())
    r1, r2 = rng.random(count), rng.random(count)
    s = np.sqrt(r1)
    points = ((1 - s)[:, None] * a[faces] + (s * (1 - r2))[:, None] * b[faces] +
              (s * r2)[:, None] * c[faces])
    normals = cross[faces] / np.maximum(np.linalg.norm(cross[faces], axis=1), 1e-300)[:, None]
    return points, normals


def damage(points, normals, rng, removed=0.10, outliers=0.01):
    """Removes a contiguous patch of `removed` of the points (those nearest a random point) and
    adds `outliers` × count points uniformly in the grown bounding box (random normals)."""
    seed = points[rng.integers(len(points))]
    order = np.argsort(np.linalg.norm(points - seed, axis=1))
    keep = np.sort(order[int(removed * len(points)):])
    points, normals = points[keep], normals[keep]
    low, high = points.min(axis=0), points.max(axis=0)
    pad = 0.1 * (high - low)
    count = int(outliers * len(points))
    extra = rng.uniform(low - pad, high + pad, size=(count, 3))
    extra_normals = rng.normal(size=(count, 3))
    extra_normals /= np.linalg.norm(extra_normals, axis=1)[:, None]
    return np.vstack([points, extra]), np.vstack([normals, extra_normals])


def errors(U, answer, diagonal):
    e = np.linalg.norm(U - answer, axis=1) / diagonal
    return float(e.mean()), float(e.max())


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scenarios", nargs="*",
                        default=[os.path.join(here, "..", "..", "..", "shared", "scenarios",
                                              f"{name}.toml") for name in DEFAULT_SCENARIOS])
    parser.add_argument("--out", default="results/registration_known_answer.json")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--flat-updates", type=int, default=30,
                        help="registration.max_updates of the flat runs (hierarchical: 30)")
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    rows = []
    for path in args.scenarios:
        scenario = harap.load_scenario(path)
        V, F = scenario.V, scenario.F
        answer = harap.deform(*scenario, **scenario.deform_arguments(), threads=args.threads,
                              trace=False).positions
        diagonal = float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))
        points, normals = sample_surface(answer, F, 2 * len(V), rng)
        damaged_points, damaged_normals = damage(points, normals, rng)
        targets = {
            "mesh": dict(target=answer, target_faces=F),
            "points": dict(target=points, target_normals=normals),
            "damaged": dict(target=damaged_points, target_normals=damaged_normals),
        }
        name = os.path.basename(path).removesuffix(".toml")
        rest_mean, rest_max = errors(V, answer, diagonal)
        print(f"{name}: {len(V)} vertices, rest error mean {rest_mean:.4f} max {rest_max:.4f} "
              f"of the diagonal", flush=True)
        for kind, target in targets.items():
            for hierarchical in (True, False):
                clock = time.perf_counter()
                options = {} if hierarchical else {
                    "registration.max_updates": args.flat_updates}
                result = harap.register(V, F, **target, hierarchical=hierarchical,
                                        threads=args.threads, options=options)
                seconds = time.perf_counter() - clock
                mean, largest = errors(result.positions, answer, diagonal)
                report = result.report
                row = dict(scenario=name, vertices=len(V), target=kind,
                           mode="hierarchical" if hierarchical else "flat",
                           mean_error=mean, max_error=largest,
                           residual_rms=report["residual"]["rms_relative"],
                           kept=report["correspondences"]["kept"],
                           updates=report["correspondence_updates"],
                           iterations=report["iterations"], seconds=seconds,
                           arap_energy=report["arap_energy"], rest_mean_error=rest_mean)
                rows.append(row)
                print(f"  {kind:8s} {row['mode']:12s} mean {mean:.5f} max {largest:.5f} "
                      f"residual {row['residual_rms']:.5f} kept {row['kept']} updates "
                      f"{row['updates']} {seconds:.2f} s", flush=True)
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    with open(args.out, "w") as file:
        json.dump(rows, file, indent=1)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
