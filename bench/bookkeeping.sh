#!/usr/bin/env bash
# Share of `snl solve` (default options but --max-iter) spent outside the
# iteration kernels: history records, stopping sums and tests, exact sums.
#   NET=net.h5 NP=2 ITERS=300 BINS="/path/old/snl build/bin/snl" bench/bookkeeping.sh
#   NET=net.h5 EXTRAS="--test-every 10|" bench/bookkeeping.sh   # option sets, '|'-separated
# One solve per binary and option set (EXTRAS, default: none), in the order
# given, each under the shared bench lock;
# prints the load average before and after each, and per run: iterations,
# solve_seconds, iterate_seconds, the fraction outside 1 - iterate / solve,
# stop_test_seconds, record_seconds and gradient_tests (where the binary
# reports them), RMSE,
# and whether the positions equal the first binary's, byte for byte.
set -euo pipefail
NET=${NET:?NET=network.h5}
NP=${NP:-2}
ITERS=${ITERS:-300}
BINS=${BINS:-build/bin/snl}
WORK=${WORK:-/tmp/snl-bookkeeping}
# Runs that time themselves wait for each other on a shared machine: LOCK names the lock file.
LOCK=${LOCK:-$WORK/bench.lock}
mkdir -p "$WORK"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
i=0
first=""
IFS='|' read -r -a extras <<<"${EXTRAS:-}"
[ ${#extras[@]} -gt 0 ] || extras=("")
for b in $BINS; do
for e in "${extras[@]}"; do
  i=$((i + 1))
  rm -f "$WORK/r$i.h5"
  echo "# run $i: $(date -u +%FT%TZ) load $(cut -d' ' -f1-3 /proc/loadavg): mpirun -np $NP $b solve $NET -o $WORK/r$i.h5 --max-iter $ITERS $e --json $WORK/r$i.json -q"
  # shellcheck disable=SC2086  # e: words on purpose
  flock "$LOCK" mpirun -np "$NP" "$b" solve "$NET" -o "$WORK/r$i.h5" --max-iter "$ITERS" $e --json "$WORK/r$i.json" -q
  echo "# run $i ended: $(date -u +%FT%TZ) load $(cut -d' ' -f1-3 /proc/loadavg)"
  [ -n "$first" ] || first="$WORK/r$i.h5"
  /usr/bin/python3 - "$WORK/r$i.json" "$WORK/r$i.h5" "$first" <<'PY'
import json, sys, h5py
d = json.load(open(sys.argv[1]))
same = h5py.File(sys.argv[2], "r")["positions"][()].tobytes() == h5py.File(sys.argv[3], "r")["positions"][()].tobytes()
s, it = d["solve_seconds"], d["iterate_seconds"]
print(f"iterations {d['iterations']} solve_s {s:.2f} iterate_s {it:.2f} outside {1 - it / s:.3f} "
      f"stop_test_s {d.get('stop_test_seconds', 'n/a')} record_s {d.get('record_seconds', 'n/a')} "
      f"gradient_tests {d.get('gradient_tests', 'n/a')} "
      f"rmse {d.get('rmse')} ml_cost {d['ml_cost']!r} positions_equal_first {same}")
PY
done
done
