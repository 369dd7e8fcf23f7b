#!/usr/bin/env bash
# Bad input end to end: every broken network (each spec rule, truncations,
# random corruptions) ends in one clear error, a non-zero exit on 1 and 2
# ranks, within seconds, and an existing output file is left untouched.
source "$(dirname "$0")/common.bash"
"$SNL" generate -o "$T/net.h5" --sensors 60 --avg-degree 6 --sigma 0.05 --seed 3 -q
"$PY" "$SNL_SOURCE_DIR/tools/make_bad_networks.py" "$T/net.h5" "$T/bad" --random 6 > "$T/list"
"$SNL" solve "$T/net.h5" -o "$T/keep.h5" --max-iter 5 --tol 0 -q
sum0=$(md5sum < "$T/keep.h5")
n=0
while read -r f; do
  name=$(basename "$f" .h5)
  for np in 1 2; do
    set +e
    timeout 60 "$MPIEXEC" "$MPIEXEC_NUMPROC_FLAG" $np --oversubscribe "$SNL" solve "$f" -o "$T/keep.h5" \
      --max-iter 5 --tol 0 -q < /dev/null > "$T/out" 2> "$T/err"
    rc=$?
    set -e
    [ $rc -eq 124 ] && fail "$name np=$np: hang (killed by timeout)"
    case $name in
      corrupt_*)  # a random corruption may hit bytes that do not matter
        if [ $rc -eq 0 ]; then sum0=$(md5sum < "$T/keep.h5"); continue; fi ;;
    esac
    [ $rc -ne 0 ] || fail "$name np=$np: accepted a broken file"
    [ $rc -lt 128 ] || fail "$name np=$np: crashed (status $rc)"; 
    nerr=$(grep -c '^snl: error: ' "$T/err" || true)
    [ "$nerr" -eq 1 ] || { cat "$T/err"; fail "$name np=$np: expected exactly one error message, got $nerr"; }
    grep -q "internal error" "$T/err" && fail "$name np=$np: internal error instead of a clear message"
    [ "$(md5sum < "$T/keep.h5")" = "$sum0" ] || fail "$name np=$np: existing output was modified"
    ls "$T"/keep.h5.tmp* > /dev/null 2>&1 && fail "$name np=$np: temporary file left behind"
    n=$((n + 1))
  done
  set +e
  "$SNL" info "$f" > /dev/null 2> "$T/err"; rc=$?
  set -e
  case $name in corrupt_*|no_anchors) ;; *) [ $rc -ne 0 ] || fail "info accepted $name";; esac
done < "$T/list"
echo "bad_input: $n failing runs checked"
# Usage errors (issue 46): exit status 2 and one message, the output untouched.
for bad in "solve $T/net.h5 -o $T/keep.h5 --seed -1" "solve $T/net.h5 -o $T/keep.h5 --checkpoint-every 5" \
           "generate -o $T/keep.h5 --sensors 10 --seed -1" "consensus generate -o $T/keep.h5 --nodes 10 --seed -1"; do
  set +e
  # shellcheck disable=SC2086
  "$SNL" $bad -q > /dev/null 2> "$T/err"; rc=$?
  set -e
  [ $rc -eq 2 ] || { cat "$T/err"; fail "$bad: exit status $rc, not 2"; }
  grep -q -- "--seed\|--checkpoint" "$T/err" || { cat "$T/err"; fail "$bad: the message does not name the option"; }
  [ "$(md5sum < "$T/keep.h5")" = "$sum0" ] || fail "$bad: existing output was modified"
done
# Invalid solver options: one clear message, a non-zero exit, the output untouched.
for bad in "--temporal-block 0" "--temporal-block 65" "--max-iter -1" "--test-every -1" "--test-every 20 --stop papers" \
           "--tol nan" "--tol -1" "--tol inf"; do
  set +e
  # shellcheck disable=SC2086
  mpi 2 "$SNL" solve "$T/net.h5" -o "$T/keep.h5" $bad -q > /dev/null 2> "$T/err"; rc=$?
  set -e
  [ $rc -ne 0 ] && [ $rc -lt 128 ] || fail "$bad: exit status $rc"
  [ "$(grep -c '^snl: error: ' "$T/err")" -eq 1 ] || { cat "$T/err"; fail "$bad: expected exactly one error message"; }
  [ "$(md5sum < "$T/keep.h5")" = "$sum0" ] || fail "$bad: existing output was modified"
  case $bad in
    --test-every*) grep -q -- "--test-every" "$T/err" || { cat "$T/err"; fail "$bad: unclear message"; } ;;
    --tol*) grep -q -- "--tol must be a finite number" "$T/err" || { cat "$T/err"; fail "$bad: unclear message"; } ;;
  esac
done
# Output directory missing, and an unwritable output: clear errors, no hang.
set +e
mpi 2 "$SNL" solve "$T/net.h5" -o "$T/nope/r.h5" -q 2> "$T/err"; rc=$?
set -e
[ $rc -ne 0 ] && grep -q "does not exist" "$T/err" || fail "missing output directory not reported"
