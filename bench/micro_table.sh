#!/usr/bin/env bash
# One relaxation, MM and mm-accel iteration on one core (snl_micro,
# BM_Iteration with the RCM order) on the default network, for each dimension,
# repetition and instruction set, with the load average before each run
# (docs/performance.md, "kernels on one core"). Needs -DSNL_BUILD_BENCH=ON.
#   SNL_MICRO_SENSORS=1000000 bench/micro_table.sh > docs/data/perf/results-DATE-default-micro.txt
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
MICRO=${MICRO:-$ROOT/build/bin/snl_micro}
REPS=${REPS:-3}
DIMS=${DIMS:-"2 3"}
SIMDS=${SIMDS:-"avx512 avx2 0"}
[ -x "$MICRO" ] || { echo "micro_table.sh: $MICRO not found (configure with -DSNL_BUILD_BENCH=ON)" >&2; exit 1; }
flags=avx2
grep -q -m1 -w avx512f /proc/cpuinfo && flags=avx512f
echo "== $(date -u +%Y-%m-%dT%H:%M:%SZ) $(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo '?')" \
  "$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//') | flags: $flags" \
  "| n = ${SNL_MICRO_SENSORS:-1000000}"
for dim in $DIMS; do
  for rep in $(seq 1 "$REPS"); do
    for simd in $SIMDS; do
      load=$(cut -d' ' -f1 /proc/loadavg)
      row=$(SNL_MICRO_DIM=$dim SNL_SIMD=$simd "$MICRO" --benchmark_filter='^BM_Iteration<.*>/1/' 2>/dev/null |
        awk '/^BM_Iteration</ {printf "%s %s %s  ", $1, $2, $3}')
      echo "dim=$dim rep=$rep SNL_SIMD=$simd load=$load: $row"
    done
  done
done
