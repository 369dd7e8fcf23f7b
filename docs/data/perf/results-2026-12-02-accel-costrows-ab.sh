#!/usr/bin/env bash
# mm-accel's iteration, A: commit 977f25e (separate blend pass over y,
# acceptance costs with lane-by-lane row loads) against B: the extrapolating
# MM kernel plus the MM kernel's row loads in the AVX2 cost pass. Same
# protocol as results-2026-12-02-accel-fused-ab.sh (which it runs), 3 rounds.
#   A=old/bin/snl B=build-bench/bin/snl NET=net_1000000.h5 \
#     docs/data/perf/results-2026-12-02-accel-costrows-ab.sh
set -euo pipefail
ROUNDS=3 exec "$(dirname "$0")/results-2026-12-02-accel-fused-ab.sh"
