#!/usr/bin/env bash
# Reproduces paper 003's tables and figures (docs/reproduction.md): Table I and
# Fig. 2 (the optimality gap on a 1-D star), Figs. 3-4 (relaxation quality and
# run time), Fig. 6 and Table II (Algorithm 1 against the distributed ESDP) and
# Fig. 7 (the asynchronous methods in f_hat). Outputs go to docs/ and docs/data/.
#   repro/003.sh [BUILD_DIR]      (default build; about an hour on 2 cores)
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
bash repro/repro_003_table1.sh "$BUILD" 500
/usr/bin/python3 repro/repro_003_fig34.py "$BUILD/bin/snl" 6
/usr/bin/python3 repro/repro_003_fig34.py "$BUILD/bin/snl" 3 inputs/net50_allanchors_s0.01.h5 _B
bash repro/repro_003_fig6.sh "$BUILD/bin/snl" 16
bash repro/repro_003_fig7.sh "$BUILD/bin/snl"
