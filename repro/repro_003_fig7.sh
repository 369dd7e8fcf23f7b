#!/usr/bin/env bash
# 003 Fig. 7 (final f_hat of the parallel Algorithm 1 and the asynchronous
# Algorithm 2 at the same communications): the two runs of docs/experiments.md
# ("Parallel Algorithm 1 vs the asynchronous Algorithm 2 at equal
# communications"), whose per-trial CSVs carry f_hat (003 eq. 6, column fhat)
# beside the ML cost and RMSE; then the table and docs/repro_003_fig7.png.
# Usage: repro/repro_003_fig7.sh [SNL]   (default build/bin/snl)
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
SNL=${1:-$ROOT/build/bin/snl}
OUT=$ROOT/docs/data
for net in B:net50_allanchors_s0.01 A:net50_s0.01; do
  "$SNL" experiment "$ROOT/inputs/${net#*:}.h5" -o "$OUT/fig7_async_${net%%:*}.csv" --start random \
    --algorithms relaxation,async,async-exact --tol 0 --budget 400 --sigmas 0.01,0.05,0.1 --trials 50 -q
done
/usr/bin/python3 "$ROOT/repro/repro_003_fig7.py" "$OUT/fig7_async_A.csv" "$OUT/fig7_async_B.csv" \
  "$ROOT/docs/repro_003_fig7.png" | tee "$OUT/repro_003_fig7.txt"
