#!/usr/bin/env bash
# Runs snl's algorithms on the two external benchmark networks of the field
# (../shared/benchmarks or $BENCH_DIR) and prints a markdown table.
#   tools/run_benchmarks.sh [RANKS]
set -euo pipefail
cd "$(dirname "$0")/.."
NP=${1:-2}
BENCH_DIR=${BENCH_DIR:-../shared/benchmarks}
SNL=${SNL:-build/bin/snl}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
row() {  # row NAME LABEL JSON
  /usr/bin/python3 - "$@" <<'PY'
import json, sys
name, label, path = sys.argv[1:4]
d = json.load(open(path))
g = lambda k, f: ("-" if d.get(k) is None else format(d[k], f))
print(f"| {name} | {label} | {d['iterations']} | {d['termination']} | {d['ml_cost']:.5g} | {d['relaxed_cost']:.5g} | "
      f"{g('gap_certificate', '.4g')} | {d['apriori_bound']:.4g} | {d['rmse']:.5f} | {d['rmse_localizable']:.5f} | "
      f"{d['mpe']:.5f} | {d['communications_per_sensor']:.0f} | {d['reals_per_sensor']:.0f} | {d['wall_seconds']:.2f} |")
PY
}
echo "| network | method | iterations | termination | ML cost f | f_hat | gap certificate (22) at the relaxation's solution | a-priori (23) | RMSE | RMSE (localizable) | MPE | messages/sensor | reals/sensor | wall s |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
for b in test10-500 test20-1000; do
  net="$BENCH_DIR/$b.h5"
  # The papers' stopping rule and pipeline (relaxation then MM), as they report them.
  s() { mpirun -np "$NP" "$SNL" solve "$net" -q --stop papers "$@"; }
  s -o "$T/relax.h5" --algorithm relaxation --tol 1e-6 --max-iter 100000 --json "$T/relax.json"
  row $b "relaxation (003 Alg. 1), tol 1e-6" "$T/relax.json"
  s -o "$T/pipe.h5" --algorithm pipeline --refine mm --tol 1e-6 --max-iter 100000 --json "$T/pipe.json"
  row $b "pipeline: relaxation then MM (000), tol 1e-6" "$T/pipe.json"
  s -o "$T/mm.h5" --algorithm mm --init "$T/relax.h5" --tol 0 --max-iter 10000 --json "$T/mm.json"
  row $b "MM from relaxation, 10000 it" "$T/mm.json"
  s -o "$T/bb.h5" --algorithm bb --init "$T/relax.h5" --tol 0 --max-iter 476 --json "$T/bb.json"
  row $b "BB (T=20) from relaxation, 476 it (same reals as MM)" "$T/bb.json"
  s -o "$T/mmr.h5" --algorithm mm --tol 1e-6 --max-iter 100000 --json "$T/mmr.json"
  row $b "MM from random init, tol 1e-6" "$T/mmr.json"
  s -o "$T/bbr.h5" --algorithm bb --tol 1e-6 --max-iter 100000 --json "$T/bbr.json"
  row $b "BB from random init, tol 1e-6" "$T/bbr.json"
done
