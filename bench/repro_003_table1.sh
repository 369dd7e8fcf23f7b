#!/usr/bin/env bash
# 003 Table I / Fig. 2: the quality of the disk relaxation on the 1-D star (one
# sensor at x = 3, anchors at 2, 4, 5: `snl generate --topology star`), sigma
# = 0.25, 500 noise draws. Per trial: the relaxation (Algorithm 1) from a
# random start to --tol 1e-12, then `snl eval --global-opt` for the exact ML
# optimum f*, the eq. (22) certificate and the eq. (23) bound.
#   bench/repro_003_table1.sh [SNL] [TRIALS]
# Writes docs/data/repro_003_table1.csv (one row per trial),
# docs/data/repro_003_table1.txt (the means) and docs/repro_003_fig2.png.
set -euo pipefail
SNL=${1:-build/bin/snl}
TRIALS=${2:-500}
cd "$(dirname "$0")/.."
SNL=$(realpath "$SNL")
W=$(mktemp -d /tmp/repro003t1.XXXXXX)
trap 'rm -rf "$W"' EXIT
trial() {  # trial T: network, relaxation and evaluation of noise draw T (seed T)
  "$SNL" generate --dim 1 --topology star --sensors 1 --sigma 0.25 --seed "$1" -o "$W/net_$1.h5" -q
  "$SNL" solve "$W/net_$1.h5" --algorithm relaxation --seed "$1" --tol 1e-12 --max-iter 100000 -o "$W/res_$1.h5" -q
  "$SNL" eval "$W/net_$1.h5" "$W/res_$1.h5" --global-opt --json "$W/eval_$1.json" > /dev/null
}
export -f trial
export SNL W
# Independent trials, 8 at a time (each process mostly waits on MPI start-up).
seq 1 "$TRIALS" | xargs -P 8 -I{} bash -c 'trial {}'
/usr/bin/python3 bench/repro_003_table1.py "$W" "$TRIALS" docs/data/repro_003_table1.csv docs/data/repro_003_table1.txt \
  docs/repro_003_fig2.png
