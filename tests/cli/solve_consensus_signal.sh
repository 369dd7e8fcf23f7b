#!/usr/bin/env bash
# snl consensus solve under signals: SIGTERM (and SIGUSR1) stop a run after it
# writes a checkpoint (exit 3, no result written); --restart on another number
# of ranks ends with the uninterrupted run's x and history, bit for bit. A
# checkpoint of other options or of another problem is refused.
source "$(dirname "$0")/common.bash"
"$SNL" consensus generate -o "$T/p.h5" --nodes 80 --seed 11 -q
"$SNL" consensus generate -o "$T/q.h5" --nodes 80 --seed 12 -q
same() {  # x and every history column identical
  h5diff "$1" "$2" /x > /dev/null || fail "$3: x differs"
  h5diff "$1" "$2" /history > /dev/null || fail "$3: history differs"
}
# Seconds per primal iteration (SNL_TEST_CONSENSUS_DELAY): Newton converges in
# 5 iterations, so it gets longer ones; the signal lands 0.3 s after every rank
# has its handler installed, well inside every run.
# The snl ranks in process group $1; none yet (ps finds no process before
# setsid has made the group, and exits 1) is an empty list, not a failure of
# the script under pipefail.
rank_pids() { ps -o pid=,comm= -g "$1" | awk '$2 == "snl" {print $1}' || true; }
for case in "0.5 newton-tree --dual splitting" "0.2 subgradient --max-iter 40" "0.2 incremental --max-iter 40"; do
  read -r delay m <<< "$case"
  read -r -a ARGS <<< "--method $m -q"
  mpi 2 "$SNL" consensus solve "$T/p.h5" -o "$T/ref.h5" "${ARGS[@]}"
  for sig in TERM USR1; do
    rm -f "$T/ck.h5" "$T/out.h5"
    SNL_TEST_CONSENSUS_DELAY=$delay setsid "$MPIEXEC" "$MPIEXEC_NUMPROC_FLAG" 3 --oversubscribe \
      -x SNL_TEST_CONSENSUS_DELAY "$SNL" consensus solve "$T/p.h5" -o "$T/out.h5" "${ARGS[@]}" --checkpoint "$T/ck.h5" &
    pid=$!
    # The signal goes to the ranks (as a batch system sends it), not to mpirun.
    ranks=""
    for _ in $(seq 200); do
      ranks=$(rank_pids "$pid")
      [ "$(echo "$ranks" | wc -w)" -eq 3 ] && break
      sleep 0.05
    done
    # shellcheck disable=SC2086  # ranks: a list of pids
    wait_caught "$sig" $ranks || fail "$m: the ranks did not install their SIG$sig handler"
    sleep 0.3
    ranks=$(rank_pids "$pid")
    [ -n "$ranks" ] || fail "$m: the run ended before the signal"
    kill -s "$sig" $ranks
    rc=0
    wait_watched "$pid" "$m: the signalled run" || rc=$?
    [ "$rc" -eq 3 ] || fail "$m: SIG$sig gave exit $rc, expected 3"
    [ -f "$T/ck.h5" ] || fail "$m: no checkpoint after SIG$sig"
    [ -f "$T/out.h5" ] && fail "$m: a result was written after SIG$sig"
    mpi 1 "$SNL" consensus solve "$T/p.h5" -o "$T/out.h5" "${ARGS[@]}" --restart "$T/ck.h5"
    same "$T/ref.h5" "$T/out.h5" "$m after SIG$sig, resumed on 1 rank"
  done
  # Refused: other options, another problem (one error line, exit 1, output untouched).
  cp "$T/ref.h5" "$T/keep.h5"
  rc=0
  mpi 2 "$SNL" consensus solve "$T/p.h5" -o "$T/ref.h5" --method central -q --restart "$T/ck.h5" 2> "$T/err" || rc=$?
  [ "$rc" -eq 1 ] && grep -q "checkpoint of other options" "$T/err" || fail "$m: other options not refused ($rc)"
  rc=0
  mpi 2 "$SNL" consensus solve "$T/q.h5" -o "$T/ref.h5" "${ARGS[@]}" --restart "$T/ck.h5" 2> "$T/err" || rc=$?
  [ "$rc" -eq 1 ] && grep -q "checkpoint of another problem" "$T/err" || fail "$m: other problem not refused ($rc)"
  [ "$(grep -c 'snl: error' "$T/err")" -eq 1 ] || fail "$m: expected one error line"
  cmp -s "$T/ref.h5" "$T/keep.h5" || fail "$m: a refused restart touched the output"
done
echo "solve_consensus_signal: signals, restarts and refusals as expected"
