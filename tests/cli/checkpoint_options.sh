#!/usr/bin/env bash
# What a checkpoint must match (checkpoint_options() in checkpoint.hpp): a
# restart that changes exactly one of those options, or the network, is refused
# with one message naming that option, a non-zero status, and the output and
# checkpoint files untouched. A restart that repeats them resumes (from an
# iteration > 0) and ends with the uninterrupted run's bytes, also with another
# --partition, --init or (for methods without a random clock) --seed, which the
# checkpoint's iterates make irrelevant. --check-monotone is refused for the
# methods without a monotone surrogate.
source "$(dirname "$0")/common.bash"
"$SNL" generate -o "$T/net.h5" --sensors 400 --avg-degree 7 --sigma 0.05 --seed 31 -q
"$SNL" generate -o "$T/other.h5" --sensors 400 --avg-degree 7 --sigma 0.05 --seed 32 -q

# Base runs: each writes checkpoints every EVERY iterations; the file keeps the
# last one before the end (a mid-run state).
PIPE=(--algorithm pipeline --max-iter 120 --tol 1e-12 --grad-tol 1e-14 --history-every 5 --temporal-block 2)
BB=(--algorithm bb --max-iter 60 --tol 0 --bb-rounds 10)
ASYNC=(--algorithm async --max-iter 60 --tol 0 --seed 7)
for base in PIPE BB ASYNC; do
  declare -n A=$base
  mpi 2 "$SNL" solve "$T/net.h5" -o "$T/ref.$base.h5" "${A[@]}" -q --checkpoint "$T/ck.$base.h5" --checkpoint-every 20
  [ -f "$T/ck.$base.h5" ] || fail "$base: no checkpoint written"
done

