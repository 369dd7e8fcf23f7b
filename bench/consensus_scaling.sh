#!/usr/bin/env bash
# Consensus Newton (001) on growing random geometric graphs of average degree 6
# (family exp): primal iterations, dual iterations, messages per node and wall
# time, on 1 and 2 ranks, for the three dual solvers of newton-tree (Armijo steps):
#   cg         preconditioned CG, one-hop messages and one allreduce per iteration (the default)
#   splitting  001's matrix-splitting iteration (the paper's method, reconstructed)
#   exact      the exact leaf-to-root / root-to-leaf sweep of the tree system
# and, for the splitting, the dual iterations the first Newton step needs to
# reach the dual tolerance (uncapped probe).
# Splitting runs above SPLIT_FULL_MAX nodes are capped at SPLIT_CAP_ITERS Newton
# steps (each up to --dual-max-iter 10000 dual iterations): a full run would take hours.
# Output: docs/data/consensus/scaling.txt (appended to as runs finish; each
# invocation adds its own header with its settings).
# Usage: bench/consensus_scaling.sh [BUILD_DIR]   (default build)
# Settings (environment): NS, NPS, DUALS ("exact splitting"), SPLIT_FULL_MAX,
# SPLIT_CAP_ITERS, PROBE_NS ("" skips the probe), PROBE_CAP, OUT; RATE_NS ("" skips
# it): the splitting's contraction rate on the same problems, computed with
# tools/plot_consensus.py --splitting-rate, to RATE_OUT
# (docs/data/consensus/splitting_rate.txt).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
SNL=${SNL:-$ROOT/${1:-build}/bin/snl}
NS=${NS-"100 1000 10000 100000 1000000"}
NPS=${NPS:-"1 2"}
DUALS=${DUALS:-"cg exact splitting"}
SPLIT_FULL_MAX=${SPLIT_FULL_MAX:-10000}
SPLIT_CAP_ITERS=${SPLIT_CAP_ITERS:-1}
PROBE_NS=${PROBE_NS-"100 1000 10000"}
PROBE_CAP=${PROBE_CAP:-300000}
OUT=${OUT:-$ROOT/docs/data/consensus/scaling.txt}
RATE_NS=${RATE_NS-"100 1000 10000 100000 1000000"}
RATE_OUT=${RATE_OUT:-$ROOT/docs/data/consensus/splitting_rate.txt}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
W=$(mktemp -d "${TMPDIR:-/tmp}/consensus_scaling.XXXXXX")
trap 'rm -rf "$W"' EXIT
mkdir -p "$(dirname "$OUT")"

# One row from a solve's JSON summary and the command's own wall time.
row() {  # n links np dual cap json cmd_wall
  /usr/bin/python3 - "$@" <<'PY'
import json, sys
n, links, np_, dual, cap, path, wall = sys.argv[1:]
d = json.load(open(path))
print(f"{int(n):>8} {int(links):>8} {d.get('tree_depth', -1):>5} {np_:>2} {dual:>9} {cap:>6} {d['iterations']:>6} "
      f"{d['dual_iterations']:>9} {d['termination']:>14} {d['max_abs_error']:>10.3e} {d['messages_per_node']:>12.1f} "
      f"{d['wall_seconds']:>9.3f} {float(wall):>9.2f}")
PY
}
solve() {  # np json args...
  local np=$1 json=$2; shift 2
  local t0 t1
  t0=$(date +%s.%N)
  mpirun -np "$np" "$SNL" consensus solve "$@" -q --json "$json" < /dev/null > /dev/null
  t1=$(date +%s.%N)
  echo "$t1 - $t0" | bc
}

