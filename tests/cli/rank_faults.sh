#!/usr/bin/env bash
# Rank faults (issue #5): one rank fails (fault injection, SNL_TEST_FAIL=
# <point>:<rank>[:<iteration>]) while the others go on; every rank must stop,
# with a non-zero status and one message, never a hang (timeout 60).
#   read   after the slab read: agreed like a bad slab -> clean error, status 1
#   setup  start of problem setup (others already in collectives)
#   alloc  std::bad_alloc between two collectives of the setup
#   solve  an exception inside iteration K
# setup/alloc/solve cannot be agreed on without a hang: the failing rank prints
# "snl: error: rank R: ...; aborting all ranks" and calls MPI_Abort (status 70;
# Open MPI adds its own MPI_ABORT banner).
source "$(dirname "$0")/common.bash"
"$SNL" generate -o "$T/net.h5" --sensors 400 --avg-degree 6 --sigma 0.05 --seed 3 -q
"$SNL" solve "$T/net.h5" -o "$T/keep.h5" --max-iter 5 --tol 0 -q
sum0=$(md5sum < "$T/keep.h5")
n=0
check() {  # check NP SPEC EXPECTED_STATUS MESSAGE_REGEX
  local np=$1 spec=$2 want=$3 msg=$4
  run_failing "$np" "$spec" "SNL_TEST_FAIL=$spec" "$want" "$msg" solve "$T/net.h5" -o "$T/keep.h5" \
    --algorithm pipeline --max-iter 30 --tol 0 -q
  [ "$NERR" -eq 1 ] || { cat "$T/err"; fail "$spec np=$np: expected exactly one error message, got $NERR"; }
  [ "$(md5sum < "$T/keep.h5")" = "$sum0" ] || fail "$spec np=$np: existing output was modified"
  ! ls "$T" | grep -q '\.tmp-' || fail "$spec np=$np: temporary file left behind"
  echo "ok: $spec np=$np status $want: $(grep '^snl: error: ' "$T/err")"
  n=$((n + 1))
}
for np in 2 3; do
  last=$((np - 1))
  check $np "read:$last" 1 "injected failure at 'read' on rank $last"
  check $np "read:0" 1 "injected failure at 'read' on rank 0"
  check $np "setup:$last" 70 "rank $last: injected failure at 'setup'.*aborting all ranks"
  check $np "alloc:$last" 70 "rank $last: out of memory during problem setup; aborting all ranks"
  check $np "alloc:0" 70 "rank 0: out of memory during problem setup; aborting all ranks"
  check $np "solve:$last:7" 70 "rank $last: injected failure at 'solve' on rank $last iteration 7.*aborting all ranks"
  check $np "solve:0:25" 70 "rank 0: injected failure at 'solve' on rank 0 iteration 25.*aborting all ranks"
done
# A hook aimed at a rank that does not exist changes nothing.
SNL_TEST_FAIL=alloc:9 "$SNL" solve "$T/net.h5" -o "$T/ok.h5" --max-iter 5 --tol 0 -q
echo "rank_faults: $n failing runs checked"
