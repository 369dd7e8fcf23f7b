#!/bin/bash
# 1M sensors, one rank: relaxation and MM iteration (RCM order), 2D and 3D,
# before and after, AVX-512 / AVX2 / scalar. BEFORE: a directory holding the
# libsnl.so.0 of the earlier build (for the recorded file: the node-lane
# kernels of 4fc75ab without prefetch); "after" is build/.
#   BEFORE=/path/to/old/lib bash docs/data/perf/results-2026-11-29-prefetch-micro.sh
set -euo pipefail
cd "$(dirname "$0")/../../.."
: "${BEFORE:?set BEFORE to the directory holding the earlier libsnl.so.0}"
echo "== $(date -u +%FT%TZ) $(grep -m1 'model name' /proc/cpuinfo)"
for dim in 2 3; do for rep in 1 2 3; do for v in before after; do for simd in avx512 avx2 0; do
  lib=""; [ $v = before ] && lib=$BEFORE
  echo -n "dim=$dim $v SNL_SIMD=$simd: "
  LD_LIBRARY_PATH=$lib SNL_SIMD=$simd SNL_MICRO_DIM=$dim SNL_MICRO_SENSORS=1000000 build/bin/snl_micro --benchmark_filter='BM_Iteration<k.*>/1' 2>&1 | grep -E "^BM" | awk '{printf "%s %s ms  ", $1, $2}'; echo
done; done; done; done
