#!/bin/bash
# As results-2026-12-02-default-micro.sh, for MM and mm-accel only, AVX2
# kernels: 1M sensors, one rank, the default network in 2D and 3D, three
# repetitions; BUILD (default build-bench) holds the benchmark build of the
# code to measure.
#   bash docs/data/perf/results-2026-12-02-accel-micro.sh > docs/data/perf/results-2026-12-02-accel-micro.txt
set -euo pipefail
cd "$(dirname "$0")/../../.."
BUILD=${BUILD:-build-bench}
echo "== $(date -u +%FT%TZ) $(grep -m1 'model name' /proc/cpuinfo) | flags: $(grep -m1 -o 'avx512f' /proc/cpuinfo || echo 'no avx512f')"
for dim in 2 3; do for rep in 1 2 3; do
  echo -n "dim=$dim rep=$rep SNL_SIMD=avx2 load=$(cut -d' ' -f1 /proc/loadavg): "
  SNL_SIMD=avx2 SNL_MICRO_NETWORK=default SNL_MICRO_DIM=$dim SNL_MICRO_SENSORS=1000000 \
    "$BUILD"/bin/snl_micro --benchmark_filter='BM_Iteration<kMM.*>/1' 2>&1 | grep -E "^BM" | awk '{printf "%s %s ms  ", $1, $2}'
  echo
done; done
