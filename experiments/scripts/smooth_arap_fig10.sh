#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The smooth ARAP measurement of docs/results.md ("Fig. 10: smooth ARAP"): classic vs
# hierarchical with smooth_arap next to spokes_and_rims, on the shared armadillo-bend (173K
# vertices) and cylinder-bend (built-in cylinder, 480K vertices) scenarios and the repository's
# 20K cylinder-bend, plus pictures.
#
#   experiments/scripts/smooth_arap_fig10.sh [OUT_DIR [REPEATS]]
#   experiments/scripts/smooth_arap_fig10.sh --table OUT_DIR...   # the table over several runs
#
# Writes OUT_DIR/<scenario>.<energy>.<run>.<repeat>.json (harap reports) and .ply (last repeat),
# prints a markdown table (total time: the minimum over the repeats) and renders
# OUT_DIR/<scenario>.png with experiments/scripts/render_ply.py if Debian's python3-matplotlib is
# installed. Needs a Release build in build/ and the shared data beside the repository.
set -euo pipefail
repo=$(cd "$(dirname "$0")/../.." && pwd)

# table DIR...: one row per run name, total time the minimum over every report of that name.
table() {
  python3 - "$@" <<'EOF'
import glob, json, os, sys
runs = {}
for folder in sys.argv[1:]:
    for path in sorted(glob.glob(os.path.join(folder, "*.json"))):
        name = os.path.basename(path).rsplit(".", 2)[0]
        runs.setdefault(name, []).append(json.load(open(path)))
print("| scenario | V | energy | method | P | C | S | T (min) | T (all runs) | E | iterations per level (finest first) |")
print("|---|---:|---|---|---:|---:|---:|---:|---|---:|---|")
for name in sorted(runs):
    reports = runs[name]
    scenario, energy, method = name.split(".")
    best = min(reports, key=lambda r: r["timings"]["total"])
    t = best["timings"]
    levels = ", ".join(str(l["iterations"]) for l in best["levels"])
    totals = " / ".join(f'{r["timings"]["total"]:.1f}' for r in reports)
    print(f'| {scenario} | {best["levels"][0]["vertices"]} | {energy} | {method} | '
          f'{t["precompute"]:.2f} | {t["constrain"]:.2f} | {t["solve"]:.2f} | {t["total"]:.2f} | '
          f'{totals} | {best["energy"]:.5g} | {levels} |')
EOF
}
if [ "${1:-}" = "--table" ]; then
  shift
  table "$@"
  exit 0
fi

harap=$repo/build/harap
shared=${HARAP_SHARED_DIR:-$repo/../shared}
out=${1:-smooth-arap-fig10}
repeats=${2:-1}
mkdir -p "$out"

# run NAME SCENARIO ARGS...: REPEATS runs of `harap deform`.
run() {
  local name=$1 scenario=$2
  shift 2
  for repeat in $(seq 1 "$repeats"); do
    echo "== $name ($repeat/$repeats)" >&2
    "$harap" deform "$scenario" "$@" --report "$out/$name.$repeat.json" --out "$out/$name.ply" -q
  done
}

scenarios=(
  "armadillo-bend=$shared/scenarios/armadillo-bend.toml"
  "cylinder-bend=$shared/scenarios/cylinder-bend.toml"
  "cylinder-bend-20k=$repo/experiments/scenarios/cylinder-bend.toml"
)
for entry in "${scenarios[@]}"; do
  s=${entry%%=*}
  scenario=${entry#*=}
  for energy in spokes_and_rims smooth_arap; do
    for optimizer in classic hierarchical; do
      run "$s.$energy.$optimizer" "$scenario" --optimizer "$optimizer" --energy "$energy"
    done
  done
  # The published code's local step: rotations fitted to the spokes-and-rims part only.
  run "$s.smooth_arap.classic-published-fit" "$scenario" --optimizer classic \
    --energy smooth_arap --set energy.rotation_fit=spokes_and_rims
  # Each level's mass matrix rescaled to mean 1 on its own mesh instead of the input mesh's scale.
  run "$s.smooth_arap.hierarchical-level-mass" "$scenario" --optimizer hierarchical \
    --energy smooth_arap --set energy.mass_normalization=level
done

table "$out"

if /usr/bin/python3 -c "import matplotlib" 2>/dev/null; then
  render=$repo/experiments/scripts/render_ply.py
  titles=("ARAP, classic" "ARAP, hierarchical" "smooth ARAP, classic" "smooth ARAP, hierarchical")
  /usr/bin/python3 "$render" "$out"/armadillo-bend.{spokes_and_rims,smooth_arap}.{classic,hierarchical}.ply \
    --titles "${titles[@]}" --up y --view 10 -75 --out "$out/armadillo-bend.png"
  for s in cylinder-bend cylinder-bend-20k; do
    /usr/bin/python3 "$render" "$out"/$s.{spokes_and_rims,smooth_arap}.{classic,hierarchical}.ply \
      --titles "${titles[@]}" --view 5 0 --panel 2.6 --out "$out/$s.png"
  done
else
  echo "python3-matplotlib not installed: no pictures" >&2
fi
