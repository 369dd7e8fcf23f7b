#!/usr/bin/env bash
# Peer comparison (docs/ceres.md): snl MM on 2 ranks vs Ceres LM (central), both
# started from the same relaxation output R0.h5.
#   usage: bench/ceres/compare.sh [WORKDIR] [N ...]     (default N: 10000 100000 1000000)
# Needs a build with -DSNL_BUILD_CERES=ON (BUILD, default ./build). Recorded
# runs: docs/data/perf/results-*-ceres.txt.
# Stopping rules (override through the environment):
#   relaxation: --tol 1e-6 --max-iter $RELAX_ITER (300)
#   MM:         --tol 1e-6 --max-iter $MM_ITER (300)
#   Ceres LM:   function_tolerance 1e-6, --max-iter $CERES_ITER (50, Ceres' default)
# TABLE_ONLY=1 prints the table of the runs already in WORKDIR.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=${BUILD:-$ROOT/build}
SNL=$BUILD/bin/snl
CERES=$BUILD/bin/ceres_ml
WORK=${1:-/tmp/snl-ceres}
shift || true
SIZES=("$@")
[ ${#SIZES[@]} -gt 0 ] || SIZES=(10000 100000 1000000)
RELAX_ITER=${RELAX_ITER:-300}
MM_ITER=${MM_ITER:-300}
CERES_ITER=${CERES_ITER:-50}
NP=${NP:-2}
SEED=${SEED:-1}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
MPIRUN=(mpirun -np "$NP" --bind-to core)
mkdir -p "$WORK"
for f in "$SNL" "$CERES"; do [ -x "$f" ] || { echo "missing $f (build with -DSNL_BUILD_CERES=ON)" >&2; exit 1; }; done

# peak RSS (MiB) of a command through GNU time, when available
TIME=()
[ -x /usr/bin/time ] && TIME=(/usr/bin/time -f "%M")

for n in "${SIZES[@]}"; do
  [ -z "${TABLE_ONLY:-}" ] || break  # TABLE_ONLY=1: only print the table of existing runs
  d=$WORK/n$n
  mkdir -p "$d"
  net=$d/net.h5
  # 1% random anchors: with the 4 corner anchors alone almost nothing is anchored at degree 6.
  [ -f "$net" ] || "$SNL" generate -o "$net" --sensors "$n" --avg-degree 6 --sigma 0.01 --seed "$SEED" \
    --anchors $((n / 100)) --localizable no -q
  if [ ! -f "$d/R0.h5" ]; then
    "${MPIRUN[@]}" "$SNL" solve "$net" -o "$d/R0.h5" --algorithm relaxation --tol 1e-6 --max-iter "$RELAX_ITER" --history-every 50 \
      --json "$d/R0.json" -q
  fi
  "${MPIRUN[@]}" "$SNL" solve "$net" -o "$d/mm.h5" --algorithm mm --init "$d/R0.h5" --tol 1e-6 \
    --max-iter "$MM_ITER" --history-every 50 --json "$d/mm.json" -q
  "${TIME[@]}" "$CERES" "$net" "$d/R0.h5" -o "$d/ceres.h5" --json "$d/ceres.json" --max-iter "$CERES_ITER" \
    --tol 1e-6 --threads "$NP" -q > "$d/ceres.log" 2> "$d/ceres.err" || { cat "$d/ceres.err" >&2; exit 1; }
  tail -n 1 "$d/ceres.err" > "$d/ceres.rss_kb" || true
done

# One table. Wall = whole command (read + setup + solve + write); solve = the iterations only.
python3 - "$WORK" "${SIZES[@]}" <<'PY'
import json, sys, os
work, sizes = sys.argv[1], sys.argv[2:]
hdr = ("n", "method", "wall_s", "solve_s", "iters", "term", "ml_cost", "rmse", "rmse_loc")
print("| " + " | ".join(hdr) + " |")
print("|" + "---|" * len(hdr))
def fmt(x, f):
    return "-" if x is None else format(x, f)
for n in sizes:
    d = os.path.join(work, "n" + n)
    for name, label in (("R0", "relaxation (start), 2 ranks"), ("mm", "snl MM, 2 ranks"), ("ceres", "Ceres LM, 1 proc")):
        j = json.load(open(os.path.join(d, name + ".json")))
        print("| %s | %s | %s | %s | %d | %s | %s | %s | %s |" % (
            n, label, fmt(j["wall_seconds"], ".2f"), fmt(j["solve_seconds"], ".2f"), j["iterations"],
            j["termination"], fmt(j["ml_cost"], ".6g"), fmt(j.get("rmse"), ".6g"), fmt(j.get("rmse_localizable"), ".6g")))
PY
