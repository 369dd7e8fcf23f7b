#!/usr/bin/env bash
# MM against mm-accel from the same relaxation output: communications per
# sensor to come within 1e-6 (relative) of the final ML cost, and time per
# iteration. Writes, per network, the JSON summaries, the refinements'
# histories (CSV) and the load average before each refinement (uptime) to
# OUT, then OUT/summary.csv and OUT/summary.md (bench/accel_refine.py).
#   [RELAX_MAX=N] [SOLVE_ARGS="..."] bench/accel_refine.sh OUT MAX_ITER HISTORY_EVERY RANKS NET.h5...
# SOLVE_ARGS (split on spaces) go to all three solves: the measurement model,
# e.g. "--weights file --loss huber:0.02".
# The relaxation is the papers' pipeline's (--stop papers --tol 1e-6, at most
# RELAX_MAX iterations, default 10000); both refinements then run MAX_ITER
# iterations (--tol 0) from its output, one after the other in the same run
# (their ms/iteration ratio is the comparable timing).
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=$1 MAXIT=$2 EVERY=$3 NP=$4; shift 4
SNL=${SNL:-build/bin/snl}
RELAX_MAX=${RELAX_MAX:-10000}
read -r -a EXTRA <<< "${SOLVE_ARGS:-}"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
mkdir -p "$OUT"
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
for net in "$@"; do
  name=$(basename "$net" .h5)
  s() { mpirun -np "$NP" "$SNL" solve "$net" -q ${EXTRA[@]+"${EXTRA[@]}"} "$@"; }
  s -o "$T/relax.h5" --algorithm relaxation --stop papers --tol 1e-6 --max-iter "$RELAX_MAX" --json "$OUT/$name.relax.json"
  for alg in mm mm-accel; do
    uptime > "$OUT/$name.$alg.uptime.txt"
    s -o "$T/$alg.h5" --algorithm $alg --init "$T/relax.h5" --tol 0 --max-iter "$MAXIT" --history-every "$EVERY" \
      --json "$OUT/$name.$alg.json"
    /usr/bin/python3 - "$T/$alg.h5" "$OUT/$name.$alg.history.csv" <<'PY'
import sys, h5py, numpy as np
h = h5py.File(sys.argv[1], "r")["history"]
cols = ["phase_iteration", "communications", "ml_cost", "cost", "rel_change", "rmse", "elapsed"]
np.savetxt(sys.argv[2], np.column_stack([h[c][:] for c in cols]), delimiter=",", header=",".join(cols),
           comments="", fmt="%.17g")
PY
  done
done
/usr/bin/python3 bench/accel_refine.py "$OUT" > "$OUT/summary.md"
cat "$OUT/summary.md"
