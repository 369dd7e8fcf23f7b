#!/usr/bin/env bash
# Does asynchrony pay against a straggler? On NP ranks and a generated network
# of N sensors, from the distance-vector start (--init dv), the time for the
# synchronous relaxation (Nesterov, --algorithm relaxation) and for 003's
# asynchronous method run for real (--algorithm async --mode free) to bring
# the relaxed cost f_hat to a target (--target-cost: tested every 50
# iterations by the relaxation, by its own estimate then an exact test by free
# mode), with and without a straggler: the last rank sleeps DELAY seconds per
# iteration (free mode: per n_own activations of its own; --straggler-delay).
# The target is (1 + REL) times f_hat after REF_ITERS relaxation iterations.
# Time = solve_seconds (the Solver's run: iterations, tests and records, not
# the dv start); the relaxation tests the target every 10 iterations (an extra
# cost evaluation each, about one iteration's time). Every run is one line; a run that does not reach the target
# within its --max-iter says so. iters: the relaxation's iterations; free
# mode's most and fewest epochs (n_own activations) of a rank, the fewest
# being the straggler's. Raw table on stdout, CSV to $CSV; the plot:
# bench/plot_async_straggler.py.
#
#   bench/async_straggler.sh > docs/data/perf/async-straggler.txt
# Environment: N (100000), NP (2), REPS (2), DELAYS ("0 0.02 0.1 0.5"), REL (0.5),
# REF_ITERS (300), MAX_REL (3000), MAX_FREE (5000), WORK (/tmp/snl-async),
# BIN (build/bin), CSV (docs/data/perf/async-straggler.csv).
# About 4 minutes on a 2-core VM.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
BIN=${BIN:-$here/build/bin}
N=${N:-100000}
NP=${NP:-2}
REPS=${REPS:-2}
DELAYS=${DELAYS:-0 0.02 0.1 0.5}
REL=${REL:-0.5}
REF_ITERS=${REF_ITERS:-300}
MAX_REL=${MAX_REL:-3000}
MAX_FREE=${MAX_FREE:-5000}
WORK=${WORK:-/tmp/snl-async}
CSV=${CSV:-$here/docs/data/perf/async-straggler.csv}
export OMPI_ALLOW_RUN_AS_ROOT=${OMPI_ALLOW_RUN_AS_ROOT:-1} OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=${OMPI_ALLOW_RUN_AS_ROOT_CONFIRM:-1}
export OMPI_MCA_rmaps_base_oversubscribe=${OMPI_MCA_rmaps_base_oversubscribe:-1}
mkdir -p "$WORK"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
net=$WORK/net_$N.h5
[ -f "$net" ] || "$BIN/snl" generate --sensors "$N" -o "$net" -q

# json KEY...: the values of the JSON summary's keys, space-separated.
json() { /usr/bin/python3 -c 'import json, sys
j = json.load(open(sys.argv[1]))
print(" ".join(str(j[k]) for k in sys.argv[2:]))' "$tmp/s.json" "$@"; }

solve() {
  mpirun -np "$NP" "$BIN/snl" solve "$net" -o "$tmp/out.h5" --init dv --json "$tmp/s.json" -q "$@" > /dev/null
}

solve --algorithm relaxation --max-iter "$REF_ITERS" --tol 0
ref=$(json relaxed_cost)
target=$(/usr/bin/python3 -c "print(f'{$ref * (1 + $REL):.6g}')")
echo "# bench/async_straggler.sh $(date -u +%Y-%m-%dT%H:%MZ) n=$N np=$NP reps=$REPS host=$(hostname) load: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "# $("$BIN/snl" --version 2>/dev/null | head -1)"
echo "# target f_hat $target = (1 + $REL) x f_hat after $REF_ITERS relaxation iterations from --init dv ($ref)"
echo "# straggler: rank $((NP - 1)) sleeps DELAY s per iteration (free: per n_own activations of its own)"
printf '%-10s %6s %3s %10s %8s %8s %14s %8s %12s %s\n' method delay rep seconds iters fewest f_hat reached mpi_bytes message
echo "method,delay,rep,seconds,iterations,fewest_epochs,relaxed_cost,reached,mpi_bytes,target,n,np" > "$CSV"
for rep in $(seq 1 "$REPS"); do
  for delay in $DELAYS; do
    for m in relaxation free; do
      if [ $m = relaxation ]; then
        solve --algorithm relaxation --max-iter "$MAX_REL" --tol 0 --target-cost "$target" --test-every 10 \
          --straggler-delay "$delay"
      else
        solve --algorithm async --mode free --max-iter "$MAX_FREE" --tol 0 --target-cost "$target" --straggler-delay "$delay"
      fi
      read -r solve_s iters cost bytes term < <(json solve_seconds iterations relaxed_cost mpi_bytes termination)
      fewest=$iters
      [ $m = free ] && fewest=$(json free_epochs_slowest_rank | cut -d. -f1)
      secs=$(/usr/bin/python3 -c "print(f'{$solve_s:.3f}')")
      reached=$([ "$term" = CONVERGENCE ] && echo yes || echo no)
      msg=$(json message)
      printf '%-10s %6s %3d %10s %8d %8d %14.6f %8s %12d %s\n' $m "$delay" "$rep" "$secs" "$iters" "$fewest" "$cost" $reached \
        "$bytes" "$msg"
      echo "$m,$delay,$rep,$secs,$iters,$fewest,$cost,$reached,$bytes,$target,$N,$NP" >> "$CSV"
    done
  done
done
