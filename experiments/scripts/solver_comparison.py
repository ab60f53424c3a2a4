#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Hierarchical ARAP with a direct solver vs iterative global steps (the paper's Section 5.2).

Runs `harap deform SCENARIO --optimizer hierarchical --trace` once per solver configuration below
(CHOLMOD; Gauss-Seidel, CG and Chebyshev at several iteration budgets per global step; CHOLMOD
and three of those again with the outer tolerance tightened to 1e-8, so that the iterative ones
keep iterating with approximate solves; the per-level rule "CHOLMOD up to 50K unknowns, CG above") on each scenario, keeps the JSON
reports in --out, and prints one Markdown table: final energy, phase times, iterations per level,
solver iterations summed over all levels, and the first time at which the finest level's energy
is within 1% of the CHOLMOD run's final energy (from the trace; "never" if it is not).

    experiments/scripts/solver_comparison.py [--harap build/harap] [--out solver-runs] \
        [--scenarios ../shared/scenarios/armadillo-bend.toml ../shared/scenarios/buddha-twist.toml]
"""
import argparse
import json
import os
import subprocess
import sys

# (label, extra harap arguments). Budgets are iterations per global step (max_iterations of the
# solver, no inner tolerance) unless the label says otherwise.
CONFIGURATIONS = [
    ("cholmod", ["--solver", "cholmod"]),
    ("gauss_seidel 1 sweep", ["--solver", "gauss_seidel", "--set", "solver.max_iterations=1"]),
    ("gauss_seidel 5 sweeps", ["--solver", "gauss_seidel", "--set", "solver.max_iterations=5"]),
    ("gauss_seidel 20 sweeps", ["--solver", "gauss_seidel", "--set", "solver.max_iterations=20"]),
    ("gauss_seidel 100 sweeps", ["--solver", "gauss_seidel", "--set", "solver.max_iterations=100"]),
    ("cg 5", ["--solver", "cg", "--set", "solver.max_iterations=5"]),
    ("cg 20", ["--solver", "cg", "--set", "solver.max_iterations=20"]),
    ("cg 100", ["--solver", "cg", "--set", "solver.max_iterations=100"]),
    ("cg to 1e-8 (cap 2000)", ["--solver", "cg", "--set", "solver.max_iterations=2000",
                               "--set", "solver.tolerance=1e-8"]),
    ("chebyshev 10", ["--solver", "chebyshev", "--set", "solver.max_iterations=10"]),
    ("chebyshev 30", ["--solver", "chebyshev", "--set", "solver.max_iterations=30"]),
    ("chebyshev 100", ["--solver", "chebyshev", "--set", "solver.max_iterations=100"]),
    ("cholmod, outer tol 1e-8", ["--solver", "cholmod", "--tolerance", "1e-8"]),
    ("gauss_seidel 5 sweeps, outer tol 1e-8", ["--solver", "gauss_seidel", "--set",
                                               "solver.max_iterations=5", "--tolerance", "1e-8"]),
    ("cg 20, outer tol 1e-8", ["--solver", "cg", "--set", "solver.max_iterations=20",
                               "--tolerance", "1e-8"]),
    ("chebyshev 30, outer tol 1e-8", ["--solver", "chebyshev", "--set",
                                      "solver.max_iterations=30", "--tolerance", "1e-8"]),
    ("cholmod ≤ 50K, else cg 20", ["--solver", "cg", "--set", "solver.max_iterations=20",
                                   "--set", "solver.small_systems.max_unknowns=50000",
                                   "--set", "solver.small_systems.type=cholmod"]),
]


def run(harap, scenario, label, arguments, out_dir):
    name = os.path.splitext(os.path.basename(scenario))[0]
    slug = "".join(c if c.isalnum() else "-" for c in label).strip("-")
    report = os.path.join(out_dir, f"{name}--{slug}.json")
    command = [harap, "deform", scenario, "--optimizer", "hierarchical", "--report", report,
               "--trace", "-q"] + arguments
    print("$ " + " ".join(command), file=sys.stderr, flush=True)
    subprocess.run(command, check=True)
    with open(report, encoding="utf-8") as file:
        return name, json.load(file)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--harap", default="build/harap")
    parser.add_argument("--out", default="solver-runs", help="folder for the JSON reports")
    parser.add_argument("--scenarios", nargs="+",
                        default=["../shared/scenarios/armadillo-bend.toml",
                                 "../shared/scenarios/buddha-twist.toml"])
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)

    print("| scenario | global step | E | C s | S s | T s | t(E ≤ 1.01 E_cholmod) s | iterations "
          "per level (finest first) | solver iterations | max residual (finest) |")
    print("|---|---|---:|---:|---:|---:|---:|---|---:|---:|")
    for scenario in args.scenarios:
        reference = None
        for label, arguments in CONFIGURATIONS:
            name, report = run(args.harap, scenario, label, arguments, args.out)
            if reference is None:
                reference = report["energy"]  # the first configuration is CHOLMOD
            reached = next((entry["t"] for entry in report["trace"]
                            if entry["level"] == 0 and entry["energy"] <= 1.01 * reference),
                           None)
            when = f"{reached:.2f}" if reached is not None else "never"
            levels = report["levels"]
            per_level = ", ".join(str(level["iterations"]) for level in levels)
            solver_iterations = sum(level["solver_iterations"] for level in levels)
            finest = levels[0]
            residual = (f"{finest['max_relative_residual']:.1e}"
                        if finest["solver_iterations"] > 0 else "–")
            timings = report["timings"]
            print(f"| {name} | {label} | {report['energy']:.6g} | {timings['constrain']:.2f} | "
                  f"{timings['solve']:.2f} | {timings['total']:.2f} | {when} | {per_level} | "
                  f"{solver_iterations} | {residual} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
