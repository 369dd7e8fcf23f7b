#!/usr/bin/env bash
# mm-accel's iteration with the edge variables' extrapolation formed inside
# the MM kernel (B) against a separate blend pass (A, commit 977f25e): the
# default 1M network, 1 and 2 ranks, 200 iterations from the same start, the
# builds by turns, ROUNDS rounds. Prints one line per run (seconds per
# iteration from the solve's JSON) and whether the positions are the same bytes.
#   A=old/bin/snl B=build-bench/bin/snl NET=net_1000000.h5 [ROUNDS=2] \
#     docs/data/perf/results-2026-12-02-accel-fused-ab.sh
set -euo pipefail
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
echo "# $(date -u +%FT%TZ) $(nproc) cores; load: $(cut -d' ' -f1-3 /proc/loadavg)"
for r in $(seq 1 "${ROUNDS:-2}"); do
  for np in 1 2; do
    for v in A B; do
      bin=${!v}
      mpirun -np "$np" "$bin" solve "$NET" -o "$T/$v.h5" --algorithm mm-accel --max-iter 200 --tol 0 -q --json "$T/$v.json"
      /usr/bin/python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(f'round {sys.argv[2]} ranks {sys.argv[3]} build {sys.argv[4]}: {1e3*d[\"seconds_per_iteration\"]:.1f} ms/iteration, ML cost {d[\"ml_cost\"]!r}')" "$T/$v.json" "$r" "$np" "$v"
    done
    /usr/bin/python3 -c "import h5py,sys; a=h5py.File(sys.argv[1])['positions'][:]; b=h5py.File(sys.argv[2])['positions'][:]; print('  positions identical:', a.tobytes()==b.tobytes())" "$T/A.h5" "$T/B.h5"
  done
done
