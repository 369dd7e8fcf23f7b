#!/usr/bin/env bash
# 003 Table I / Fig. 2: the quality of the disk relaxation on the 1-D star (one
# sensor at x = 3, anchors at 2, 4, 5: `snl generate --dim 1 --topology star`),
# sigma = 0.25, 500 noise draws. Per trial: the relaxation (Algorithm 1) from a
# random start to --tol 1e-12, the exact ML optimum f* (global_1d.hpp), the
# eq. (22) certificate and the eq. (23) bound. The trials run in one process
# (repro/repro_003_table1.cpp, built here against build/libsnl.so); the first
# three are checked against the CLI (generate, solve, eval --global-opt).
#   repro/repro_003_table1.sh [BUILD] [TRIALS]
# Writes docs/data/repro_003_table1.csv (one row per trial),
# docs/data/repro_003_table1.txt (the means) and docs/repro_003_fig2.png.
set -euo pipefail
BUILD=${1:-build}
TRIALS=${2:-500}
cd "$(dirname "$0")/.."
BUILD=$(realpath "$BUILD")
W=$(mktemp -d /tmp/repro003t1.XXXXXX)
trap 'rm -rf "$W"' EXIT
mpicxx -std=c++17 -O2 -Iinclude repro/repro_003_table1.cpp -L"$BUILD" -lsnl -Wl,-rpath,"$BUILD" -o "$W/table1"
"$W/table1" "$TRIALS" > docs/data/repro_003_table1.csv
for t in 1 2 3; do
  "$BUILD/bin/snl" generate --dim 1 --topology star --sensors 1 --sigma 0.25 --seed $t -o "$W/net.h5" -q
  "$BUILD/bin/snl" solve "$W/net.h5" --algorithm relaxation --seed $t --tol 1e-12 --max-iter 100000 -o "$W/res.h5" -q
  "$BUILD/bin/snl" eval "$W/net.h5" "$W/res.h5" --global-opt --json "$W/eval_$t.json" > /dev/null
done
/usr/bin/python3 repro/repro_003_table1.py docs/data/repro_003_table1.csv "$W" docs/data/repro_003_table1.txt \
  docs/repro_003_fig2.png
