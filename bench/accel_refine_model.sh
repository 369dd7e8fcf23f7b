#!/usr/bin/env bash
# MM against mm-accel under a measurement model (docs/quality.md, "mm-accel
# under weights and Huber"): bench/accel_refine.sh, with
#   weighted/: the two benchmark networks with their true sigmas (0.1 d,
#     bench/quality_add_sigmas.py), --weights file;
#   huber/: 1,000 sensors with 10% and 20% NLOS ranges (the networks of
#     bench/quality_weights.sh, seed 1), --loss huber:0.02.
#   bench/accel_refine_model.sh [OUT] [MAX_ITER] [RANKS]
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-docs/data/accel/model} MAXIT=${2:-20000} NP=${3:-1}
BENCH_DIR=${BENCH_DIR:-../shared/benchmarks}
SNL=${SNL:-build/bin/snl}
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
for b in test10-500 test20-1000; do
  /usr/bin/python3 bench/quality_add_sigmas.py "$BENCH_DIR/$b.h5" "$T/$b.h5" 0.1
done
SOLVE_ARGS="--weights file" bench/accel_refine.sh "$OUT/weighted" "$MAXIT" 1 "$NP" "$T/test10-500.h5" "$T/test20-1000.h5"
for f in 0.1 0.2; do
  "$SNL" generate -q -o "$T/nlos$f.h5" --sensors 1000 --avg-degree 10 --anchors corners --anchor-radius 0.3 \
    --sigma 0.01 --seed 1 --nlos-fraction "$f" --nlos-bias 0.3 --localizable no
done
SOLVE_ARGS="--loss huber:0.02" bench/accel_refine.sh "$OUT/huber" "$MAXIT" 1 "$NP" "$T/nlos0.1.h5" "$T/nlos0.2.h5"
