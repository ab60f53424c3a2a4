#!/usr/bin/env bash
# Runs every libFuzzer harness of a HARAP_FUZZ build for a bounded time each.
#   tests/fuzz/run_fuzzers.sh BUILD_DIR [SECONDS_PER_TARGET] [TARGET...]
# Each harness starts from its seed corpus (tests/fuzz/corpus/<target>/) and saved regressions;
# new inputs go to a scratch folder, not into the repository. On a failure the input is kept in
# BUILD_DIR/fuzz-artifacts/ and the script exits non-zero: copy that file into
# tests/fuzz/regressions/<target>/ once the bug is fixed. Prints one summary line per target.
set -euo pipefail
build=${1:?usage: run_fuzzers.sh BUILD_DIR [SECONDS_PER_TARGET] [TARGET...]}
seconds=${2:-25}
shift $(( $# >= 2 ? 2 : 1 ))
source_dir="$(cd "$(dirname "$0")" && pwd)"
artifacts="$build/fuzz-artifacts"
mkdir -p "$artifacts"
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT

targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  for binary in "$build"/fuzz/harap_fuzz_*; do targets+=("${binary##*/harap_fuzz_}"); done
fi
status=0
for target in "${targets[@]}"; do
  binary="$build/fuzz/harap_fuzz_$target"
  inputs=("$source_dir/corpus/$target")
  [ -d "$source_dir/regressions/$target" ] && inputs+=("$source_dir/regressions/$target")
  mkdir -p "$scratch/$target"
  log="$artifacts/$target.log"
  # -timeout: one input taking 10 s is a hang; -rss_limit_mb/-malloc_limit_mb: the readers bound
  # their allocations by the input size, so a 1 GB request is a bug.
  if "$binary" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=1024 \
      -print_final_stats=1 -artifact_prefix="$artifacts/$target-" \
      "$scratch/$target" "${inputs[@]}" >"$log" 2>&1; then
    runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
    echo "fuzz $target: ok, $runs executions in ${seconds} s"
  else
    echo "fuzz $target: FAILED (log $log); crashing inputs:" >&2
    ls "$artifacts/$target-"* >&2 || true
    grep -m1 -A12 "ERROR\|==ERROR\|runtime error\|uncaught\|deadly" "$log" >&2 || tail -20 "$log" >&2
    status=1
  fi
done
exit $status
