#!/usr/bin/env bash
# 003's asynchronous method (Algorithm 2: async, eq. 20's step; with Algorithm 3:
# async-exact) in its replay mode, bit-identical to the sequential activation
# order (src/solvers/async.cpp), against one synchronous relaxation iteration:
# the time of n activations (one async "iteration") over the time of one
# relaxation iteration on the same network and ranks, and the MPI bytes per
# iteration and per activation. Each run also prints the final relaxed cost
# f_hat, so a fast wrong answer shows: async's cost is the same bits for any
# build that replays the same order (OLD: a build of the previous code, whose
# async is run once per repetition beside the new one) and any rank count.
# One line per run; the ratio is to the relaxation run just before, in the same
# repetition. Recorded runs: docs/data/perf/async-replay-*.txt.
# With FREE=1 (the default) also async --mode free (docs/async.md): each rank
# activates its own nodes unsynchronised, ITERS times n_own activations per
# rank (--max-iter, --tol 0), so its time per "iteration" is the slowest
# rank's per n_own activations; its cost is not reproducible (other bits on
# every run).
#
#   SIZES="100000 1000000" REPS=3 bench/async_replay.sh
# Environment: SIZES ("100000 1000000"), REPS (3), NP (2), ITERS (20: relaxation
# and async iterations; 10 from 10^6 sensors), EXACT_ITERS (3; async-exact runs
# below 10^6 sensors only), WORK (/tmp/snl-async: the networks, made with
# `snl generate --sensors N` if missing), BIN (build/bin), OLD (another snl
# binary whose async runs beside, below 10^6 sensors; unset: none), FREE (1: also async-free). About 2 minutes at 10^5 and 10^6
# with REPS=3 on a 2-core VM (the 10^6 network takes a minute to generate).
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
BIN=${BIN:-$here/build/bin}
SIZES=${SIZES:-100000 1000000}
REPS=${REPS:-3}
NP=${NP:-2}
EXACT_ITERS=${EXACT_ITERS:-3}
WORK=${WORK:-/tmp/snl-async}
OLD=${OLD:-}
FREE=${FREE:-1}
export OMPI_ALLOW_RUN_AS_ROOT=${OMPI_ALLOW_RUN_AS_ROOT:-1} OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=${OMPI_ALLOW_RUN_AS_ROOT_CONFIRM:-1}
mkdir -p "$WORK"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# run SNL N METHOD ITERS: one solve from the random start; prints
# "seconds_per_iteration mpi_bytes_per_iteration relaxed_cost".
run() {
  local snl=$1 n=$2 alg=$3 it=$4
  local extra=()
  [ "$alg" = async-free ] && alg=async extra=(--mode free)
  mpirun -np "$NP" "$snl" solve "$WORK/net_$n.h5" -o "$tmp/out.h5" --algorithm "$alg" "${extra[@]}" --init random \
    --max-iter "$it" --tol 0 --history-every 1000000 --json "$tmp/s.json" -q >/dev/null
  /usr/bin/python3 - "$tmp/s.json" "$it" <<'EOF'
import json, sys
j = json.load(open(sys.argv[1]))
it = int(sys.argv[2])
assert j["iterations"] == it, (j["iterations"], it)
print(f'{j["seconds_per_iteration"]:.6f} {j["mpi_bytes"] / it:.0f} {j["relaxed_cost"]:.15g}')
EOF
}

echo "# bench/async_replay.sh $(date -u +%Y-%m-%dT%H:%MZ) np=$NP reps=$REPS host=$(hostname) load: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "# $("$BIN/snl" --version 2>/dev/null | head -1)${OLD:+; OLD=$OLD}"
printf '%-8s %-12s %3s %10s %8s %14s %12s %s\n' n method rep ms_per_it ratio bytes_per_it bytes_per_act relaxed_cost
for n in $SIZES; do
  [ -f "$WORK/net_$n.h5" ] || "$BIN/snl" generate --sensors "$n" -o "$WORK/net_$n.h5" >/dev/null
  it=${ITERS:-$([ "$n" -ge 1000000 ] && echo 10 || echo 20)}
  for rep in $(seq 1 "$REPS"); do
    methods="relaxation async"
    [ "$FREE" = 1 ] && methods="$methods async-free"
    [ "$n" -lt 1000000 ] && methods="$methods async-exact"
    [ -n "$OLD" ] && [ "$n" -lt 1000000 ] && methods="$methods old-async"
    base=""
    for m in $methods; do
      snl="$BIN/snl" alg=$m iters=$it
      [ "$m" = async-exact ] && iters=$EXACT_ITERS
      [ "$m" = old-async ] && snl=$OLD alg=async
      read -r spi bpi cost < <(run "$snl" "$n" "$alg" "$iters")
      [ -z "$base" ] && base=$spi
      awk -v n="$n" -v m="$m" -v r="$rep" -v s="$spi" -v b="$base" -v bpi="$bpi" -v c="$cost" -v it="$iters" 'BEGIN {
        printf "%-8s %-12s %3d %10.3f %8.2f %14.0f %12.4f %s (%d iterations)\n", n, m, r, 1000 * s, s / b, bpi, bpi / n, c, it }'
    done
  done
done
