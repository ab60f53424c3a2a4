#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Side-by-side timing of harap.deform (Python module) and `harap deform` (the command) on one
scenario (docs/results.md, "The Python module"). Alternates fresh processes of each, RUNS times, and prints
the energy (as the command prints it, 10 significant digits) and the report's total time.

    PYTHONPATH=build/python python3 experiments/scripts/python_vs_cli.py \\
        ../shared/scenarios/armadillo-bend.toml --runs 5 -- --optimizer hierarchical --tolerance 1e-6

Python runs: harap.load_scenario(scenario), then harap.deform(*scenario, ...) with the same
optimizer and tolerance (initial and planar from the scenario)."""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

parser = argparse.ArgumentParser()
parser.add_argument("scenario")
parser.add_argument("--runs", type=int, default=5)
parser.add_argument("--harap", default="build/harap")
parser.add_argument("--baseline", help="a second harap executable to alternate with (e.g. a "
                    "build without position-independent code)")
parser.add_argument("--optimizer", default="hierarchical")
parser.add_argument("--tolerance", type=float, default=1e-6)
args = parser.parse_args()

PYTHON_RUN = """
import json, sys, harap
s = harap.load_scenario(sys.argv[1])
r = harap.deform(*s, **s.deform_arguments(), optimizer=sys.argv[2], tolerance=float(sys.argv[3]),
                 trace=False)
print(json.dumps({"energy": r.report["energy"], "total": r.report["timings"]["total"],
                  "iterations": r.report["iterations"]}))
"""


def run_cli(executable=None):
    with tempfile.TemporaryDirectory() as folder:
        report = os.path.join(folder, "report.json")
        subprocess.run([executable or args.harap, "deform", args.scenario, "--optimizer", args.optimizer,
                        "--tolerance", str(args.tolerance), "--report", report, "--quiet"],
                       check=True)
        data = json.load(open(report))
    return {"energy": data["energy"], "total": data["timings"]["total"],
            "iterations": data["iterations"]}


def run_python():
    output = subprocess.run([sys.executable, "-c", PYTHON_RUN, args.scenario, args.optimizer,
                             str(args.tolerance)], check=True, capture_output=True, text=True)
    return json.loads(output.stdout)


commands = [("cli", run_cli), ("python", run_python)]
if args.baseline:
    commands.append(("baseline", lambda: run_cli(args.baseline)))
results = {name: [] for name, _ in commands}
for run in range(args.runs):
    for name, function in commands:
        r = function()
        results[name].append(r)
        print(f"run {run + 1} {name:>8}: energy {r['energy']:.9e}  iterations {r['iterations']}"
              f"  total {r['total']:.3f} s", flush=True)
for name, runs in results.items():
    totals = [r["total"] for r in runs]
    energies = sorted({format(r["energy"], ".9e") for r in runs})
    print(f"{name:>8}: median total {statistics.median(totals):.3f} s "
          f"(min {min(totals):.3f}, max {max(totals):.3f}); energies {energies}")
ratio = statistics.median(r["total"] for r in results["python"]) / \
    statistics.median(r["total"] for r in results["cli"])
print(f"python / cli median total: {ratio:.3f}")
if args.baseline:
    ratio = statistics.median(r["total"] for r in results["cli"]) / \
        statistics.median(r["total"] for r in results["baseline"])
    print(f"cli / baseline median total: {ratio:.3f}")
