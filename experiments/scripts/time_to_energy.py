#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Time to energy from `harap deform --report R.json --trace` reports (issue 3's criterion).

E_best is the lowest final energy among the given reports (run them with classic at tolerance 0
and a large iteration cap, and hierarchical at a tight tolerance). For each report, t(p%) is the
first trace time (seconds since the start of the run, precomputation included) at which the
finest-level (level 0) energy is within p% of E_best.

    experiments/scripts/time_to_energy.py classic.json hierarchical.json [--percent 1]
"""
import argparse
import json
import sys


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("reports", nargs="+", help="JSON reports written with --trace")
    parser.add_argument("--percent", type=float, default=1.0, help="within this many percent")
    args = parser.parse_args()

    runs = []
    for path in args.reports:
        with open(path, encoding="utf-8") as file:
            report = json.load(file)
        if "trace" not in report:
            print(f"{path}: no trace (run harap deform with --trace)", file=sys.stderr)
            return 1
        finest = [entry for entry in report["trace"] if entry["level"] == 0]
        runs.append((path, report, finest))

    best = min(min([report["energy"]] + [e["energy"] for e in finest]) for _, report, finest in runs)
    threshold = best * (1.0 + args.percent / 100.0)
    print(f"E_best = {best:.9g}; threshold (+{args.percent:g}%) = {threshold:.9g}")
    print(f"{'report':40} {'optimizer':>13} {'final E':>12} {'total s':>9} "
          f"{'t(' + format(args.percent, 'g') + '%) s':>10}")
    for path, report, finest in runs:
        reached = next((e["t"] for e in finest if e["energy"] <= threshold), None)
        when = f"{reached:.3f}" if reached is not None else "never"
        print(f"{path:40} {report['optimizer']:>13} {report['energy']:12.6g} "
              f"{report['timings']['total']:9.2f} {when:>10}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
