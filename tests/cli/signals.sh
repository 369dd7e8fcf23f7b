#!/usr/bin/env bash
# Stop surfaces of snl solve: SIGTERM (what Slurm sends every task at a time
# limit or scancel) makes a run write its checkpoint and exit with status 3, no
# result written; --checkpoint-seconds S writes a checkpoint once S seconds of
# the run have passed (none before). Resuming from either checkpoint starts at
# an iteration > 0 and ends with the uninterrupted run's bytes.
source "$(dirname "$0")/common.bash"
"$SNL" generate -o "$T/net.h5" --sensors 3000 --avg-degree 7 --sigma 0.05 --seed 41 -q
# The cases below need a run whose solve lasts well beyond its first second,
# on any machine: the iteration budget grows until the solve takes >= 3 s.
iters=4000
while :; do
  ARGS=(--algorithm pipeline --max-iter $iters --tol 0)
  rm -f "$T/ref.h5" "$T/ref.json"
  mpi 2 "$SNL" solve "$T/net.h5" -o "$T/ref.h5" --json "$T/ref.json" "${ARGS[@]}" -q
  solve_seconds=$(tr ',' '\n' < "$T/ref.json" | sed -n 's/^ *"solve_seconds": *//p')
  echo "uninterrupted run, --max-iter $iters: solve $solve_seconds s"
  [ "$(echo "$solve_seconds >= 3" | bc)" = 1 ] && break
  [ "$iters" -ge 1000000 ] && fail "the run stays shorter than 3 s at --max-iter $iters"
  iters=$((iters * 4))
done

# resume CKPT: resumes from CKPT (iteration > 0), result equal to ref.h5.
resume() {
  rm -f "$T/out.h5"
  mpi 2 "$SNL" solve "$T/net.h5" -o "$T/out.h5" "${ARGS[@]}" --restart "$1" 2> "$T/log.resume" ||
    { cat "$T/log.resume"; fail "resume from $1 failed"; }
  local from
  from=$(sed -n 's/^snl solve: resuming from .* (total iteration \([0-9]*\))$/\1/p' "$T/log.resume")
  [ -n "$from" ] && [ "$from" -gt 0 ] || { cat "$T/log.resume"; fail "did not resume from an iteration > 0"; }
  h5diff "$T/ref.h5" "$T/out.h5" /positions || fail "resumed from iteration $from: result differs"
  echo "resumed from total iteration $from: result identical"
}

# SIGTERM to every rank once the run iterates (its first progress line).
"$MPIEXEC" "$MPIEXEC_NUMPROC_FLAG" 2 --oversubscribe "$SNL" solve "$T/net.h5" -o "$T/stopped.h5" "${ARGS[@]}" \
  --progress-seconds 0.2 --checkpoint "$T/term.h5" 2> "$T/log.term" &
pid=$!
for _ in $(seq 600); do grep -q '^relaxation ' "$T/log.term" && break; sleep 0.05; done
grep -q '^relaxation ' "$T/log.term" || { cat "$T/log.term"; fail "the run did not start iterating"; }
[ -f "$T/term.h5" ] && fail "a checkpoint before any signal (none was asked for)"
ranks=$(pgrep -P $pid) || fail "no rank processes under mpirun"
for r in $ranks; do kill -TERM "$r"; done
set +e; wait_watched $pid "the run stopped by SIGTERM"; rc=$?; set -e
[ $rc -eq 3 ] || { cat "$T/log.term"; fail "SIGTERM: exit status $rc, expected 3"; }
[ -f "$T/term.h5" ] || fail "SIGTERM: no checkpoint written"
[ -f "$T/stopped.h5" ] && fail "SIGTERM: a stopped run wrote its result"
grep -q "resume with --restart $T/term.h5" "$T/log.term" || { cat "$T/log.term"; fail "SIGTERM: no resume hint"; }
resume "$T/term.h5"

# --checkpoint-seconds 1: the first checkpoint appears after >= 1 s of the run.
t0=$(date +%s.%N)
setsid "$MPIEXEC" "$MPIEXEC_NUMPROC_FLAG" 2 --oversubscribe "$SNL" solve "$T/net.h5" -o "$T/stopped.h5" "${ARGS[@]}" -q \
  --checkpoint "$T/sec.h5" --checkpoint-seconds 1 &
pid=$!
for _ in $(seq 1200); do [ -f "$T/sec.h5" ] && break; kill -0 $pid 2>/dev/null || break; sleep 0.01; done
t1=$(date +%s.%N)
[ -f "$T/sec.h5" ] || fail "--checkpoint-seconds 1: no checkpoint while the run lasted"
kill -0 $pid 2>/dev/null || fail "--checkpoint-seconds 1: the run ended before its checkpoint could be checked"
after=$(echo "$t1 - $t0" | bc)
[ "$(echo "$after >= 1" | bc)" = 1 ] || fail "--checkpoint-seconds 1: a checkpoint after only $after s"
echo "--checkpoint-seconds 1: first checkpoint after $after s"
# The file is renamed into place complete: stop the run (SIGKILL, all its processes) and resume from it.
kill_session $pid
resume "$T/sec.h5"
echo "signals: ok"
