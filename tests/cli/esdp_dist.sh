#!/usr/bin/env bash
# The distributed ESDP from the command line: the same positions, objective and
# history bits on 1, 2 and 3 ranks (the JSON's timings aside); a run stopped
# by a signal resumes from its checkpoint to the same bits; bad options are usage errors
# (status 2 for an option it cannot honour, 1 for a bad value; one error line,
# an existing output untouched, no JSON).
source "$(dirname "$0")/common.bash"
NET="$SNL_SOURCE_DIR/inputs/net10_s0.05.h5"
args=(--algorithm esdp-dist --stop papers --tol 0 --max-iter 300 -q)
for np in 1 2 3; do
  mpi $np "$SNL" solve "$NET" -o "$T/r$np.h5" --json "$T/r$np.json" "${args[@]}"
done
for np in 2 3; do
  h5diff -q "$T/r1.h5" "$T/r$np.h5" /positions || fail "positions differ between 1 and $np ranks"
  h5diff -q "$T/r1.h5" "$T/r$np.h5" /history/cost || fail "history differs between 1 and $np ranks"
done
"$PY" - "$T/r1.json" "$T/r3.json" <<'PYEOF' || fail "JSON"
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:])
assert a["algorithm"] == "esdp-dist" and a["iterations"] == 300, a
assert a["relaxation_objective"] == b["relaxation_objective"] and a["consensus_residual"] == b["consensus_residual"]
assert a["communications_per_sensor"] == 300, a["communications_per_sensor"]
PYEOF
# Stopped by SIGUSR1 after some checkpoints (slow writes keep it alive), resumed on
# 2 ranks: the same bits as the straight run (S_b, U_b and own entries restored).
ck=(--algorithm esdp-dist --stop papers --tol 0 --max-iter 2000 -q)
"$SNL" solve "$NET" -o "$T/full.h5" "${ck[@]}"
set +e
SNL_TEST_CHECKPOINT_DELAY=0.1 "$SNL" solve "$NET" -o "$T/stopped.h5" "${ck[@]}" --checkpoint "$T/ck.h5" \
  --checkpoint-every 50 &
pid=$!
for _ in $(seq 400); do [ -f "$T/ck.h5" ] && break; sleep 0.05; done
sleep 0.2
kill -USR1 $pid
wait_watched $pid "the signalled run"
rc=$?
set -e
[ $rc -eq 3 ] || fail "expected exit status 3 after SIGUSR1, got $rc"
mpi 2 "$SNL" solve "$NET" -o "$T/resumed.h5" "${ck[@]}" --restart "$T/ck.h5"
h5diff -q "$T/full.h5" "$T/resumed.h5" /positions || fail "the resumed run's positions differ"
cp "$T/r1.h5" "$T/keep.h5"
sum0=$(md5sum < "$T/keep.h5")
refuse() {  # refuse STATUS MESSAGE ARGS...: 2 for an option the method cannot honour, 1 for a bad value
  local want=$1 msg=$2; shift 2
  for np in 2; do  # 2 ranks: they must agree on the refusal
    rm -f "$T/x.json"
    set +e; mpi $np "$SNL" solve "$NET" -o "$T/keep.h5" --json "$T/x.json" -q "$@" 2> "$T/err"; rc=$?; set -e
    [ $rc -eq "$want" ] || fail "$*: status $rc, expected $want"
    [ "$(grep -c '^snl: error: ' "$T/err")" -eq 1 ] || fail "$*: expected one error: $(cat "$T/err")"
    grep -q -- "$msg" "$T/err" || fail "$*: unclear message: $(cat "$T/err")"
    [ "$(md5sum < "$T/keep.h5")" = "$sum0" ] || fail "$*: existing output was modified"
    [ ! -e "$T/x.json" ] || fail "$*: JSON written"
  done
}
refuse 2 "give --stop papers" --algorithm esdp-dist --stop gradient
# Without --stop it takes the papers' rule: the bits of --stop papers.
mpi 2 "$SNL" solve "$NET" -o "$T/default.h5" --algorithm esdp-dist --max-iter 300 -q
mpi 2 "$SNL" solve "$NET" -o "$T/papers.h5" --algorithm esdp-dist --max-iter 300 --stop papers -q
h5diff -q "$T/default.h5" "$T/papers.h5" /positions || fail "esdp-dist without --stop is not --stop papers"
refuse 1 "--esdp-rho must be a finite number > 0" --algorithm esdp-dist --stop papers --esdp-rho 0
refuse 1 "--esdp-rho must be a finite number > 0" --algorithm esdp-dist --stop papers --esdp-rho nan
refuse 2 "--esdp-rho is not honoured by --algorithm relaxation" --algorithm relaxation --esdp-rho 2
echo "esdp_dist: ok"
