#!/usr/bin/env bash
# 003's asynchronous method run for real (--algorithm async|async-exact --mode
# free, docs/async.md) through the command line, on generated 2D and 3D
# networks: it reaches the relaxation's optimum on 1, 2 and 3 ranks; --mode free is
# refused where it cannot be honoured; a rank that fails inside the free loop
# ends the run with one error and status 1, never a hang; a replay that loses
# a row ends with an error (status 70), never a hang; SIGTERM stops a free run
# with a checkpoint (every rank stopped by agreement, messages drained) and a
# restart from it reaches the same optimum.
source "$(dirname "$0")/common.bash"
cost() { $PY -c "import json,sys; print(json.load(open(sys.argv[1]))['relaxed_cost'])" "$1"; }
near() {  # near A B RTOL WHAT
  $PY -c "import sys; a, b, t = map(float, sys.argv[1:4]); sys.exit(0 if abs(a - b) <= t * abs(b) else 1)" "$1" "$2" "$3" ||
    fail "$4: $1 not within $3 of $2"
}
"$SNL" generate -o "$T/net2.h5" --sensors 300 --avg-degree 30 --anchors 20 --sigma 0.05 --seed 5 -q
"$SNL" generate -o "$T/net3.h5" --sensors 120 --dim 3 --avg-degree 40 --anchors 20 --sigma 0.05 --seed 6 -q

# The optimum, then free mode on 1, 2 and 3 ranks (async in 2D, async-exact in 3D: the inexact step is slow there).
for d in 2 3; do
  alg=async
  [ $d = 3 ] && alg=async-exact
  mpi 2 "$SNL" solve "$T/net$d.h5" -o "$T/rel$d.h5" --algorithm relaxation --init random --tol 1e-9 --max-iter 400000 \
    --history-every 500 --json "$T/rel$d.json" -q
  for np in 1 2 3; do
    mpi $np "$SNL" solve "$T/net$d.h5" -o "$T/free$d.h5" --algorithm $alg --mode free --init random --tol 1e-6 \
      --max-iter 100000 --json "$T/free$d.json" -q
    grep -q '"termination": "CONVERGENCE"' "$T/free$d.json" ||
      { cat "$T/free$d.json"; fail "$alg --mode free ${d}D on $np ranks: not converged"; }
    near "$(cost "$T/free$d.json")" "$(cost "$T/rel$d.json")" 1e-6 "$alg --mode free ${d}D on $np ranks"
    echo "ok: $alg --mode free ${d}D on $np ranks: f_hat $(cost "$T/free$d.json"), relaxation $(cost "$T/rel$d.json")"
    rm -f "$T/free$d.h5"
  done
done

# Refusals (before anything is read): status 2 for an option the method cannot honour.
set +e
"$SNL" solve "$T/net2.h5" -o "$T/x.h5" --algorithm relaxation --mode free -q 2> "$T/err"; rc=$?
set -e
[ $rc -eq 2 ] && grep -q -- "--mode is not honoured by --algorithm relaxation (only by async, async-exact)" "$T/err" ||
  { cat "$T/err"; fail "--mode free with relaxation: status $rc"; }
set +e
"$SNL" solve "$T/net2.h5" -o "$T/x.h5" --algorithm async --mode fast -q 2> "$T/err"; rc=$?
set -e
[ $rc -ne 0 ] && grep -q "unknown --mode 'fast'" "$T/err" || { cat "$T/err"; fail "--mode fast: status $rc"; }
echo "ok: refusals"

# failing NP SPEC_ENV EXPECTED_STATUS REGEX ARGS...: the run ends (timeout 60: no hang) with the status and message.
failing() {
  local np=$1 envspec=$2 want=$3 msg=$4
  shift 4
  run_failing "$np" "$envspec" "$envspec" "$want" "$msg" solve "$T/net2.h5" -o "$T/x.h5" "$@" -q
  # One message (the free loop agrees on it); the replay's guard fires on every rank stuck, the same words.
  [ "$want" -ne 1 ] || [ "$NERR" -eq 1 ] || { cat "$T/err"; fail "$envspec np=$np: $NERR error messages, expected 1"; }
  [ -f "$T/x.h5" ] && fail "$envspec np=$np: a failed run wrote its result"
  echo "ok: $envspec np=$np status $want: $(grep -m1 '^snl: error: ' "$T/err")"
}
for np in 2 3; do
  last=$((np - 1))
  failing $np SNL_TEST_FAIL=async-free:$last:3 1 \
    "rank $last: injected failure at 'async-free' on rank $last iteration 3 .*in the free asynchronous loop" \
    --algorithm async --mode free --max-iter 100000 --tol 0
  failing $np SNL_TEST_FAIL=async-free:0:5 1 "rank 0: injected failure at 'async-free'" \
    --algorithm async-exact --mode free --max-iter 100000 --tol 0
done
# The replay with a lost row (SNL_TEST_ASYNC_DROP_ROW=R: rank R never sends
# one row in the second iteration): a bounded wait, then an error.
failing 2 SNL_TEST_ASYNC_DROP_ROW=1 70 "the replay waited [0-9]+ rounds for rows that never came \(a row was lost\)" \
  --algorithm async --max-iter 5 --tol 0

