#!/usr/bin/env bash
# Peer comparison (docs/ceres.md): snl MM, snl mm-accel and Ceres LM (central),
# all three started from the same relaxation output R0.h5 (the pipeline's first
# phase: `snl solve --algorithm relaxation` with the default stopping rule) and
# run until they converge or hit their caps; bench/ceres/table.py then finds the
# lowest final ML cost and each run's iterations and time to common targets.
#   usage: bench/ceres/compare.sh OUT WORK N [N ...]
# OUT: small raw outputs (JSON summaries, histories as CSV, logs with `uptime`),
# e.g. docs/data/ceres; WORK: networks and result files (large). Existing
# networks/starts in WORK are reused; each rerun of the refinements adds a rep.
# Networks: the default generator (`snl generate --sensors N --seed 1`: region
# grown at constant density, sigma 0.14 of the link radius, degree 16, anchors
# auto). Needs a build with -DSNL_BUILD_CERES=ON (BUILD, default ./build).
# Environment (defaults): NP (1) snl ranks, THREADS (1) Ceres threads,
#   SNL_TOL (1e-7, gradient rule), SNL_ITER (20000), MM_ITER (SNL_ITER; MM's cap), CERES_ITER (100),
#   ALGS ("mm mm-accel": the snl refinements to run), EVERY (10: their history interval;
#   a record costs about three iterations, so large networks want more),
#   CERES_TOL (1e-12: function, gradient and parameter tolerance), CRLB (1: `snl eval --crlb`
#   on the network once), LOCK (a lock file, default WORK/bench.lock; every command runs under flock).
set -euo pipefail
{  # the whole script is parsed before it runs: editing it during a run is safe
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=${BUILD:-$ROOT/build}
SNL=$BUILD/bin/snl
CERES=$BUILD/bin/ceres_ml
OUT=$1 WORK=$2
shift 2
NP=${NP:-1} THREADS=${THREADS:-1}
SNL_TOL=${SNL_TOL:-1e-7} SNL_ITER=${SNL_ITER:-20000}
MM_ITER=${MM_ITER:-$SNL_ITER}
ALGS=${ALGS:-mm mm-accel}
CERES_ITER=${CERES_ITER:-100} CERES_TOL=${CERES_TOL:-1e-12}
CRLB=${CRLB:-1}
EVERY=${EVERY:-10}
LOCK=${LOCK:-$WORK/bench.lock}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
for f in "$SNL" "$CERES"; do [ -x "$f" ] || { echo "missing $f (build with -DSNL_BUILD_CERES=ON)" >&2; exit 1; }; done
RUN=()
[ "$NP" -gt 1 ] && RUN=(mpirun -np "$NP" --bind-to core)
# locked command with the load before and after and GNU time's wall/CPU/RSS
timed() {  # LOG CMD...
  local log=$1; shift
  { echo "# $(date -u +%FT%TZ) $*"; echo "# before: $(uptime)"; } >> "$log"
  flock "$LOCK" /usr/bin/time -f "# time: %e s wall, %U s user, %S s sys, %M KB max RSS" "$@" >> "$log" 2>&1
  echo "# after: $(uptime)" >> "$log"
}
history_csv() {  # RESULT.h5 OUT.csv
  /usr/bin/python3 - "$1" "$2" <<'PY'
import sys, h5py, numpy as np
h = h5py.File(sys.argv[1], "r")["history"]
cols = [c for c in ("iteration", "ml_cost", "elapsed", "step_accepted", "rmse") if c in h]
np.savetxt(sys.argv[2], np.column_stack([h[c][:] for c in cols]), delimiter=",", header=",".join(cols),
           comments="", fmt="%.17g")
PY
}

for n in "$@"; do
  o=$OUT/n$n w=$WORK/n$n
  mkdir -p "$o" "$w"
  net=$w/net.h5
  [ -f "$net" ] || timed "$o/generate.log" "$SNL" generate -o "$net" --sensors "$n" --seed 1
  [ -f "$w/R0.h5" ] || timed "$o/R0.log" "${RUN[@]}" "$SNL" solve "$net" -o "$w/R0.h5" --algorithm relaxation \
    --history-every 100 --json "$o/R0.json"
  rep=1
  while [ -f "$o/ceres.$rep.json" ]; do rep=$((rep + 1)); done
  for alg in $ALGS; do
    cap=$SNL_ITER
    [ $alg = mm ] && cap=$MM_ITER
    timed "$o/$alg.$rep.log" "${RUN[@]}" "$SNL" solve "$net" -o "$w/$alg.h5" --algorithm $alg --init "$w/R0.h5" \
      --tol "$SNL_TOL" --max-iter "$cap" --history-every "$EVERY" --json "$o/$alg.$rep.json"
    history_csv "$w/$alg.h5" "$o/$alg.$rep.history.csv"
  done
  timed "$o/ceres.$rep.log" "$CERES" "$net" "$w/R0.h5" -o "$w/ceres.h5" --json "$o/ceres.$rep.json" \
    --max-iter "$CERES_ITER" --tol "$CERES_TOL" --gradient-tol "$CERES_TOL" --parameter-tol "$CERES_TOL" \
    --threads "$THREADS" -q
  history_csv "$w/ceres.h5" "$o/ceres.$rep.history.csv"
  /usr/bin/python3 "$ROOT/bench/ceres/errors.py" "$w" > "$o/errors.$rep.txt"
  if [ "$CRLB" = 1 ] && [ ! -f "$o/crlb.json" ]; then
    # the bound on the anchored rigid part, Fisher information at the truth (a property of the network)
    timed "$o/crlb.log" "$SNL" eval "$net" "$w/mm-accel.h5" --crlb --fim-at truth --no-covariance --json "$o/crlb.json"
  fi
done
# raw files without machine paths
for n in "$@"; do sed -i "s#$BUILD#BUILD#g; s#$WORK#WORK#g" "$OUT/n$n"/*.log "$OUT/n$n"/*.json; done
/usr/bin/python3 "$ROOT/bench/ceres/table.py" "$OUT"
exit
}
