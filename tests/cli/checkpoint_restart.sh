#!/usr/bin/env bash
# Checkpoint/restart: a run stopped by SIGUSR1 (what Slurm's --signal sends)
# writes a checkpoint and exits with status 3; resuming on 1, 2 or 3 ranks gives
# positions bit-identical to the uninterrupted run (2D, and MM on a 3D network).
# Wrong network, wrong options and damaged checkpoints are refused with a
# clear message.
source "$(dirname "$0")/common.bash"
"$SNL" generate -o "$T/net.h5" --sensors 1000 --avg-degree 7 --sigma 0.05 --seed 21 -q
"$SNL" generate -o "$T/other.h5" --sensors 1000 --avg-degree 7 --sigma 0.05 --seed 22 -q
"$SNL" generate -o "$T/small.h5" --sensors 400 --avg-degree 7 --sigma 0.05 --seed 23 -q
"$SNL" generate -o "$T/net3.h5" --sensors 1000 --dim 3 --avg-degree 7 --sigma 0.05 --seed 24 -q
# mm3: MM on a 3D network (3D SIMD kernels, 3D edge variables in the checkpoint).
# pipeline4: four iterations per pass over memory (--temporal-block 4); its
# signal checkpoints fall on pass ends, and its positions equal pipeline's.
for case in async pipeline pipeline4 bb mm3 mm-accel mm; do  # mm last: the refusals below use its checkpoint
  alg=${case%[34]}
  ARGS=(--max-iter 400 --tol 0 -q)
  NET="$T/net.h5"
  EVERY=50
  if [ $case = async ]; then ARGS=(--max-iter 300 --tol 0 -q); NET="$T/small.h5"; EVERY=20; fi
  if [ $case = mm3 ]; then NET="$T/net3.h5"; fi
  if [ $case = mm-accel ]; then ARGS=(--max-iter 400 --tol 0 -q); fi  # z(k), z(k-1) and t in the checkpoint
  if [ $case = pipeline4 ]; then ARGS+=(--temporal-block 4); EVERY=40; fi
  mpi 2 "$SNL" solve "$NET" -o "$T/ref.$case.h5" --algorithm $alg "${ARGS[@]}"
  # Stop a run with SIGUSR1 after it has written some checkpoints.
  rm -f "$T/ck.h5"
  set +e
  # Slow checkpoint writes (test hook) keep the run alive until the signal lands.
  SNL_TEST_CHECKPOINT_DELAY=0.25 \
  "$MPIEXEC" "$MPIEXEC_NUMPROC_FLAG" 2 --oversubscribe -x SNL_TEST_CHECKPOINT_DELAY "$SNL" solve "$NET" -o "$T/stopped.h5" \
    --algorithm $alg "${ARGS[@]}" --checkpoint "$T/ck.h5" --checkpoint-every $EVERY &
  pid=$!
  for _ in $(seq 400); do [ -f "$T/ck.h5" ] && break; sleep 0.05; done
  sleep 0.2
  kill -USR1 $pid
  wait_watched $pid "$case: the signalled run"
  rc=$?
  set -e
  [ $rc -eq 3 ] || fail "$case: expected exit status 3 after SIGUSR1, got $rc"
  [ -f "$T/stopped.h5" ] && fail "$case: a stopped run must not write the result"
  for np in 1 3; do
    cp "$T/ck.h5" "$T/ck$np.h5"
    mpi $np "$SNL" solve "$NET" -o "$T/res.$case.$np.h5" --algorithm $alg "${ARGS[@]}" \
      --checkpoint "$T/ck$np.h5" --checkpoint-every 1000 --restart "$T/ck$np.h5"
    h5diff "$T/ref.$case.h5" "$T/res.$case.$np.h5" /positions || fail "$case: restart on $np ranks differs"
  done
done
h5diff "$T/ref.pipeline.h5" "$T/ref.pipeline4.h5" /positions || fail "--temporal-block 4 changed the positions"
ARGS=(--max-iter 400 --tol 0 -q)
# Refusals: another network, other options, damaged files.
expect_error() {  # expect_error PATTERN cmd...
  local pat=$1; shift
  set +e; "$@" > "$T/out" 2> "$T/err"; local rc=$?; set -e
  [ $rc -ne 0 ] || fail "accepted: $*"
  grep -q "$pat" "$T/err" || { cat "$T/err"; fail "message lacks '$pat': $*"; }
}
expect_error "another network" mpi 2 "$SNL" solve "$T/other.h5" -o "$T/x.h5" --algorithm bb "${ARGS[@]}" --restart "$T/ck.h5"
expect_error "incompatible options" mpi 2 "$SNL" solve "$T/net.h5" -o "$T/x.h5" --algorithm bb --max-iter 99 -q --restart "$T/ck.h5"
expect_error "incompatible options" mpi 2 "$SNL" solve "$T/net.h5" -o "$T/x.h5" --algorithm mm "${ARGS[@]}" \
  --temporal-block 2 --restart "$T/ck.h5"
head -c 3000 "$T/ck.h5" > "$T/trunc.h5"
expect_error "trunc.h5" mpi 2 "$SNL" solve "$T/net.h5" -o "$T/x.h5" --algorithm bb "${ARGS[@]}" --restart "$T/trunc.h5"
expect_error "not an snl checkpoint" mpi 1 "$SNL" solve "$T/net.h5" -o "$T/x.h5" --algorithm bb "${ARGS[@]}" --restart "$T/net.h5"
[ -f "$T/x.h5" ] && fail "a refused restart wrote output"
echo "checkpoint_restart: ok"