if [ -n "$NS" ]; then
{
  echo "# bench/consensus_scaling.sh, $(date -u +%Y-%m-%dT%H:%MZ), $(nproc) cores, $(uname -n); NS=\"$NS\" NPS=\"$NPS\" DUALS=\"$DUALS\" SPLIT_FULL_MAX=$SPLIT_FULL_MAX SPLIT_CAP_ITERS=$SPLIT_CAP_ITERS"
  echo "# snl consensus generate -o P.h5 --nodes N --avg-degree 6 --seed 1  (family exp)"
  echo "# mpirun -np NP snl consensus solve P.h5 -o R.h5 --method newton-tree --dual DUAL [--max-iter CAP] -q --json J"
  echo "# defaults: --max-iter 100 --dual-max-iter 10000 --tol 1e-10 --dual-tol 1e-12 --step armijo; depth = spanning-tree depth (BFS)"
  echo "# cap: Newton steps allowed ('-' = default 100); wall_solve from the JSON, wall_cmd includes start-up and I/O"
  echo "#        n    links depth np      dual    cap primal      dual    termination    max_err    msgs/node wall_solve  wall_cmd"
} >> "$OUT"
for n in $NS; do
  "$SNL" consensus generate -o "$W/p$n.h5" --nodes "$n" --avg-degree 6 --seed 1 -q
  links=$(/usr/bin/python3 -c "import h5py,sys; print(h5py.File(sys.argv[1])['edges'].shape[0])" "$W/p$n.h5")
  for np in $NPS; do
    if [[ " $DUALS " == *" cg "* ]]; then
      wall=$(solve "$np" "$W/j.json" "$W/p$n.h5" -o "$W/r.h5" --method newton-tree --dual cg)
      row "$n" "$links" "$np" cg - "$W/j.json" "$wall" >> "$OUT"
    fi
    if [[ " $DUALS " == *" exact "* ]]; then
      wall=$(solve "$np" "$W/j.json" "$W/p$n.h5" -o "$W/r.h5" --method newton-tree --dual exact)
      row "$n" "$links" "$np" exact - "$W/j.json" "$wall" >> "$OUT"
    fi
    if [[ " $DUALS " != *" splitting "* ]]; then
      :
    elif [ "$n" -le "$SPLIT_FULL_MAX" ]; then
      wall=$(solve "$np" "$W/j.json" "$W/p$n.h5" -o "$W/r.h5" --method newton-tree --dual splitting)
      row "$n" "$links" "$np" splitting - "$W/j.json" "$wall" >> "$OUT"
    else
      wall=$(solve "$np" "$W/j.json" "$W/p$n.h5" -o "$W/r.h5" --method newton-tree --dual splitting \
        --max-iter "$SPLIT_CAP_ITERS")
      row "$n" "$links" "$np" splitting "$SPLIT_CAP_ITERS" "$W/j.json" "$wall" >> "$OUT"
    fi
  done
  rm -f "$W/p$n.h5"
done
fi
[ -z "$PROBE_NS" ] || {
  echo "# probe: dual iterations of the FIRST Newton step until the splitting meets --dual-tol 1e-12"
  echo "# mpirun -np 1 snl consensus solve P.h5 -o R.h5 --method newton-tree --dual splitting --max-iter 1 --dual-max-iter $PROBE_CAP"
  echo "#        n    links depth np      dual    cap primal      dual    termination    max_err    msgs/node wall_solve  wall_cmd"
} >> "$OUT"
for n in $PROBE_NS; do
  "$SNL" consensus generate -o "$W/p$n.h5" --nodes "$n" --avg-degree 6 --seed 1 -q
  links=$(/usr/bin/python3 -c "import h5py,sys; print(h5py.File(sys.argv[1])['edges'].shape[0])" "$W/p$n.h5")
  wall=$(solve 1 "$W/j.json" "$W/p$n.h5" -o "$W/r.h5" --method newton-tree --dual splitting --max-iter 1 \
    --dual-max-iter "$PROBE_CAP")
  row "$n" "$links" 1 splitting 1 "$W/j.json" "$wall" >> "$OUT"
done
if [ -n "$RATE_NS" ]; then
  {
    echo "# bench/consensus_scaling.sh, $(date -u +%Y-%m-%dT%H:%MZ): the dual splitting's contraction at the first"
    echo "# Newton step (x = 0) on newton-tree's BFS tree; problems as in scaling.txt (--avg-degree 6 --seed 1, family exp)."
    echo "# /usr/bin/python3 tools/plot_consensus.py --splitting-rate P.h5: lambda_min of (D + Bbar)^-1 M,"
    echo "# rate = 1 - lambda_min per dual iteration, iters_1e-12 = ln(1e12) / lambda_min"
    echo "#        n  depth  lambda_min         rate  iters_1e-12"
  } >> "$RATE_OUT"
  for n in $RATE_NS; do
    "$SNL" consensus generate -o "$W/q$n.h5" --nodes "$n" --avg-degree 6 --seed 1 -q
    /usr/bin/python3 "$ROOT/tools/plot_consensus.py" --splitting-rate "$W/q$n.h5" | grep -v '^#' >> "$RATE_OUT"
    rm -f "$W/q$n.h5"
  done
fi
echo "wrote $OUT"
