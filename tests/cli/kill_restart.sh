#!/usr/bin/env bash
# Fault test: SIGKILL a 2-rank run at random moments (checkpoint writes made
# slow by a test hook, so some kills land inside a write), restart from what is
# on disk, repeat; the final positions equal the uninterrupted run bit for bit.
source "$(dirname "$0")/common.bash"
"$SNL" generate -o "$T/net.h5" --sensors 3000 --avg-degree 7 --sigma 0.05 --seed 5 -q
ARGS=(--algorithm pipeline --max-iter 3000 --tol 0 -q)
mpi 2 "$SNL" solve "$T/net.h5" -o "$T/ref.h5" "${ARGS[@]}"
export SNL_TEST_CHECKPOINT_DELAY=0.15
RANDOM=7
kills=0
for attempt in $(seq 40); do
  restart=()
  [ -f "$T/ck.h5" ] && restart=(--restart "$T/ck.h5")
  setsid "$MPIEXEC" "$MPIEXEC_NUMPROC_FLAG" 2 --oversubscribe "$SNL" solve "$T/net.h5" -o "$T/out.h5" "${ARGS[@]}" \
    --checkpoint "$T/ck.h5" --checkpoint-every 150 "${restart[@]}" &
  pid=$!
  delay=$(( (RANDOM % 120) + 40 ))
  for _ in $(seq $delay); do kill -0 $pid 2>/dev/null || break; sleep 0.01; done
  if kill -0 $pid 2>/dev/null && [ $kills -lt 6 ]; then
    kill -9 -- -$pid 2>/dev/null || true
    wait $pid 2>/dev/null || true
    kills=$((kills + 1))
    ls "$T"/ck.h5.tmp* > /dev/null 2>&1 && rm -f "$T"/ck.h5.tmp*  # what a killed writer leaves
    continue
  fi
  wait $pid || fail "run failed after $kills kills"
  break
done
[ -f "$T/out.h5" ] || fail "never finished"
[ $kills -ge 1 ] || fail "no kill happened (run too fast?)"
h5diff "$T/ref.h5" "$T/out.h5" /positions || fail "result after $kills kills differs from the uninterrupted run"
echo "kill_restart: $kills kills, result identical"
