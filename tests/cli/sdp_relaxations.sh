#!/usr/bin/env bash
# The centralized relaxations from the command line: the result file and JSON
# carry the relaxation's objective, DSDP's status and time; options they cannot
# honour are usage errors (status 2); a solver failure (injected on rank 0) is
# one error, status 4, on 1 and 2 ranks, and leaves an existing output untouched.
source "$(dirname "$0")/common.bash"
NET="$SNL_SOURCE_DIR/inputs/net10_s0.01.h5"
for alg in sdp esdp edm; do
  mpi 2 "$SNL" solve "$NET" -o "$T/$alg.h5" --algorithm $alg --json "$T/$alg.json" -q
  "$PY" - "$T/$alg.h5" "$T/$alg.json" $alg <<'PYEOF' || fail "$alg: result or JSON"
import sys, json, h5py, math
f, j = h5py.File(sys.argv[1], "r"), json.load(open(sys.argv[2]))
for src in (dict(f.attrs), j):
    assert src["sdp_status"] in ("converged", b"converged"), src["sdp_status"]
    assert 0 <= float(src["relaxation_objective"]) <= float(src["ml_cost"]) + 1e-9
    assert float(src["sdp_seconds"]) > 0
assert j["algorithm"] == sys.argv[3] and j["iterations"] == 1 and j["converged"]
assert f["positions"].shape == (10, 2) and j["rmse"] < 0.05, j["rmse"]
PYEOF
done
for opt in "--tol 1e-3" "--max-iter 5" "--init $T/sdp.h5"; do
  set +e; "$SNL" solve "$NET" -o "$T/x.h5" --algorithm sdp $opt -q 2> "$T/err"; rc=$?; set -e
  [ $rc -eq 2 ] || fail "sdp $opt: status $rc, expected 2"
  grep -q "not honoured by --algorithm sdp" "$T/err" || fail "sdp $opt: $(cat "$T/err")"
done
cp "$T/sdp.h5" "$T/keep.h5"
sum0=$(md5sum < "$T/keep.h5")
for np in 1 2; do
  set +e
  SNL_TEST_FAIL=sdp:0 mpi $np "$SNL" solve "$NET" -o "$T/keep.h5" --algorithm esdp --json "$T/f.json" -q 2> "$T/err"
  rc=$?
  set -e
  [ $rc -eq 4 ] || fail "injected solver failure np=$np: status $rc, expected 4"
  [ "$(grep -c '^snl: error: ' "$T/err")" -eq 1 ] || fail "np=$np: expected one error: $(cat "$T/err")"
  grep -q "found no solution" "$T/err" || fail "np=$np: unclear message: $(cat "$T/err")"
  [ "$(md5sum < "$T/keep.h5")" = "$sum0" ] || fail "np=$np: existing output was modified"
  [ ! -e "$T/f.json" ] || fail "np=$np: JSON written after a failure"
done
echo "sdp_relaxations: ok"
