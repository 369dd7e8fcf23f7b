#!/bin/bash
# 1M sensors, one rank: relaxation and MM iteration (RCM order), 2D and 3D,
# before (lib of commit 4fc75ab, /tmp/pf0) and after, AVX-512 / AVX2 / scalar.
cd /work/main
echo "== $(date -u +%FT%TZ) $(grep -m1 'model name' /proc/cpuinfo)"
for dim in 2 3; do for rep in 1 2 3; do for v in before after; do for simd in avx512 avx2 0; do
  lib=""; [ $v = before ] && lib=/tmp/pf0
  echo -n "dim=$dim $v SNL_SIMD=$simd: "
  LD_LIBRARY_PATH=$lib SNL_SIMD=$simd SNL_MICRO_DIM=$dim SNL_MICRO_SENSORS=1000000 build/bin/snl_micro --benchmark_filter='BM_Iteration<k.*>/1' 2>&1 | grep -E "^BM" | awk '{printf "%s %s ms  ", $1, $2}'; echo
done; done; done; done
