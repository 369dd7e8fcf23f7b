#!/usr/bin/env bash
# Weighted ML and the Huber loss on data (docs/quality.md, "Weighted ML" and
# "NLOS outliers"): writes docs/data/quality/{benchmarks,nlos}.csv and the
# tables of docs/quality.md to stdout.
#   bench/quality_weights.sh [RANKS] [TRIALS]
# Part 1: the two benchmark networks (multiplicative noise, nf = 0.1): the
# default (dv-pipeline) and the pipeline (relaxation then mm-accel from the
# random start), unweighted and weighted, against the weighted CRLB
# (bench/quality_crlb.py, dense J^-1 over the localizable sensors).
# Part 2: 1,000 sensors (average degree 10, the 4 corner anchors with link
# radius 0.3, sigma 0.01) with 0/5/10/20% NLOS ranges (bias uniform in [0, 0.3]):
# the pipeline (--algorithm pipeline) with --loss l2 and huber:0.02, TRIALS
# networks (seeds 1..TRIALS).
set -euo pipefail
cd "$(dirname "$0")/.."
NP=${1:-2}
TRIALS=${2:-3}
BENCH_DIR=${BENCH_DIR:-inputs/benchmarks}
SNL=${SNL:-build/bin/snl}
OUT=${OUT:-docs/data/quality}
PY=/usr/bin/python3
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
mkdir -p "$OUT"
solve() { mpirun -np "$NP" "$SNL" solve -q "$@"; }
field() { $PY -c "import json,sys; d=json.load(open(sys.argv[1])); print(','.join(str(d[k]) for k in sys.argv[2:]))" "$@"; }
KEYS="iterations termination ml_cost rmse rmse_localizable"

# Rows: the pipeline unweighted; weighted from the measured ranges
# (multiplicative:0.1); weighted with the true sigmas (file, an oracle copy of
# the network, bench/quality_add_sigmas.py); and weighted MM (true sigmas)
# started from the unweighted pipeline's result.
echo "network,run,iterations,termination,ml_cost,rmse,rmse_localizable,crlb_rmse_localizable,localizable" > "$OUT/benchmarks.csv"
for b in test10-500 test20-1000; do
  net="$BENCH_DIR/$b.h5"
  crlb=$($PY bench/quality_crlb.py "$net" 0.1)
  $PY bench/quality_add_sigmas.py "$net" "$T/sig.h5" 0.1
  for alg in dv-pipeline pipeline; do
    solve "$net" -o "$T/r.h5" --algorithm $alg --weights none --json "$T/r.json"
    echo "$b,$alg --weights none,$(field "$T/r.json" $KEYS),$crlb" >> "$OUT/benchmarks.csv"
    solve "$net" -o "$T/r.h5" --algorithm $alg --weights multiplicative:0.1 --json "$T/r.json"
    echo "$b,$alg --weights multiplicative:0.1,$(field "$T/r.json" $KEYS),$crlb" >> "$OUT/benchmarks.csv"
    solve "$T/sig.h5" -o "$T/r.h5" --algorithm $alg --weights file --json "$T/r.json"
    echo "$b,$alg --weights file (true sigmas),$(field "$T/r.json" $KEYS),$crlb" >> "$OUT/benchmarks.csv"
  done
  solve "$net" -o "$T/u.h5" --algorithm pipeline --weights none -q
  solve "$T/sig.h5" -o "$T/r.h5" --weights file --algorithm mm --init "$T/u.h5" --json "$T/r.json"
  echo "$b,mm --weights file (true sigmas) from the unweighted pipeline,$(field "$T/r.json" $KEYS),$crlb" >> "$OUT/benchmarks.csv"
done

echo "seed,nlos_fraction,loss,iterations,termination,ml_cost,rmse,rmse_localizable" > "$OUT/nlos.csv"
for seed in $(seq 1 "$TRIALS"); do
  for f in 0 0.05 0.1 0.2; do
    "$SNL" generate -q -o "$T/n.h5" --sensors 1000 --avg-degree 10 --anchors corners --anchor-radius 0.3 --sigma 0.01 --seed "$seed" \
      --nlos-fraction "$f" --nlos-bias 0.3 --localizable no
    for loss in l2 huber:0.02; do
      solve "$T/n.h5" -o "$T/r.h5" --algorithm pipeline --loss "$loss" --json "$T/r.json"
      echo "$seed,$f,$loss,$(field "$T/r.json" $KEYS)" >> "$OUT/nlos.csv"
    done
  done
done
$PY bench/quality_tables.py "$OUT"
