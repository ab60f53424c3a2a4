#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Interactive strategies side by side (docs/results.md, "Interactive sessions and dragging"): `harap drag --report` per strategy, then a
table and a figure of the latency and the energy of every frame.

`harap run` drives `harap deform` only, so this script runs `harap drag` itself, one strategy
after the other on the same scenario, frames and tolerance:

    from_scratch   --from-scratch --optimizer hierarchical   (a fresh one-shot run per frame)
    classic        --optimizer classic                       (session, classic ARAP)
    hierarchical   --optimizer hierarchical                  (session, the default start)
    preview        --optimizer hierarchical --preview        (session, Preview() frames)

    experiments/scripts/drag_strategies.py ../shared/scenarios/armadillo-bend.toml \
        --out results/drag/armadillo-bend [--frames 30] [--tolerance 1e-6] [--threads 2] \
        [--strategies from_scratch,hierarchical] [--harap build/harap] [--plot-only]

Writes OUT/<strategy>.json (the drag reports), OUT/drag_strategies.png (top: milliseconds per
frame, log scale; bottom: each frame's energy over the from-scratch frame's, or the energy
itself without a from-scratch run) and prints a Markdown table: setup (H+P) and first C,
the frames' total, its ratio to from scratch, the median frame, the energy ratio's range and
the frames more than 1% above. --plot-only redraws from existing reports. Preview energies are
evaluated outside the frame's time (CurrentEnergy()). Timings are wall times on whatever else
the machine runs: run the strategies back to back, repeat, and say so.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys

STRATEGIES = {
    "from_scratch": ["--optimizer", "hierarchical", "--from-scratch"],
    "classic": ["--optimizer", "classic"],
    "hierarchical": ["--optimizer", "hierarchical"],
    "preview": ["--optimizer", "hierarchical", "--preview"],
}
LABELS = {
    "from_scratch": "from scratch per frame (hierarchical)",
    "classic": "session, classic",
    "hierarchical": "session, hierarchical",
    "preview": "session, preview",
}


def run(args, strategy, path):
    command = [args.harap, "drag", args.scenario, "--frames", str(args.frames), "--tolerance",
               str(args.tolerance), "--threads", str(args.threads), "--report", path]
    command += STRATEGIES[strategy] + args.extra
    print("+", " ".join(command), file=sys.stderr, flush=True)
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL)


def load(path):
    with open(path, encoding="utf-8") as file:
        report = json.load(file)
    if "frames" not in report:
        raise SystemExit(f"{path}: not a harap drag report (no frames)")
    return report


def summary(reports):
    base = reports.get("from_scratch")
    base_total = sum(f["seconds"] for f in base["frames"]) if base else None
    print("| strategy | setup H+P + first C (s) | frames (s) | ratio to from scratch | "
          "median frame (ms) | energy ratio (min–max) | frames > 1% above |")
    print("|---|---|---|---|---|---|---|")
    for name, report in reports.items():
        frames = report["frames"]
        total = sum(f["seconds"] for f in frames)
        median = 1e3 * statistics.median(f["seconds"] for f in frames)
        setup = (f"{report.get('setup_seconds', 0.0):.2f} + "
                 f"{report.get('constrain_seconds', 0.0):.2f}") if name != "from_scratch" else "–"
        ratio = f"{total / base_total:.3f}" if base_total else "–"
        if base and len(base["frames"]) == len(frames):
            ratios = [f["energy"] / b["energy"] for f, b in zip(frames, base["frames"])]
            energy = f"{min(ratios):.4f}–{max(ratios):.4f}"
            above = str(sum(r > 1.01 for r in ratios))
        else:
            energy, above = "–", "–"
        print(f"| {LABELS.get(name, name)} | {setup} | {total:.2f} | {ratio} | {median:.1f} | "
              f"{energy} | {above} |")


def plot(reports, path, title):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    base = reports.get("from_scratch")
    figure, (top, bottom) = plt.subplots(2, 1, figsize=(7, 6.5), sharex=True)
    for name, report in reports.items():
        frames = [f["frame"] for f in report["frames"]]
        top.plot(frames, [1e3 * f["seconds"] for f in report["frames"]], marker=".",
                 label=LABELS.get(name, name))
        if base and len(base["frames"]) == len(report["frames"]):
            energy = [f["energy"] / b["energy"] for f, b in zip(report["frames"], base["frames"])]
        else:
            energy = [f["energy"] for f in report["frames"]]
        bottom.plot(frames, energy, marker=".", label=LABELS.get(name, name))
    top.set_yscale("log")
    top.set_ylabel("frame latency (ms)")
    top.grid(True, which="both", alpha=0.3)
    top.legend(fontsize=8)
    top.set_title(title)
    bottom.set_yscale("log")
    bottom.set_ylabel("energy / from-scratch energy" if base else "energy")
    bottom.set_xlabel("frame")
    bottom.grid(True, which="both", alpha=0.3)
    figure.tight_layout()
    figure.savefig(path, dpi=120)
    print(f"wrote {path}", file=sys.stderr)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("scenario")
    parser.add_argument("--out", required=True, help="folder for the reports and the figure")
    parser.add_argument("--frames", type=int, default=30)
    parser.add_argument("--tolerance", type=float, default=1e-6)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--strategies", default=",".join(STRATEGIES),
                        help="comma-separated subset of " + ", ".join(STRATEGIES))
    parser.add_argument("--harap", default=os.path.join("build", "harap"))
    parser.add_argument("--plot-only", action="store_true", help="reuse OUT/<strategy>.json")
    parser.add_argument("extra", nargs="*", help="after --: more harap drag options")
    args = parser.parse_args()
    strategies = [s for s in args.strategies.split(",") if s]
    unknown = [s for s in strategies if s not in STRATEGIES]
    if unknown:
        raise SystemExit(f"unknown strategies {unknown}; valid: {', '.join(STRATEGIES)}")
    os.makedirs(args.out, exist_ok=True)
    reports = {}
    for strategy in strategies:
        path = os.path.join(args.out, f"{strategy}.json")
        if not args.plot_only:
            run(args, strategy, path)
        reports[strategy] = load(path)
    summary(reports)
    name = os.path.splitext(os.path.basename(args.scenario))[0]
    title = f"{name}: {args.frames} frames, tolerance {args.tolerance:g}"
    plot(reports, os.path.join(args.out, "drag_strategies.png"), title)


if __name__ == "__main__":
    main()