# SIGTERM during a free run (slowed: rank 1 sleeps 5 ms per epoch): checkpoint, status 3; the restart converges.
ARGS=(--algorithm async --mode free --init random --tol 1e-6 --max-iter 100000 --history-every 50)
"$MPIEXEC" "$MPIEXEC_NUMPROC_FLAG" 2 --oversubscribe "$SNL" solve "$T/net2.h5" -o "$T/stopped.h5" "${ARGS[@]}" \
  --straggler-delay 0.005 --progress-seconds 0.1 --checkpoint "$T/ck.h5" 2> "$T/log.term" &
pid=$!
for _ in $(seq 600); do grep -q '^async ' "$T/log.term" && break; sleep 0.05; done
grep -q '^async ' "$T/log.term" || { cat "$T/log.term"; fail "the free run did not start iterating"; }
ranks=$(pgrep -P $pid) || fail "no rank processes under mpirun"
wait_caught TERM $ranks || fail "the ranks do not catch SIGTERM"
for r in $ranks; do kill -TERM "$r"; done
set +e; wait_watched $pid "the free run stopped by SIGTERM"; rc=$?; set -e
[ $rc -eq 3 ] || { cat "$T/log.term"; fail "SIGTERM: exit status $rc, expected 3"; }
[ -f "$T/ck.h5" ] || fail "SIGTERM: no checkpoint written"
mpi 2 "$SNL" solve "$T/net2.h5" -o "$T/resumed.h5" "${ARGS[@]}" --restart "$T/ck.h5" --json "$T/res.json" \
  2> "$T/log.resume" || { cat "$T/log.resume"; fail "the restart failed"; }
from=$(sed -n 's/^snl solve: resuming from .* (total iteration \([0-9]*\))$/\1/p' "$T/log.resume")
[ -n "$from" ] && [ "$from" -gt 0 ] || { cat "$T/log.resume"; fail "did not resume from an iteration > 0"; }
grep -q '"termination": "CONVERGENCE"' "$T/res.json" || { cat "$T/res.json"; fail "the restarted run did not converge"; }
near "$(cost "$T/res.json")" "$(cost "$T/rel2.json")" 1e-6 "restart"
echo "ok: SIGTERM at total iteration $from, restart converged to f_hat $(cost "$T/res.json")"
# The same checkpoint on 3 ranks (the state is per node).
mpi 3 "$SNL" solve "$T/net2.h5" -o "$T/resumed3.h5" "${ARGS[@]}" --restart "$T/ck.h5" --json "$T/res3.json" -q ||
  fail "the restart on 3 ranks failed"
grep -q '"termination": "CONVERGENCE"' "$T/res3.json" || { cat "$T/res3.json"; fail "the 3-rank restart did not converge"; }
near "$(cost "$T/res3.json")" "$(cost "$T/rel2.json")" 1e-6 "restart on 3 ranks"
echo "ok: restart on 3 ranks converged to f_hat $(cost "$T/res3.json")"
# Restarting with the replay is refused (the checkpoint records --mode free).
set +e
"$SNL" solve "$T/net2.h5" -o "$T/x.h5" --algorithm async --init random --tol 1e-6 --max-iter 100000 --history-every 50 \
  --restart "$T/ck.h5" -q 2> "$T/err"; rc=$?
set -e
[ $rc -ne 0 ] && grep -q -- "--mode free in the checkpoint" "$T/err" || { cat "$T/err"; fail "replay restart from a free checkpoint: status $rc"; }

# --straggler-delay: the synchronous relaxation waits for the slowed rank every
# iteration (10 x 0.05 s); in free mode the other rank goes on (more epochs
# than the straggler's); a rank that does not exist is refused.
mpi 2 "$SNL" solve "$T/net2.h5" -o "$T/slow.h5" --algorithm relaxation --max-iter 10 --tol 0 --straggler-delay 0.05 \
  --json "$T/slow.json" -q
$PY -c "import json,sys; s = json.load(open(sys.argv[1]))['solve_seconds']; sys.exit(0 if s >= 0.5 else 1)" "$T/slow.json" ||
  fail "--straggler-delay 0.05: 10 relaxation iterations took less than 0.5 s"
mpi 2 "$SNL" solve "$T/net2.h5" -o "$T/slowfree.h5" --algorithm async --mode free --max-iter 100000 --tol 0 \
  --target-cost "$($PY -c "print($(cost "$T/rel2.json") * 1.5)")" --straggler-delay 0.005 --json "$T/slowfree.json" -q
$PY -c "import json,sys; j = json.load(open(sys.argv[1]))
sys.exit(0 if j['termination'] == 'CONVERGENCE' and j['free_epochs_fastest_rank'] > j['free_epochs_slowest_rank'] else 1)" \
  "$T/slowfree.json" || { cat "$T/slowfree.json"; fail "free mode with a straggler: the fast rank did not go on"; }
set +e
"$MPIEXEC" "$MPIEXEC_NUMPROC_FLAG" 2 --oversubscribe "$SNL" solve "$T/net2.h5" -o "$T/x.h5" --algorithm relaxation \
  --straggler-delay 0.1 --straggler-rank 2 -q 2> "$T/err"; rc=$?
set -e
[ $rc -eq 1 ] && grep -q -- "--straggler-rank 2: the run has only 2 ranks" "$T/err" || { cat "$T/err"; fail "--straggler-rank 2 on 2 ranks: status $rc"; }
echo "ok: straggler"
echo "async_free: ok"
