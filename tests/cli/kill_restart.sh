#!/usr/bin/env bash
# Fault test: SIGKILL a 2-rank run at random moments (checkpoint writes made
# slow by a test hook, so some kills land inside a write), restart from what is
# on disk, repeat; the final positions equal the uninterrupted run bit for bit,
# and the log shows that the restarts resumed from checkpoints (iteration > 0),
# not from scratch. A second case kills the pipeline once its checkpoint is in
# the refinement phase (the default, mm-accel) and checks that the restart
# resumes inside it.
source "$(dirname "$0")/common.bash"
"$SNL" generate -o "$T/net.h5" --sensors 3000 --avg-degree 7 --sigma 0.05 --anchors corners --side 1 --seed 5 -q 2> /dev/null
ARGS=(--algorithm pipeline --max-iter 3000 --tol 0)
REF=mm-accel  # the pipeline's default refinement on this network (no sigmas, l2)
mpi 2 "$SNL" solve "$T/net.h5" -o "$T/ref.h5" "${ARGS[@]}" -q
export SNL_TEST_CHECKPOINT_DELAY=0.15
# start_run LOG [extra...]: a 2-rank run in its own process group, resuming from ck.h5 if there is one.
start_run() {
  local log=$1; shift
  local restart=()
  [ -f "$T/ck.h5" ] && restart=(--restart "$T/ck.h5")
  setsid "$MPIEXEC" "$MPIEXEC_NUMPROC_FLAG" 2 --oversubscribe "$SNL" solve "$T/net.h5" -o "$T/out.h5" "${ARGS[@]}" \
    --checkpoint "$T/ck.h5" --checkpoint-every 150 "${restart[@]}" "$@" 2> "$log" &
  pid=$!
}
kill_run() {
  kill_session $pid  # mpirun and its ranks (each in a process group of its own)
  rm -f "$T"/ck.h5.tmp*  # what a killed writer leaves
}
# resumed_from LOG: the total iteration the run in LOG resumed from ("" if it did not resume).
resumed_from() { sed -n 's/^snl solve: resuming from .* (total iteration \([0-9]*\))$/\1/p' "$1"; }

RANDOM=7
kills=0 resumes=0
for attempt in $(seq 40); do
  had_ckpt=0
  [ -f "$T/ck.h5" ] && had_ckpt=1
  start_run "$T/log.$attempt"
  delay=$(( (RANDOM % 120) + 40 ))
  for _ in $(seq $delay); do kill -0 $pid 2>/dev/null || break; sleep 0.01; done
  if kill -0 $pid 2>/dev/null && [ $kills -lt 6 ]; then
    kill_run
    kills=$((kills + 1))
  else
    wait_watched $pid "attempt $attempt" || { cat "$T/log.$attempt"; fail "run failed after $kills kills"; }
  fi
  if [ $had_ckpt = 1 ]; then
    from=$(resumed_from "$T/log.$attempt")
    # A run killed before it read its checkpoint has not printed the line yet.
    if [ -n "$from" ]; then
      [ "$from" -gt 0 ] || fail "attempt $attempt resumed from iteration $from"
      resumes=$((resumes + 1))
    fi
  fi
  [ -f "$T/out.h5" ] && break
done
[ -f "$T/out.h5" ] || fail "never finished"
[ $kills -ge 1 ] || fail "no kill happened (run too fast?)"
[ $resumes -ge 1 ] || fail "no restart resumed from a checkpoint ($kills kills): the test proved nothing"
h5diff "$T/ref.h5" "$T/out.h5" /positions || fail "result after $kills kills differs from the uninterrupted run"
echo "kill_restart: $kills kills, $resumes resumes, result identical"

# Kill inside the pipeline's refinement: wait for a checkpoint whose phase is $REF.
rm -f "$T/ck.h5" "$T/out.h5"
start_run "$T/log.mm1"
phase=""
for _ in $(seq 1200); do
  kill -0 $pid 2>/dev/null || break
  [ -f "$T/ck.h5" ] && phase=$(h5dump -a /phase_algorithm "$T/ck.h5" 2>/dev/null | sed -n 's/.*(0): "\(.*\)".*/\1/p')
  [ "$phase" = $REF ] && break
  sleep 0.05
done
[ "$phase" = $REF ] || fail "no $REF checkpoint seen (phase '$phase')"
kill -0 $pid 2>/dev/null || fail "the run ended before it could be killed in $REF"
kill_run
[ -f "$T/out.h5" ] && fail "a killed run wrote its result"
unset SNL_TEST_CHECKPOINT_DELAY
start_run "$T/log.mm2"
wait_watched $pid "the restart in $REF" || { cat "$T/log.mm2"; fail "the restart in $REF failed"; }
grep -Eq "^snl solve: resuming from .* at $REF iteration [1-9][0-9]* \(total iteration [0-9]+\)$" "$T/log.mm2" ||
  { cat "$T/log.mm2"; fail "the restart did not resume inside $REF"; }
grep -q "^relaxation " "$T/log.mm2" && fail "the restart ran relaxation iterations again"
h5diff "$T/ref.h5" "$T/out.h5" /positions || fail "result after a kill in $REF differs from the uninterrupted run"
echo "kill_restart: killed and resumed inside $REF ($(grep '^snl solve: resuming' "$T/log.mm2")), result identical"