# refused BASE PATTERN NET opts...: a restart from BASE's checkpoint with opts is
# refused: status != 0, exactly one "snl:" line and it matches PATTERN, the
# output and the checkpoint (also given as --checkpoint) byte-identical.
refused() {
  local base=$1 pat=$2 net=$3; shift 3
  echo "sentinel" > "$T/out.h5"
  cp "$T/ck.$base.h5" "$T/ck.copy.h5"
  set +e
  mpi 2 "$SNL" solve "$net" -o "$T/out.h5" "$@" -q --restart "$T/ck.copy.h5" \
    --checkpoint "$T/ck.copy.h5" --checkpoint-every 20 > "$T/stdout" 2> "$T/err"
  local rc=$?
  set -e
  [ $rc -ne 0 ] || fail "$base: restart with $* accepted"
  [ "$(grep -c '^snl:' "$T/err")" -eq 1 ] || { cat "$T/err"; fail "$base: not one message for $*"; }
  grep -q "^snl: error: .*$pat" "$T/err" || { cat "$T/err"; fail "$base: message lacks '$pat' for $*"; }
  [ "$(cat "$T/out.h5")" = sentinel ] || fail "$base: a refused restart touched the output ($*)"
  cmp -s "$T/ck.$base.h5" "$T/ck.copy.h5" || fail "$base: a refused restart touched the checkpoint ($*)"
}
# with BASE-ARRAY-NAME OPTION VALUE: BASE's options with OPTION's value replaced (or appended).
with() {
  declare -n B=$1
  local opt=$2 val=$3 out=() i=0 found=0
  while [ $i -lt ${#B[@]} ]; do
    if [ "${B[$i]}" = "$opt" ]; then out+=("$opt" "$val"); found=1; else out+=("${B[$i]}" "${B[$((i + 1))]}"); fi
    i=$((i + 2))
  done
  [ $found -eq 1 ] || out+=("$opt" "$val")
  printf '%s\n' "${out[@]}"
}
# resumed BASE opts...: a restart from BASE's checkpoint with opts succeeds, from
# an iteration > 0, with the uninterrupted run's positions.
resumed() {
  local base=$1; shift
  cp "$T/ck.$base.h5" "$T/ck.copy.h5"
  mpi 2 "$SNL" solve "$T/net.h5" -o "$T/res.h5" "$@" --restart "$T/ck.copy.h5" 2> "$T/err" ||
    { cat "$T/err"; fail "$base: restart with $* refused"; }
  grep -Eq "resuming from .* iteration [1-9][0-9]*" "$T/err" || { cat "$T/err"; fail "$base: no resume reported"; }
  h5diff "$T/ref.$base.h5" "$T/res.h5" /positions || fail "$base: restart with $* differs from the uninterrupted run"
}

mapfile -t o < <(with PIPE --algorithm relaxation);  refused PIPE "--algorithm pipeline in the checkpoint, relaxation now" "$T/net.h5" "${o[@]}"
mapfile -t o < <(with PIPE --max-iter 240);          refused PIPE "--max-iter 120 in the checkpoint, 240 now" "$T/net.h5" "${o[@]}"
mapfile -t o < <(with PIPE --tol 1e-11);             refused PIPE "--tol 9.9999999999999998e-13 in the checkpoint, 9.9999999999999994e-12 now" "$T/net.h5" "${o[@]}"
mapfile -t o < <(with PIPE --grad-tol 1e-13);        refused PIPE "--grad-tol .* in the checkpoint, .* now" "$T/net.h5" "${o[@]}"
mapfile -t o < <(with PIPE --history-every 10);      refused PIPE "--history-every 5 in the checkpoint, 10 now" "$T/net.h5" "${o[@]}"
mapfile -t o < <(with PIPE --test-every 20);         refused PIPE "--test-every its default in the checkpoint, 20 now" "$T/net.h5" "${o[@]}"
mapfile -t o < <(with PIPE --temporal-block 4);      refused PIPE "--temporal-block 2 in the checkpoint, 4 now" "$T/net.h5" "${o[@]}"
mapfile -t o < <(with PIPE --temporal-block 1);      refused PIPE "--temporal-block 2 in the checkpoint, its default now" "$T/net.h5" "${o[@]}"
mapfile -t o < <(with BB --bb-rounds 20);            refused BB "--bb-rounds 10 in the checkpoint, 20 now" "$T/net.h5" "${o[@]}"
mapfile -t o < <(with ASYNC --seed 8);               refused ASYNC "--seed 7 in the checkpoint, 8 now" "$T/net.h5" "${o[@]}"
refused PIPE "another network" "$T/other.h5" "${PIPE[@]}"

# Options that need not match.
resumed PIPE "${PIPE[@]}"
resumed BB "${BB[@]}"
resumed ASYNC "${ASYNC[@]}"
resumed PIPE "${PIPE[@]}" --partition block
resumed PIPE "${PIPE[@]}" --seed 99
"$SNL" solve "$T/other.h5" -o "$T/start.h5" --algorithm relaxation --max-iter 5 -q
resumed PIPE "${PIPE[@]}" --init "$T/start.h5"
mpi 1 "$SNL" solve "$T/net.h5" -o "$T/res.h5" "${ASYNC[@]}" -q --restart "$T/ck.ASYNC.h5"  # and on one rank
h5diff "$T/ref.ASYNC.h5" "$T/res.h5" /positions || fail "ASYNC: restart on 1 rank differs"

# --check-monotone: refused (usage error, status 2) where there is no monotone surrogate.
for alg in relaxation bb pm async async-exact; do
  set +e
  mpi 2 "$SNL" solve "$T/net.h5" -o "$T/cm.h5" --algorithm $alg --max-iter 2 --check-monotone -q 2> "$T/err"
  rc=$?
  set -e
  [ $rc -eq 2 ] || { cat "$T/err"; fail "--check-monotone with $alg: status $rc, expected 2"; }
  [ "$(grep -c '^snl:' "$T/err")" -eq 1 ] && grep -q "^snl: error: --check-monotone is not honoured by --algorithm $alg" "$T/err" ||
    { cat "$T/err"; fail "--check-monotone with $alg: not one clear message"; }
  [ -f "$T/cm.h5" ] && fail "--check-monotone with $alg wrote output"
done
for alg in mm pipeline; do
  mpi 2 "$SNL" solve "$T/net.h5" -o "$T/cm.h5" --algorithm $alg --max-iter 20 --check-monotone -q ||
    fail "--check-monotone refused for $alg"
done
echo "checkpoint_options: ok"
