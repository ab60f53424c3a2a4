#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Writes DIR/report.md for a `harap run` folder: tables, figures (PNG + SVG) and pictures.

Called by `harap report DIR` after it merged the shards into DIR/results.csv; reads
DIR/experiment.json (the plan, with the config's [experiment] and [report] tables) and
DIR/runs/*.json (one `harap deform --report --trace` report per run, plus its `run` entry).

    /usr/bin/python3 experiments/scripts/report.py DIR [--no-render]

[report] keys (all optional; docs/experiments.md):
    claim      what the paper claims (printed beside what we measured)
    notes      remarks, e.g. which shared scenarios stand in for the paper's meshes
    figures    any of "phases", "energy_vs_time", "relative_scatter", "levels", "energy_bars",
               "scaling" (log-log T and peak memory against n, with fitted slopes)
    compare    what is compared: "variant" (default when [[variant]]s exist) or a [grid] key
    baseline   the value of `compare` the others are measured against (default: the first)
    panel      a [grid] key: one panel per value in "relative_scatter" (e.g. the tolerance)
    render     true/false or a list of scenario names: pictures of rest and deformed meshes
               (runs need [run] save_mesh = true); default true
    render_runs  at most this many deformed meshes per scenario picture (default 6)

Pictures are rendered with VTK (Debian python3-vtk9) under xvfb-run; without VTK or Xvfb they
fall back to flat-shaded matplotlib drawings of the same view (say so in the report).
"""
import argparse
import datetime
import json
import math
import os
import platform
import shutil
import statistics
import subprocess
import sys
import time
from collections import OrderedDict, defaultdict

try:
    import matplotlib
    import numpy as np
except ImportError as missing:  # a clear message instead of a traceback
    sys.exit(f"harap report: {sys.executable} cannot import {missing.name}, which the report's "
             "figures need. Install it (Debian: sudo apt-get install python3-matplotlib "
             "python3-numpy; .ci/setup does this) or give harap report --python an interpreter "
             "that has both.")

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

try:
    import tomllib  # Python 3.11
except ImportError:  # pragma: no cover
    tomllib = None

PHASES = [("hierarchy", "H", "#1f77b4"), ("precompute", "P", "#ff7f0e"),
          ("constrain", "C", "#2ca02c"), ("solve", "S", "#d62728")]
# One list for report.py and `harap run`, which checks [report] before any run starts.
with open(os.path.join(os.path.dirname(os.path.abspath(__file__)), "report_keys.json"),
          encoding="utf-8") as _keys_file:
    _KEYS = json.load(_keys_file)
KNOWN_FIGURES = set(_KEYS["figures"])
KNOWN_REPORT_KEYS = set(_KEYS["report_keys"])
_START = time.monotonic()


def progress(message):
    """Plain progress lines on stderr (terminal or pipe alike): what the report is doing."""
    print(f"report: [{time.monotonic() - _START:5.1f} s] {message}", file=sys.stderr, flush=True)


def energy_of(run):
    """What a run's energy value measures: the energy's name and its [energy] settings."""
    config = run["_plan"].get("config", "")
    table = ""
    if tomllib is not None:
        try:
            table = json.dumps(tomllib.loads(config).get("energy", {}), sort_keys=True)
        except tomllib.TOMLDecodeError:
            table = ""
    return (run.get("energy_type", ""), table)


def energy_label(run):
    name, table = energy_of(run)
    settings = json.loads(table) if table else {}
    settings.pop("type", None)
    extra = ", ".join(f"{k}={v}" for k, v in sorted(settings.items()))
    return f"{name}{' (' + extra + ')' if extra else ''}"


# ------------------------------------------------------------------------------------------
# Loading

def load(directory):
    with open(os.path.join(directory, "experiment.json"), encoding="utf-8") as file:
        plan = json.load(file)
    runs = []
    for entry in plan["runs"]:
        path = os.path.join(directory, "runs", entry["id"] + ".json")
        if not os.path.exists(path):
            runs.append({"run": dict(entry, status="missing"), "_plan": entry})
            continue
        with open(path, encoding="utf-8") as file:
            report = json.load(file)
        report["_plan"] = entry
        runs.append(report)
    return plan, runs


def ok(run):
    return run["run"]["status"] == "ok"


def compare_value(run, compare):
    if compare == "variant":
        return run["_plan"]["variant"]
    return run["run"].get("parameters", {}).get(compare, strip(run["_plan"]["parameters"].get(compare, "")))


def strip(literal):
    if len(literal) >= 2 and literal[0] == literal[-1] and literal[0] in "'\"":
        return literal[1:-1]
    return literal


def context_key(run, compare):
    """Everything that identifies a run except the compared value: scenario + other settings."""
    plan = run["_plan"]
    parts = [plan["scenario"]]
    if compare != "variant":
        parts.append(plan["variant"])
    for key, value in plan["parameters"].items():
        if key != compare and not key_of_variant(plan, key):
            parts.append(f"{key}={strip(value)}")
    return tuple(parts)


def key_of_variant(plan, key):
    # Variant settings come first in `parameters`; grid keys are listed in the plan's grid_keys.
    return key not in GRID_KEYS


GRID_KEYS = []


def fmt_number(value, digits=4):
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "–"
    if isinstance(value, int):
        return f"{value:,}"
    if value == 0:
        return "0"
    if abs(value) >= 1e4 or abs(value) < 1e-3:
        return f"{value:.{digits - 1}e}"
    return f"{value:.{digits}g}"


def fmt_seconds(value):
    return "–" if value is None else f"{value:.2f}"


# ------------------------------------------------------------------------------------------
# Figures

def save(fig, directory, name):
    os.makedirs(os.path.join(directory, "figures"), exist_ok=True)
    png = os.path.join("figures", name + ".png")
    svg = os.path.join("figures", name + ".svg")
    fig.savefig(os.path.join(directory, png), dpi=90, bbox_inches="tight")
    fig.savefig(os.path.join(directory, svg), bbox_inches="tight")
    plt.close(fig)
    return png, svg


def run_name(run):
    plan = run["_plan"]
    return plan["label"] or plan["variant"] or "run"


def figure_phases(directory, runs):
    done = [r for r in runs if ok(r)]
    if not done:
        return None
    fig, ax = plt.subplots(figsize=(8, 0.35 * len(done) + 1.2))
    labels = []
    for y, run in enumerate(done):
        left = 0.0
        for key, short, color in PHASES:
            width = run["timings"][key]
            ax.barh(y, width, left=left, color=color, label=short if y == 0 else None)
            left += width
        labels.append(f"{run['_plan']['scenario']}: {run_name(run)}")
    ax.set_yticks(range(len(done)))
    ax.set_yticklabels(labels, fontsize=8)
    ax.invert_yaxis()
    ax.set_xlabel("seconds")
    ax.legend(["hierarchy (H)", "precompute (P)", "constrain (C)", "solve (S)"],
              loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize=8)
    ax.set_title("Time per phase (the paper's Fig. 8)")
    return save(fig, directory, "phases"), (
        "Stacked time per phase: hierarchy (blue), precompute (orange), constrain (green), "
        "solve (red).")


def finest_trace(run):
    return [(e["t"], e["energy"]) for e in run.get("trace", []) if e["level"] == 0]


def figure_energy_vs_time(directory, runs):
    by_scenario = OrderedDict()
    for run in runs:
        if ok(run) and finest_trace(run):
            by_scenario.setdefault(run["_plan"]["scenario"], []).append(run)
    if not by_scenario:
        return None
    count = len(by_scenario)
    columns = min(count, 3)
    rows = math.ceil(count / columns)
    fig, axes = plt.subplots(rows, columns, figsize=(5.2 * columns, 3.8 * rows), squeeze=False)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, (scenario, group) in zip(axes.flat, by_scenario.items()):
        for k, run in enumerate(group):
            trace = finest_trace(run)
            t = np.array([p[0] for p in trace])
            e = np.array([p[1] for p in trace])
            setup = sum(run["timings"][key] for key in ("hierarchy", "precompute", "constrain"))
            color = colors[k % len(colors)]
            # A marker on the last point: a run with one finest-level iteration is one point.
            ax.plot(np.maximum(t - setup, 1e-4), e, "-", color=color, label=run_name(run),
                    marker="o", markersize=3, markevery=[len(t) - 1])
            ax.plot(t, e, "--", color=color, linewidth=0.9, marker="o", markersize=3,
                    markevery=[len(t) - 1])
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(scenario, fontsize=10)
        ax.set_xlabel("seconds (solid: solve only, dashed: with precomputation)", fontsize=8)
        ax.set_ylabel("energy (finest level)", fontsize=8)
        ax.legend(fontsize=7)
        ax.grid(True, which="both", alpha=0.3)
    for ax in list(axes.flat)[count:]:
        ax.axis("off")
    fig.tight_layout()
    return save(fig, directory, "energy_vs_time"), (
        "Energy of the finest level over time (the paper's Fig. 1): solid without, dashed with "
        "the precomputation (hierarchy, precompute, constrain). Hierarchical runs enter the plot "
        "when they reach the finest level.")


def pairs_against_baseline(runs, compare, baseline):
    """(run, baseline run) for every successful non-baseline run with a successful baseline."""
    base = {}
    for run in runs:
        if ok(run) and compare_value(run, compare) == baseline:
            base[context_key(run, compare)] = run
    pairs = []
    for run in runs:
        if ok(run) and compare_value(run, compare) != baseline:
            match = base.get(context_key(run, compare))
            if match is not None:
                pairs.append((run, match))
    return pairs


def quadrant_color(x, y):
    if x < 1 and y < 1:
        return "#2ca02c"  # faster and lower: the ideal
    if x >= 1 and y < 1:
        return "#1f77b4"  # slower, lower energy
    if x < 1 and y >= 1:
        return "#ff7f0e"  # faster, higher energy
    return "#d62728"      # slower and higher


def figure_relative_scatter(directory, runs, compare, baseline, panel):
    pairs = pairs_against_baseline(runs, compare, baseline)
    pairs = [(r, b) for r, b in pairs if b["energy"] > 0 and b["timings"]["total"] > 0]
    # Energy ratios only between runs of the same energy (see measured_summary).
    skipped = sum(1 for r, b in pairs if energy_of(r) != energy_of(b))
    pairs = [(r, b) for r, b in pairs if energy_of(r) == energy_of(b)]
    if not pairs:
        return None
    if panel:
        values = []
        for run, _ in pairs:
            value = run["run"]["parameters"].get(panel, "")
            if value not in values:
                values.append(value)
    else:
        values = [""]
    fig, axes = plt.subplots(1, len(values), figsize=(4.2 * len(values), 4), squeeze=False)
    for ax, value in zip(axes.flat, values):
        points = [(r["timings"]["total"] / b["timings"]["total"], r["energy"] / b["energy"], r)
                  for r, b in pairs if not panel or r["run"]["parameters"].get(panel, "") == value]
        xs = [p[0] for p in points]
        ys = [p[1] for p in points]
        # One marker per compared value (e.g. hierarchical and fast against classic).
        compared = list(OrderedDict.fromkeys(compare_value(r, compare) for _, _, r in points))
        for value_index, compared_value in enumerate(compared):
            own = [(x, y) for x, y, r in points if compare_value(r, compare) == compared_value]
            ax.scatter([x for x, _ in own], [y for _, y in own],
                       c=[quadrant_color(x, y) for x, y in own], s=22,
                       marker="o^sDv"[value_index % 5], edgecolors="black", linewidths=0.3,
                       label=compared_value if len(compared) > 1 else None)
        if len(compared) > 1:
            ax.legend(fontsize=7, loc="upper left")
        ax.axvline(1.0, color="grey", linewidth=0.8)
        ax.axhline(1.0, color="grey", linewidth=0.8)
        ax.set_xscale("log")
        ax.set_yscale("log")
        lo = min(xs + ys + [0.5]) / 1.3
        hi = max(xs + ys + [2.0]) * 1.3
        ax.set_xlim(lo, hi)
        ax.set_ylim(lo, hi)
        ax.set_xlabel("relative total time", fontsize=9)
        ax.set_ylabel("relative final energy", fontsize=9)
        ax.set_title(f"{panel.split('.')[-1]} = {value}" if panel else "", fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
    fig.suptitle(f"{compare} ≠ {baseline}, normalized by {baseline} (the paper's Fig. 11)",
                 fontsize=10)
    fig.tight_layout()
    return save(fig, directory, "relative_scatter"), (
        f"Each point: one scenario, total time and final energy relative to `{baseline}`. Green: "
        "faster and lower energy (the ideal, bottom left); blue: lower energy but slower; "
        "orange: faster but higher energy; red: slower and higher." +
        (f" {skipped} pairs with different energies are left out (their energies are not "
         "comparable)." if skipped else ""))


SIZE_BINS = [(0, 10_000, "< 10K"), (10_000, 50_000, "10K–50K"), (50_000, 100_000, "50K–100K"),
             (100_000, float("inf"), "≥ 100K")]
QUADRANTS = [("bottom-left", "faster, lower"), ("bottom-right", "slower, lower"),
             ("top-left", "faster, higher"), ("top-right", "slower, higher")]


def quadrant_of(run, base):
    """Fig. 11's quadrant of a run against its baseline run (ties count as not better)."""
    faster = run["timings"]["total"] < base["timings"]["total"]
    lower = run["energy"] < base["energy"]
    return {(True, True): 0, (False, True): 1, (True, False): 2, (False, False): 3}[(faster, lower)]


def size_bin(run):
    vertices = run["mesh"]["vertices"]
    return next(label for low, high, label in SIZE_BINS if low <= vertices < high)


def what_happened(run, base):
    """Levels, iterations and per-level energies of a run and its baseline, for the case list."""
    def levels(r):
        return "; ".join(f"L{level['level']} {level['vertices']:,} v: {level['iterations']} it, "
                         f"E {fmt_number(level['energy'], 5)}"
                         f"{'' if level.get('converged', True) else ' (not converged)'}"
                         for level in r.get("levels", []))
    return (f"time {run['timings']['total']:.3g} s vs {base['timings']['total']:.3g} s, energy "
            f"{fmt_number(run['energy'], 6)} vs {fmt_number(base['energy'], 6)} "
            f"(ratio {run['energy'] / base['energy']:.5g}); levels: {levels(run)}; baseline: "
            f"{levels(base)}")


def duration(seconds):
    """Seconds as text with three significant digits, in ms below one second."""
    return f"{seconds * 1e3:.3g} ms" if seconds < 0.9995 else f"{seconds:.3g} s"


def time_to_reach(run, energy):
    """When the run's finest level first had an energy at most `energy` (its trace's clock,
    seconds from the start, setup included), with the finest-level iterations so far; None if
    it never did."""
    for iteration, (t, e) in enumerate(finest_trace(run), start=1):
        if e <= energy + 1e-12 * abs(energy):  # a run reaches its own final energy
            return t, iteration
    return None


def times_at_equal_energy(run, base):
    """time_to_reach() of the run and of its baseline for the higher of their two final
    energies, which both reached: a comparison at equal energy, whatever their stopping tests
    did afterwards. None if either has no finest-level trace to read it from."""
    target = max(run["energy"], base["energy"])
    mine, theirs = time_to_reach(run, target), time_to_reach(base, target)
    return None if mine is None or theirs is None else (mine, theirs)


def equal_energy_ratio(run, base):
    """The run's time at equal energy over the baseline's (times_at_equal_energy)."""
    times = times_at_equal_energy(run, base)
    if times is None or times[1][0] <= 0.0:
        return None
    return times[0][0] / times[1][0]


def why_outside(run, base):
    """A case outside the bottom-left quadrant, explained from the two runs' reports and traces:
    what stopped the run where it stopped, and how the two compare at equal energy."""
    levels, base_levels = run.get("levels", []), base.get("levels", [])
    if not levels or not base_levels:
        return "no per-level data"
    fine, base_fine = levels[0], base_levels[0]
    energy_change = 100.0 * (run["energy"] / base["energy"] - 1.0)
    reasons = []
    if len(levels) == 1:
        if fine["iterations"] == base_fine["iterations"] and run["energy"] == base["energy"]:
            return (f"one level (the mesh is the hierarchy's coarsest), so the baseline's own "
                    f"{fine['iterations']} iterations and energy; only the time differs "
                    f"({duration(run['timings']['total'])} against "
                    f"{duration(base['timings']['total'])})")
        reasons.append(f"one level (the mesh is the hierarchy's coarsest): {fine['iterations']} "
                       f"iterations against {base_fine['iterations']}, energy "
                       f"{energy_change:+.2f}%")
    elif run["energy"] >= base["energy"]:
        plural = "s" if fine["iterations"] != 1 else ""
        if fine.get("converged", True):
            stop = (f"the finest level's convergence test held after {fine['iterations']} "
                    f"iteration{plural} from the up-sampled start")
        else:
            stop = (f"the finest level stopped unconverged after {fine['iterations']} "
                    f"iteration{plural} (an iteration cap, a time budget or a stop)")
        reasons.append(f"{stop}, the baseline's after {base_fine['iterations']}, "
                       f"{energy_change:+.2f}% apart")
    else:
        reasons.append(f"lower energy ({energy_change:+.2f}%) after {fine['iterations']} "
                       f"finest-level iterations against {base_fine['iterations']}")
    slower = run["timings"]["total"] >= base["timings"]["total"]
    if slower and len(levels) > 1:
        if "cg>cholmod" in str(fine.get("solver", "")):
            reasons.append("the finest level iterated (CG), stalled and was factored after all, "
                           "on the critical path (`adaptive:cg>cholmod`)")
        else:
            coarse = sum(level.get("seconds", 0.0) for level in levels[1:])
            reasons.append(f"slower: the baseline needed only {base_fine['iterations']} "
                           f"iterations ({duration(base['timings']['total'])}), and the run "
                           f"spent {duration(run['timings']['hierarchy'])} building the "
                           f"hierarchy and {duration(coarse)} on its {len(levels) - 1} coarse "
                           f"level{'s' if len(levels) > 2 else ''} (set-up and solves)")
    times = times_at_equal_energy(run, base)
    if times is not None:
        mine, theirs = times
        reached = ("the run's final energy" if run["energy"] >= base["energy"]
                   else "the baseline's final energy")
        reasons.append(f"at equal energy ({reached}): {duration(mine[0])} (finest iteration "
                       f"{mine[1]}) against {duration(theirs[0])} (iteration {theirs[1]}), "
                       f"{'faster' if mine[0] < theirs[0] else 'slower'}")
    return "; ".join(reasons)


def repetition_note(runs):
    """A sentence on runs timed by the median of repeated solves (`[run] min_time`), or ""."""
    unique = {id(r): r for r in runs}  # a baseline run sits in one pair per compared value
    counts = [r.get("repetitions", {}).get("count", 1) for r in unique.values()]
    repeated = [c for c in counts if c > 1]
    if not repeated:
        return ""
    times = (f"{min(repeated)}" if min(repeated) == max(repeated)
             else f"{min(repeated)}–{max(repeated)}")
    return (f" {len(repeated)} of these {len(counts)} runs were shorter than `[run] min_time` "
            f"and are timed by the median of {times} repetitions in their process "
            "(docs/experiments.md, \"Timing short runs\").")


def quadrant_section(runs, compare, baseline, panel):
    """Fig. 11's quadrant shares per compared value, panel value (tolerance) and size bin, and
    every case outside the bottom-left quadrant with what happened."""
    pairs = [(r, b) for r, b in pairs_against_baseline(runs, compare, baseline)
             if energy_of(r) == energy_of(b)]
    if not pairs:
        return []
    out = ["## Quadrants (Fig. 11)\n",
           f"Each test case against `{baseline}`: bottom-left = faster and lower final energy. "
           "Shares in percent of the cases in the row (count in brackets)." +
           repetition_note([r for pair in pairs for r in pair]) + "\n"]
    header = [compare, panel.split(".")[-1] if panel else "", "vertices", "cases"] + \
        [f"{name} ({meaning})" for name, meaning in QUADRANTS]
    out.append("| " + " | ".join(header) + " |")
    out.append("|" + "|".join(["---"] * 3 + ["---:"] * 5) + "|")
    groups = OrderedDict()
    at_equal_energy = OrderedDict()  # (value, tolerance): time ratios at equal energy
    untimed = 0  # pairs without a finest-level trace to read the time from
    for run, base in pairs:
        value = compare_value(run, compare)
        tolerance = run["run"]["parameters"].get(panel, "") if panel else ""
        for bin_label in ("all", size_bin(run)):
            groups.setdefault((value, tolerance, bin_label), []).append(quadrant_of(run, base))
        ratio = equal_energy_ratio(run, base)
        if ratio is None:
            untimed += 1
        else:
            at_equal_energy.setdefault((value, tolerance), []).append(ratio)
    order = {label: k for k, (_, _, label) in enumerate(SIZE_BINS)}
    for (value, tolerance, bin_label), quadrants in sorted(
            groups.items(), key=lambda item: (item[0][0], item[0][1],
                                               -1 if item[0][2] == "all" else order[item[0][2]])):
        n = len(quadrants)
        shares = [f"{100 * quadrants.count(q) / n:.0f}% ({quadrants.count(q)})" for q in range(4)]
        out.append(f"| {value} | {tolerance} | {bin_label} | {n} | " + " | ".join(shares) + " |")
    out.append("")
    if at_equal_energy:
        out.append(f"At equal energy (each pair timed to the higher of its two final energies, "
                   f"from the finest level's trace; the stopping test left out), against "
                   f"`{baseline}`:\n")
        for (value, tolerance), ratios in sorted(at_equal_energy.items()):
            faster = sum(1 for ratio in ratios if ratio < 1.0)
            where = f", {panel.split('.')[-1]} {tolerance}" if panel else ""
            out.append(f"- {value}{where}: faster in {faster} of {len(ratios)} cases "
                       f"({100 * faster / len(ratios):.0f}%), median time ratio "
                       f"{statistics.median(ratios):.3g}")
        if untimed:
            out.append(f"- {untimed} pairs left out: a run without a finest-level trace")
        out.append("")
    outside = [(r, b) for r, b in pairs if quadrant_of(r, b) != 0]
    if outside:
        out.append(f"### Cases outside the bottom-left quadrant ({len(outside)})\n")
        for run, base in outside:
            plan = run["_plan"]
            name, meaning = QUADRANTS[quadrant_of(run, base)]
            out.append(f"- **{plan['scenario']}** ({markdown_escape(run_name(run))}), "
                       f"{run['mesh']['vertices']:,} vertices, {name} ({meaning}). "
                       f"Why: {markdown_escape(why_outside(run, base))}. Data: "
                       f"{markdown_escape(what_happened(run, base))}")
        out.append("")
    else:
        out.append("Every case is in the bottom-left quadrant.\n")
    return out


def figure_levels(directory, runs):
    done = [r for r in runs if ok(r) and len(r.get("levels", [])) > 1]
    if not done:
        return None
    fig, (ax_time, ax_iterations) = plt.subplots(1, 2, figsize=(11, 0.35 * len(done) + 1.5))
    depth = max(len(r["levels"]) for r in done)
    cmap = plt.get_cmap("viridis", depth)
    labels = []
    for y, run in enumerate(done):
        left_time = left_iterations = 0.0
        for level in run["levels"]:
            color = cmap(level["level"])
            ax_time.barh(y, level["seconds"], left=left_time, color=color)
            ax_iterations.barh(y, level["iterations"], left=left_iterations, color=color)
            left_time += level["seconds"]
            left_iterations += level["iterations"]
        labels.append(f"{run['_plan']['scenario']}: {run_name(run)}")
    for ax in (ax_time, ax_iterations):
        ax.set_yticks(range(len(done)))
        ax.invert_yaxis()
    ax_time.set_yticklabels(labels, fontsize=8)
    ax_iterations.set_yticklabels([])
    ax_time.set_xlabel("seconds per level (precompute, factorization and iterations)")
    ax_iterations.set_xlabel("iterations per level")
    handles = [plt.Rectangle((0, 0), 1, 1, color=cmap(level)) for level in range(depth)]
    ax_iterations.legend(handles, [f"level {level}" for level in range(depth)], fontsize=7,
                         loc="center left", bbox_to_anchor=(1.01, 0.5))
    fig.tight_layout()
    return save(fig, directory, "levels"), (
        "Seconds (precomputation, factorization and iterations) and iterations per hierarchy "
        "level (level 0 is the input mesh).")


def figure_scaling(directory, runs, compare):
    """Log-log total time and peak memory against the vertex count, one line per compared
    value, with the least-squares slope of log T and log M over log n."""
    done = [r for r in runs if ok(r) and r.get("mesh", {}).get("vertices")]
    groups = OrderedDict()
    for run in done:
        groups.setdefault(str(compare_value(run, compare)), []).append(run)
    groups = OrderedDict((k, v) for k, v in groups.items()
                         if len({r["mesh"]["vertices"] for r in v}) >= 2)
    if not groups:
        return None
    fig, (ax_time, ax_memory) = plt.subplots(1, 2, figsize=(11, 4.2))
    slopes = []
    for name, group in groups.items():
        group = sorted(group, key=lambda r: r["mesh"]["vertices"])
        n = np.array([r["mesh"]["vertices"] for r in group], dtype=float)
        seconds = np.array([r["timings"]["total"] for r in group], dtype=float)
        memory = np.array([r["peak_memory_bytes"] for r in group], dtype=float)
        time_slope = np.polyfit(np.log(n), np.log(seconds), 1)[0]
        memory_slope = np.polyfit(np.log(n), np.log(memory), 1)[0]
        per_vertex = memory[-1] / n[-1] / 1024
        ax_time.loglog(n, seconds, "o-", label=f"{name} (slope {time_slope:.2f})")
        ax_memory.loglog(n, memory / 2**20, "o-", label=f"{name} (slope {memory_slope:.2f})")
        slopes.append(f"{name}: T ∝ n^{time_slope:.2f}, M ∝ n^{memory_slope:.2f}, "
                      f"{per_vertex:.2f} KB per vertex at n = {int(n[-1]):,}")
    ax_time.set_xlabel("vertices n")
    ax_time.set_ylabel("total seconds T")
    ax_memory.set_xlabel("vertices n")
    ax_memory.set_ylabel("peak memory M (MiB)")
    for ax in (ax_time, ax_memory):
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    return save(fig, directory, "scaling"), (
        "Total time and peak memory against the vertex count (log-log); the slopes are least-"
        "squares fits of log T and log M over log n. " + "; ".join(slopes) + ".")


def figure_energy_bars(directory, runs):
    done = [r for r in runs if ok(r)]
    scenarios = list(OrderedDict.fromkeys(r["_plan"]["scenario"] for r in done))
    names = list(OrderedDict.fromkeys(run_name(r) for r in done))
    if not done:
        return None
    fig, axes = plt.subplots(1, 2, figsize=(11, 0.9 + 0.35 * len(scenarios) * len(names) / 2))
    for ax, metric, title in ((axes[0], "energy", "final energy above the scenario's best run, %"),
                              (axes[1], "total", "total seconds")):
        for s, scenario in enumerate(scenarios):
            group = [r for r in done if r["_plan"]["scenario"] == scenario]
            best = min(r["energy"] for r in group) or 1.0
            for k, name in enumerate(names):
                match = [r for r in group if run_name(r) == name]
                if not match:
                    continue
                r = match[0]
                value = (100.0 * (r["energy"] / best - 1.0) if metric == "energy"
                         else r["timings"]["total"])
                y = s * (len(names) + 1) + k
                ax.barh(y, value, color=plt.rcParams["axes.prop_cycle"].by_key()["color"][
                    k % 10], label=name if s == 0 else None)
        ax.set_yticks([s * (len(names) + 1) + (len(names) - 1) / 2 for s in range(len(scenarios))])
        ax.set_yticklabels(scenarios, fontsize=8)
        ax.invert_yaxis()
        ax.set_title(title, fontsize=10)
    axes[1].legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))
    fig.tight_layout()
    mixed = len({energy_of(r) for r in done}) > 1
    return save(fig, directory, "energy_bars"), (
        "Final energy above the lowest energy among the runs of the same scenario (in percent; "
        "0 for the best run) and total time per run." +
        (" ⚠ The runs use different energies, whose values are not comparable: read the energy "
         "bars within runs of the same energy only." if mixed else ""))


# ------------------------------------------------------------------------------------------
# Pictures

def read_ply(path):
    with open(path, "rb") as file:
        header = []
        while True:
            line = file.readline().decode("ascii", "replace").strip()
            header.append(line)
            if line == "end_header":
                break
        vertices = faces = 0
        vertex_type = "f8"
        for line in header:
            parts = line.split()
            if parts[:2] == ["element", "vertex"]:
                vertices = int(parts[2])
            elif parts[:2] == ["element", "face"]:
                faces = int(parts[2])
            elif parts[:2] == ["property", "float"] and parts[2] == "x":
                vertex_type = "f4"
        positions = np.frombuffer(file.read(vertices * 3 * int(vertex_type[1])),
                                  dtype="<" + vertex_type).reshape(vertices, 3).astype(float)
        data = np.frombuffer(file.read(), dtype=np.uint8)
    # Faces: uchar count + count int32 indices; harap writes triangles only.
    records = data[: faces * 13].reshape(faces, 13)
    if faces and not np.all(records[:, 0] == 3):
        raise ValueError(f"{path}: only triangle PLY files are supported")
    triangles = records[:, 1:].copy().view("<i4").reshape(faces, 3)
    return positions, triangles


def handle_labels(path, count):
    labels = np.zeros(count, dtype=int)
    if path and os.path.exists(path):
        with open(path, encoding="utf-8") as file:
            for k, handle in enumerate(json.load(file)["handles"]):
                labels[np.asarray(handle["vertices"], dtype=int)] = k + 1
    return labels


HANDLE_COLORS = np.array([[0.80, 0.80, 0.78], [0.20, 0.40, 0.85], [0.85, 0.25, 0.20],
                          [0.20, 0.70, 0.30], [0.85, 0.60, 0.10]])


VIEW_TILT_DEGREES = 25.0


def view_frame(rest, deformed_list):
    """Camera axes: look along the axis where rest and deformed meshes are thinnest (so the
    deformation lies mostly in the picture), tilted about the up axis for depth."""
    stacked = np.vstack([rest] + deformed_list)
    extent = stacked.max(axis=0) - stacked.min(axis=0)
    view = int(np.argmin(extent))
    rest_extent = rest.max(axis=0) - rest.min(axis=0)
    others = [d for d in range(3) if d != view]
    up = max(others, key=lambda d: rest_extent[d])
    center = (stacked.max(axis=0) + stacked.min(axis=0)) / 2
    radius = np.linalg.norm(extent) / 2
    return view, up, center, radius


def view_direction(view, up):
    right = [d for d in range(3) if d not in (view, up)][0]
    tilt = math.radians(VIEW_TILT_DEGREES)
    direction = np.zeros(3)
    direction[view] = math.cos(tilt)
    direction[right] = math.sin(tilt)
    return direction


def render_vtk(panels, size):
    """Renders each (positions, triangles, labels) panel to an RGB array with VTK."""
    import vtk
    from vtk.util import numpy_support

    images = []
    rest = panels[0][0]
    view, up, center, radius = view_frame(rest, [p[0] for p in panels[1:]])
    for positions, triangles, labels in panels:
        points = vtk.vtkPoints()
        points.SetData(numpy_support.numpy_to_vtk(np.ascontiguousarray(positions), deep=True))
        cells = np.hstack([np.full((len(triangles), 1), 3, dtype=np.int64),
                           triangles.astype(np.int64)]).ravel()
        polys = vtk.vtkCellArray()
        polys.SetCells(len(triangles), numpy_support.numpy_to_vtkIdTypeArray(cells, deep=True))
        mesh = vtk.vtkPolyData()
        mesh.SetPoints(points)
        mesh.SetPolys(polys)
        colors = (HANDLE_COLORS[np.minimum(labels, len(HANDLE_COLORS) - 1)] * 255).astype(np.uint8)
        color_array = numpy_support.numpy_to_vtk(colors, deep=True)
        color_array.SetName("colors")
        mesh.GetPointData().SetScalars(color_array)
        normals = vtk.vtkPolyDataNormals()
        normals.SetInputData(mesh)
        normals.SplittingOff()
        mapper = vtk.vtkPolyDataMapper()
        mapper.SetInputConnection(normals.GetOutputPort())
        mapper.SetColorModeToDirectScalars()
        actor = vtk.vtkActor()
        actor.SetMapper(mapper)
        actor.GetProperty().SetInterpolationToPhong()
        actor.GetProperty().SetSpecular(0.15)
        renderer = vtk.vtkRenderer()
        renderer.AddActor(actor)
        renderer.SetBackground(1.0, 1.0, 1.0)
        window = vtk.vtkRenderWindow()
        window.SetOffScreenRendering(1)
        window.AddRenderer(renderer)
        window.SetSize(size, size)
        camera = renderer.GetActiveCamera()
        direction = view_direction(view, up)
        up_vector = np.zeros(3)
        up_vector[up] = 1.0
        camera.SetFocalPoint(*center)
        camera.SetPosition(*(center + direction * radius * 4.0))
        camera.SetViewUp(*up_vector)
        camera.SetViewAngle(30.0)
        renderer.ResetCameraClippingRange()
        window.Render()
        grab = vtk.vtkWindowToImageFilter()
        grab.SetInput(window)
        grab.Update()
        image = grab.GetOutput()
        width, height, _ = image.GetDimensions()
        pixels = numpy_support.vtk_to_numpy(image.GetPointData().GetScalars())
        images.append(pixels.reshape(height, width, -1)[::-1, :, :3])
        window.Finalize()
    return images


def render_matplotlib(panels, size):
    """Fallback without VTK/Xvfb: the same camera as render_vtk (orthographic), faces drawn flat
    shaded with the painter's algorithm in a 2D plot. All panels share one screen frame, fitted
    to the projected meshes, so the mesh fills its panel and the panels compare at one scale.
    Returns images sized to that frame's aspect (longer side `size` pixels)."""
    from matplotlib.collections import PolyCollection

    rest = panels[0][0]
    view, up, center, _ = view_frame(rest, [p[0] for p in panels[1:]])
    towards = view_direction(view, up)  # from the mesh towards the camera
    up_vector = np.zeros(3)
    up_vector[up] = 1.0
    right_vector = np.cross(up_vector, towards)
    right_vector /= np.linalg.norm(right_vector)
    screen = np.stack([right_vector, up_vector], axis=1)
    # One frame for all panels: the projected bounding box of every mesh, with a small margin.
    projected = [(positions - center) @ screen for positions, _, _ in panels]
    low = np.min([p.min(axis=0) for p in projected], axis=0)
    high = np.max([p.max(axis=0) for p in projected], axis=0)
    extent = np.maximum(high - low, 1e-12 * max(1.0, float(np.max(high - low))))
    margin = 0.03 * extent.max()
    low, high = low - margin, high + margin
    aspect = float(np.clip((high[1] - low[1]) / (high[0] - low[0]), 0.25, 4.0))
    width_px, height_px = (size, size * aspect) if aspect <= 1 else (size / aspect, size)
    light = towards + 0.5 * up_vector - 0.4 * right_vector  # from the upper left
    light /= np.linalg.norm(light)

    images = []
    for (positions, triangles, labels), flat in zip(panels, projected):
        corners = positions[triangles]
        normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        lengths = np.linalg.norm(normals, axis=1, keepdims=True)
        normals = normals / np.maximum(lengths, 1e-300)
        # Two-sided: open meshes show both sides.
        shade = 0.3 + 0.7 * np.abs(normals @ light)
        depth = ((corners.mean(axis=1) - center) @ towards)
        order = np.argsort(depth)  # far faces first
        base = HANDLE_COLORS[np.minimum(labels[triangles].max(axis=1), len(HANDLE_COLORS) - 1)]
        colors = np.clip(base * shade[:, None], 0, 1)[order]
        fig = plt.figure(figsize=(width_px / 100, height_px / 100), dpi=100)
        ax = fig.add_axes([0, 0, 1, 1])
        ax.add_collection(PolyCollection(flat[triangles[order]], facecolors=colors,
                                         edgecolors=colors, linewidths=0.2, antialiased=True))
        ax.set_xlim(low[0], high[0])
        ax.set_ylim(low[1], high[1])
        ax.set_aspect("auto")
        ax.set_axis_off()
        fig.canvas.draw()
        images.append(np.asarray(fig.canvas.buffer_rgba())[:, :, :3].copy())
        plt.close(fig)
    return images


def render_pictures(directory, runs, selection, per_scenario, use_vtk):
    """One PNG per scenario: rest mesh with handles, then the deformed meshes."""
    by_scenario = OrderedDict()
    for run in runs:
        info = run["run"]
        if ok(run) and info.get("mesh") and os.path.exists(os.path.join(directory, info["mesh"])):
            scenario = run["_plan"]["scenario"]
            if selection is True or scenario in selection:
                by_scenario.setdefault(scenario, []).append(run)
    results = []
    renderer = render_vtk if use_vtk else render_matplotlib
    os.makedirs(os.path.join(directory, "pictures"), exist_ok=True)
    for number, (scenario, group) in enumerate(by_scenario.items(), 1):
        if not use_vtk:
            progress(f"picture {number}/{len(by_scenario)}: {scenario}")
        group = group[:per_scenario]
        info = group[0]["run"]
        rest_path = os.path.join(directory, info["rest_mesh"])
        if not os.path.exists(rest_path):
            continue
        rest, triangles = read_ply(rest_path)
        labels = handle_labels(os.path.join(directory, info.get("handles", "")), len(rest))
        panels = [(rest, triangles, labels)]
        titles = ["rest (handles coloured)"]
        for run in group:
            deformed, _ = read_ply(os.path.join(directory, run["run"]["mesh"]))
            panels.append((deformed, triangles, labels))
            titles.append(f"{run_name(run)}\nE = {fmt_number(run['energy'])}, "
                          f"T = {run['timings']['total']:.2f} s")
        images = renderer(panels, 420)
        # Panels as tall as the pictures need (wide meshes get short panels, not white bands),
        # plus room for two title lines.
        aspect = images[0].shape[0] / images[0].shape[1]
        panel_width = 2.8
        picture_height = min(panel_width * aspect, 4.5)
        # Constrained layout keeps the suptitle clear of the panel titles (tight_layout does not).
        fig, axes = plt.subplots(1, len(images),
                                 figsize=(panel_width * len(images), picture_height + 0.9),
                                 squeeze=False, layout="constrained")
        for ax, image, title in zip(axes.flat, images, titles):
            ax.imshow(image)
            ax.set_title(title, fontsize=9)
            ax.axis("off")
        fig.suptitle(scenario, fontsize=11)
        path = os.path.join("pictures", f"{scenario}.png")
        fig.savefig(os.path.join(directory, path), dpi=100, bbox_inches="tight")
        plt.close(fig)
        results.append((scenario, path))
    return results


# ------------------------------------------------------------------------------------------
# Text

# ------------------------------------------------------------------------------------------
# Registration experiments ([known_answers]: `harap register ... --answer`)

def is_registration(run):
    return run.get("command") == "register"


def answer_errors(run):
    """(mean, max) vertex error against the known answer, in % of the diagonal, or None."""
    answer = run.get("answer")
    if not answer:
        return None
    return 100.0 * answer["mean_error_relative"], 100.0 * answer["max_error_relative"]


def registration_summary(runs, compare, baseline):
    """Per compared value: time against `baseline` and the answer errors of both."""
    lines = []
    by_value = OrderedDict()
    for run, base in pairs_against_baseline(runs, compare, baseline):
        by_value.setdefault(compare_value(run, compare), []).append((run, base))
    for value, group in by_value.items():
        n = len(group)
        t_ratio = [r["timings"]["total"] / b["timings"]["total"] for r, b in group
                   if b["timings"]["total"] > 0]
        faster = sum(1 for r, b in group if r["timings"]["total"] < b["timings"]["total"])
        errors = [(answer_errors(r), answer_errors(b)) for r, b in group]
        errors = [(e, f) for e, f in errors if e and f]
        text = (f"**{value}** vs **{baseline}** ({n} {'case' if n == 1 else 'cases'}): faster in "
                f"{faster}/{n}")
        if t_ratio:
            text += (f", median total-time ratio {statistics.median(t_ratio):.3g} "
                     f"(range {min(t_ratio):.3g}–{max(t_ratio):.3g})")
        if errors:
            lower = sum(1 for e, f in errors if e[0] < f[0])
            text += (f"; lower mean error in {lower}/{len(errors)}; median mean error "
                     f"{statistics.median(e[0] for e, _ in errors):.3g}% vs "
                     f"{statistics.median(f[0] for _, f in errors):.3g}% of the diagonal")
        lines.append(text + ".")
    return lines


def runs_table_head(columns, alignments):
    """The "## Runs" heading and a Markdown table head; alignments: "---" or "---:" per column."""
    return ["## Runs\n", "| " + " | ".join(columns) + " |", "|" + "|".join(alignments) + "|"]


def unfinished_row(run, columns):
    """A table row for a run that did not finish: its scenario, label, status and error."""
    error = run["run"].get("error", "not run yet")
    return (f"| {run['_plan']['scenario']} | | {markdown_escape(run_name(run))} | "
            f"{run['run']['status']}: {markdown_escape(error)} " + "|" * (columns - 3))


def registration_table(runs):
    columns = ["case", "V", "run", "target", "updates", "iterations", "mean error %",
               "max error %", "residual RMS %", "ARAP energy", "T (s)"]
    out = runs_table_head(columns, ["---", "---:", "---", "---:"] + ["---:"] * 7)
    for run in runs:
        plan_entry = run["_plan"]
        if not ok(run):
            out.append(unfinished_row(run, len(columns)))
            continue
        errors = answer_errors(run)
        target = run["target"]
        out.append(
            f"| {plan_entry['scenario']} | {run['source']['vertices']:,} | "
            f"{markdown_escape(run_name(run))} | {target['points']:,} {target['kind']} | "
            f"{run['correspondence_updates']} | {run['iterations']} | "
            f"{fmt_number(errors[0], 3) if errors else '–'} | "
            f"{fmt_number(errors[1], 3) if errors else '–'} | "
            f"{fmt_number(100.0 * run['residual']['rms_relative'], 3)} | "
            f"{fmt_number(run['arap_energy'], 5)} | {fmt_seconds(run['timings']['total'])} |")
    out.append("\nErrors |u − U| against the known answer and the residual (distance to the "
               "target) in % of the rest mesh's bounding-box diagonal; updates: correspondence "
               "updates over all levels; T: total seconds (the target's search tree included). "
               "The cases (source, target, answer) are in `cases/`, per-run JSON reports in "
               "`runs/`, all rows in `results.csv`.\n")
    return out


def deformation_table(runs):
    columns = ["scenario", "V", "run", "H", "P", "C", "S", "T", "E", "M (MiB)",
               "iterations per level", "conv."]
    out = runs_table_head(columns, ["---", "---:", "---"] + ["---:"] * 7 + ["---", "---"])
    for run in runs:
        plan_entry = run["_plan"]
        if not ok(run):
            out.append(unfinished_row(run, len(columns)))
            continue
        t = run["timings"]
        levels = ", ".join(str(level["iterations"]) for level in run.get("levels", []))
        out.append(
            f"| {plan_entry['scenario']} | {run['mesh']['vertices']:,} | "
            f"{markdown_escape(run_name(run))} | "
            f"{fmt_seconds(t['hierarchy']) if len(run.get('levels', [])) > 1 else '–'} | "
            f"{fmt_seconds(t['precompute'])} | {fmt_seconds(t['constrain'])} | "
            f"{fmt_seconds(t['solve'])} | {fmt_seconds(t['total'])} | "
            f"{fmt_number(run['energy'], 5)} | {run['peak_memory_bytes'] / 2**20:.0f} | "
            f"{levels} | {'yes' if run['converged'] else 'no'} |")
    out.append("\nH hierarchy, P precompute, C constrain (factorization), S solve, T total, in "
               "seconds; E final energy (rotations re-fitted); M peak memory of the run's process. "
               "Per-run JSON reports (with the energy trace) are in `runs/`, all rows in "
               "`results.csv`.\n")
    return out


def measured_summary(runs, compare, baseline):
    lines = []
    pairs = pairs_against_baseline(runs, compare, baseline)
    by_value = OrderedDict()
    for run, base in pairs:
        by_value.setdefault(compare_value(run, compare), []).append((run, base))
    for value, group in by_value.items():
        n = len(group)
        different = sorted({(energy_label(r), energy_label(b)) for r, b in group
                            if energy_of(r) != energy_of(b)})
        if different:
            # Values of different functionals: no "lower energy" or energy ratio between them.
            t_ratio = [r["timings"]["total"] / b["timings"]["total"] for r, b in group
                       if b["timings"]["total"] > 0]
            faster = sum(1 for r, b in group if r["timings"]["total"] < b["timings"]["total"])
            text = (f"**{value}** vs **{baseline}** ({n} {'pair' if n == 1 else 'pairs'}): "
                    f"⚠ different energies ({'; '.join(f'{a} vs {b}' for a, b in different)}), "
                    "so their values are not compared; faster in total in "
                    f"{faster}/{n}")
            if t_ratio:
                text += f", median total-time ratio {statistics.median(t_ratio):.3g}"
            lines.append(text + ".")
            continue
        e_ratio = [r["energy"] / b["energy"] for r, b in group if b["energy"] > 0]
        t_ratio = [r["timings"]["total"] / b["timings"]["total"] for r, b in group
                   if b["timings"]["total"] > 0]
        s_ratio = [r["timings"]["solve"] / b["timings"]["solve"] for r, b in group
                   if b["timings"]["solve"] > 0]
        lower = sum(1 for r, b in group if r["energy"] < b["energy"])
        faster = sum(1 for r, b in group if r["timings"]["total"] < b["timings"]["total"])
        both = sum(1 for r, b in group if r["energy"] < b["energy"]
                   and r["timings"]["total"] < b["timings"]["total"])
        text = (f"**{value}** vs **{baseline}** ({n} {'pair' if n == 1 else 'pairs'}): lower energy in {lower}/{n}, "
                f"faster in total in {faster}/{n}, both in {both}/{n}")
        if e_ratio:
            text += (f"; median energy ratio {statistics.median(e_ratio):.4g} "
                     f"(range {min(e_ratio):.4g}–{max(e_ratio):.4g})")
        if t_ratio:
            text += f", median total-time ratio {statistics.median(t_ratio):.3g}"
        if s_ratio:
            text += f", median solve-time ratio {statistics.median(s_ratio):.3g}"
        lines.append(text + ".")
    return lines


def machine_note(runs):
    threads = sorted({r["run"].get("threads") for r in runs if r["run"].get("threads")})
    jobs = sorted({r["run"].get("jobs") for r in runs if r["run"].get("jobs")})
    cpu = ""
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as file:
            for line in file:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    load = ""
    if hasattr(os, "getloadavg"):
        load = ", load average at report time {:.2f} {:.2f} {:.2f}".format(*os.getloadavg())
    return (f"{platform.node() or 'this machine'}: {os.cpu_count()} cores ({cpu or 'unknown CPU'})"
            f"{load}; threads per run {', '.join(map(str, threads)) or '?'}, "
            f"concurrent runs (--jobs) {', '.join(map(str, jobs)) or '?'}. Timings on a shared "
            "machine are noisy (±10–15% and more while others build); energies are exact.")


def markdown_escape(text):
    return str(text).replace("|", "\\|").replace("\n", " ")


def report_settings(plan, runs):
    """The config's [report] table, checked, with its defaults filled in."""
    report = plan.get("report", {})
    unknown = set(report) - KNOWN_REPORT_KEYS
    if unknown:
        sys.exit(f"{plan.get('config_file')}: unknown [report] keys {sorted(unknown)}; valid: "
                 f"{sorted(KNOWN_REPORT_KEYS)}")
    figures = report.get("figures", ["phases", "energy_vs_time"])
    for figure in figures:
        if figure not in KNOWN_FIGURES:
            sys.exit(f"{plan.get('config_file')}: [report] figures: unknown '{figure}'; valid: "
                     f"{sorted(KNOWN_FIGURES)}")
    has_variants = any(r["variant"] for r in plan["runs"])
    compare = report.get("compare", "variant" if has_variants else (GRID_KEYS[0] if GRID_KEYS else ""))
    values = list(OrderedDict.fromkeys(compare_value(r, compare) for r in runs)) if compare else []
    return {
        "report": report,
        "figures": figures,
        "compare": compare,
        "baseline": report.get("baseline", values[0] if values else ""),
        "render": report.get("render", True),
        "per_scenario": int(report.get("render_runs", 6)),
    }


def header_section(plan, runs, directory):
    """Title, description, the commands that made the report, run counts and the machine."""
    out = []
    title = plan.get("title") or plan.get("name")
    out.append(f"# {title}\n")
    if plan.get("description"):
        out.append(plan["description"] + "\n")
    config_file = plan.get("config_file", "")
    relative_config = os.path.relpath(config_file) if config_file else "CONFIG.toml"
    out.append("```bash\n"
               f"./build/harap run {relative_config} --out {directory}\n"
               f"./build/harap report {directory}\n```\n")
    statuses = defaultdict(int)
    for run in runs:
        statuses[run["run"]["status"]] += 1
    out.append(f"Runs: {len(runs)} planned — " +
               ", ".join(f"{count} {status}" for status, count in sorted(statuses.items())) + ".\n")
    out.append(f"Machine: {machine_note(runs)} Generated "
               f"{datetime.datetime.now().strftime('%Y-%m-%d %H:%M')}.\n")
    return out


def claim_section(runs, settings, registration):
    """The config's claim beside what the runs measured, then the main table."""
    report, compare, baseline = settings["report"], settings["compare"], settings["baseline"]
    summarize = registration_summary if registration else measured_summary
    measured = summarize(runs, compare, baseline) if compare else []
    out = ["## Paper vs. measured\n", "| the paper claims | we measured |\n| --- | --- |"]
    claim = report.get("claim", "(no claim given in the config)")
    out.append(f"| {markdown_escape(claim)} | "
               f"{markdown_escape('<br>'.join(measured) or 'no comparable pairs of runs')} |\n")
    if report.get("notes"):
        out.append(f"Notes: {report['notes']}\n")
    out.extend(registration_table(runs) if registration else deformation_table(runs))
    return out


def figures_section(directory, runs, settings):
    """Each figure the config asks for, or why it has no data."""
    figures, compare, baseline = settings["figures"], settings["compare"], settings["baseline"]
    out = ["## Figures\n"] if figures else []
    for number, figure in enumerate(figures, 1):
        progress(f"figure {number}/{len(figures)}: {figure}")
        if figure == "phases":
            made = figure_phases(directory, runs)
        elif figure == "energy_vs_time":
            made = figure_energy_vs_time(directory, runs)
        elif figure == "relative_scatter":
            made = figure_relative_scatter(directory, runs, compare, baseline,
                                           settings["report"].get("panel", ""))
        elif figure == "levels":
            made = figure_levels(directory, runs)
        elif figure == "scaling":
            made = figure_scaling(directory, runs, compare)
        else:
            made = figure_energy_bars(directory, runs)
        if made is None:
            out.append(f"- {figure}: no data (no successful run with what it needs)\n")
            continue
        (png, svg), caption = made
        out.append(f"![{figure}]({png})\n\n{caption} ([SVG]({svg}))\n")
    return out


def pictures_section(directory, runs, settings, backend):
    """The rest and deformed meshes, rendered, or why there are none."""
    progress("pictures of the meshes (VTK under Xvfb if available, else matplotlib)")
    pictures, used = make_pictures(directory, runs, settings["render"], settings["per_scenario"],
                                   backend)
    if pictures:
        out = ["## Pictures\n",
               f"Rendered with {used}; rest mesh with the handles coloured (blue: first handle, "
               "red: second), then the deformed meshes of the runs, seen along the axis where "
               "the shapes are thinnest.\n"]
        out.extend(f"![{scenario}]({path})\n" for scenario, path in pictures)
        return out
    if not any(r["run"].get("mesh") for r in runs):
        return ["No pictures: the config does not save meshes (`[run] save_mesh = true`).\n"]
    return []


def failed_section(runs):
    """Every run that failed, with its reason."""
    failed = [r for r in runs if r["run"]["status"] not in ("ok", "missing")]
    if not failed:
        return []
    out = ["## Failed runs\n"]
    for run in failed:
        out.append(f"- `{run['run']['id']}` ({markdown_escape(run_name(run))}): "
                   f"{markdown_escape(run['run'].get('error', ''))}")
    out.append("")
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("directory")
    parser.add_argument("--no-render", action="store_true", help="skip the mesh pictures")
    parser.add_argument("--render-backend", choices=["auto", "vtk", "matplotlib"], default="auto")
    parser.add_argument("--render-child", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    directory = args.directory

    progress(f"reading {directory}")
    plan, runs = load(directory)
    progress(f"{len(runs)} runs, {sum(1 for r in runs if ok(r))} finished")
    GRID_KEYS[:] = plan.get("grid_keys", [])
    settings = report_settings(plan, runs)

    if args.render_child:
        # Runs under xvfb-run: only the pictures, written as a JSON list for the parent.
        pictures = render_pictures(directory, runs, settings["render"], settings["per_scenario"],
                                   use_vtk=True)
        print(json.dumps(pictures))
        return 0

    registration = any(is_registration(r) for r in runs)
    if registration:
        # The energy figures and the handle pictures do not apply to registrations: the table
        # and the comparison with the baseline say it all.
        settings["figures"] = []
        settings["render"] = False

    out = header_section(plan, runs, directory)
    out.extend(claim_section(runs, settings, registration))
    out.extend(figures_section(directory, runs, settings))
    if settings["render"] and not args.no_render:
        out.extend(pictures_section(directory, runs, settings, args.render_backend))
    if "relative_scatter" in settings["figures"] and settings["compare"]:
        out.extend(quadrant_section(runs, settings["compare"], settings["baseline"],
                                    settings["report"].get("panel", "")))
    out.extend(failed_section(runs))

    with open(os.path.join(directory, "report.md"), "w", encoding="utf-8") as file:
        file.write("\n".join(out) + "\n")
    progress("done")
    print(f"wrote {os.path.join(directory, 'report.md')}")
    return 0


def make_pictures(directory, runs, render, per_scenario, backend):
    """VTK under xvfb-run in a child process; flat-shaded matplotlib if that is not possible."""
    if backend in ("auto", "vtk"):
        xvfb = shutil.which("xvfb-run")
        try:
            import vtk  # noqa: F401
            has_vtk = True
        except ImportError:
            has_vtk = False
        if xvfb and has_vtk:
            command = [xvfb, "-a", "-s", "-screen 0 1280x1024x24", sys.executable,
                       os.path.abspath(__file__), directory, "--render-child"]
            # Two tries: `xvfb-run -a` can lose the race for a display number to another user.
            for _ in range(2):
                result = subprocess.run(command, capture_output=True, text=True, check=False)
                lines = [line for line in result.stdout.splitlines() if line.startswith("[")]
                if result.returncode == 0 and lines:
                    return [tuple(p) for p in json.loads(lines[-1])], "VTK (offscreen, Xvfb)"
            print(f"VTK rendering failed ({result.stderr.strip()[-400:]}); using matplotlib",
                  file=sys.stderr)
        elif backend == "vtk":
            print("VTK or xvfb-run missing; using matplotlib", file=sys.stderr)
    pictures = render_pictures(directory, runs, render, per_scenario, use_vtk=False)
    return pictures, "matplotlib, flat shaded (fallback: VTK or Xvfb not available)"


if __name__ == "__main__":
    sys.exit(main())
