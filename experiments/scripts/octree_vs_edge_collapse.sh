#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Octree vs edge-collapse hierarchy (the paper's Fig. 18): hierarchical ARAP with each
# hierarchy on the shared scenarios, default options otherwise (tolerance 1e-6, spokes_and_rims,
# cholmod, rotations upsampler; edge_collapse targets the octree's level vertex counts). Writes
# one report per run and prints the table of docs/results.md.
#
#   experiments/scripts/octree_vs_edge_collapse.sh [OUT_DIR] [SCENARIO ...]
#
# Run from the repository root after building (build/harap); ../shared must be present.
set -euo pipefail
out=${1:-octree-vs-edge-collapse}
shift || true
scenarios=("$@")
[ ${#scenarios[@]} -gt 0 ] || scenarios=(armadillo-bend buddha-twist cow-stretch dragon-lift)
mkdir -p "$out"
for s in "${scenarios[@]}"; do
  for h in octree edge_collapse; do
    ./build/harap deform "../shared/scenarios/$s.toml" --optimizer hierarchical --hierarchy "$h" \
      --report "$out/$s-$h.json" -q
  done
done
python3 - "$out" "${scenarios[@]}" <<'PY'
import json
import sys

out, scenarios = sys.argv[1], sys.argv[2:]
print("| scenario | V | hierarchy | H s | P s | C s | S s | T s | E | level vertices (finest first) "
      "| iterations per level |")
print("|---|---:|---|---:|---:|---:|---:|---:|---:|---|---|")
for s in scenarios:
    for h in ("octree", "edge_collapse"):
        r = json.load(open(f"{out}/{s}-{h}.json", encoding="utf-8"))
        t = r["timings"]
        levels = sorted(r["levels"], key=lambda level: level["level"])
        print(f"| {s} | {r['mesh']['vertices']} | {h} | {t['hierarchy']:.2f} | {t['precompute']:.2f} "
              f"| {t['constrain']:.2f} | {t['solve']:.2f} | {t['total']:.2f} | {r['energy']:.6g} "
              f"| {', '.join(str(level['vertices']) for level in levels)} "
              f"| {', '.join(str(level['iterations']) for level in levels)} |")
PY
