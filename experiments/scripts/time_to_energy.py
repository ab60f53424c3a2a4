#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Time to energy from `harap deform --report R.json --trace` reports (the paper's Fig. 1 quantified).

E_best is the lowest final energy among the given reports (run them with classic at tolerance 0
and a large iteration cap, and hierarchical at a tight tolerance). For each report, t(p%) is the
first trace time (seconds since the start of the run, precomputation included) at which the
finest-level (level 0) energy is within p% of E_best.

    experiments/scripts/time_to_energy.py classic.json hierarchical.json [--percent 1]
    experiments/scripts/time_to_energy.py RESULTS_DIR [--percent 1] [--markdown]

With --markdown, a last column gives the time each run needs to reach the highest final energy
among the runs (typically where classic stopped). With a `harap run` output folder (e.g. from experiments/configs/time_to_energy.toml), E_best and
t(p%) are computed per scenario over that scenario's runs, and the ratio of the slowest to the
fastest t(p%) is printed (a method that never gets there counts with its total time, its cap).
"""
import argparse
import json
import os
import sys


def load(path):
    with open(path, encoding="utf-8") as file:
        report = json.load(file)
    if "trace" not in report:
        raise SystemExit(f"{path}: no trace (run harap deform with --trace)")
    finest = [entry for entry in report["trace"] if entry["level"] == 0]
    return report, finest


def table(runs, percent, markdown, scenario=""):
    """Prints t(percent) for the (name, report, finest trace) runs of one scenario."""
    best = min(min([report["energy"]] + [e["energy"] for e in finest]) for _, report, finest in runs)
    threshold = best * (1.0 + percent / 100.0)
    times = {}
    for name, report, finest in runs:
        reached = next((e["t"] for e in finest if e["energy"] <= threshold), None)
        times[name] = (reached, report)
    # The time each run needs to reach the highest final energy of all runs (e.g. where classic
    # stopped): how much sooner the others get as far.
    worst_final = max(report["energy"] for _, report, _ in runs)
    to_worst = {name: next((e["t"] for e in finest if e["energy"] <= worst_final), None)
                for name, _, finest in runs}
    if markdown:
        for name, (reached, report) in times.items():
            when = f"{reached:.1f}" if reached is not None else \
                f"never (cap {report['timings']['total']:.1f} s, final E {report['energy'] / best - 1:+.1%})"
            worst = f"{to_worst[name]:.1f}" if to_worst[name] is not None else "–"
            print(f"| {scenario} | {name} | {report['energy']:.6g} | {best:.6g} | "
                  f"{report['timings']['total']:.1f} | {when} | {worst} |")
    else:
        print(f"{scenario + ': ' if scenario else ''}E_best = {best:.9g}; "
              f"threshold (+{percent:g}%) = {threshold:.9g}")
        print(f"{'run':40} {'optimizer':>13} {'final E':>12} {'total s':>9} "
              f"{'t(' + format(percent, 'g') + '%) s':>10}")
        for name, (reached, report) in times.items():
            when = f"{reached:.3f}" if reached is not None else "never"
            print(f"{name:40} {report['optimizer']:>13} {report['energy']:12.6g} "
                  f"{report['timings']['total']:9.2f} {when:>10}")
    effective = {name: (reached if reached is not None else report["timings"]["total"])
                 for name, (reached, report) in times.items()}
    if len(effective) >= 2 and not markdown:
        slowest = max(effective, key=effective.get)
        fastest = min(effective, key=effective.get)
        capped = " (at least: it never got there)" if times[slowest][0] is None else ""
        print(f"{fastest} is {effective[slowest] / effective[fastest]:.1f}x faster than "
              f"{slowest}{capped}\n")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("reports", nargs="+",
                        help="JSON reports written with --trace, or one `harap run` folder")
    parser.add_argument("--percent", type=float, default=1.0, help="within this many percent")
    parser.add_argument("--markdown", action="store_true", help="markdown table rows")
    args = parser.parse_args()
    if args.markdown:
        print(f"| scenario | run | final E | E_best | total s | t({args.percent:g}%) s | "
              "t(highest final E) s |")
        print("|---|---|---:|---:|---:|---:|---:|")
    if len(args.reports) == 1 and os.path.isdir(args.reports[0]):
        folder = args.reports[0]
        with open(os.path.join(folder, "experiment.json"), encoding="utf-8") as file:
            plan = json.load(file)
        by_scenario = {}
        for run in plan["runs"]:
            path = os.path.join(folder, "runs", run["id"] + ".json")
            if not os.path.exists(path):
                print(f"{run['id']}: not run yet", file=sys.stderr)
                continue
            with open(path, encoding="utf-8") as file:
                if json.load(file)["run"]["status"] != "ok":
                    print(f"{run['id']}: failed", file=sys.stderr)
                    continue
            report, finest = load(path)
            by_scenario.setdefault(run["scenario"], []).append(
                (run["label"] or run["variant"], report, finest))
        for scenario, runs in by_scenario.items():
            table(runs, args.percent, args.markdown, scenario)
        return 0
    table([(path, *load(path)) for path in args.reports], args.percent, args.markdown)
    return 0


if __name__ == "__main__":
    sys.exit(main())
