#!/bin/bash
# The rows of results-2026-12-02-default-micro.sh on a host with AVX-512: 1M
# sensors, one rank, one relaxation and one MM iteration (RCM order), 2D and 3D,
# on the generator's default network (degree 16 in 2D, 24 in 3D), with the
# AVX-512 kernels (SNL_SIMD unset: 8 nodes per register), the AVX2 kernels (4)
# and the scalar twins, three alternated repetitions. Needs the benchmark build
# (-DSNL_BUILD_BENCH=ON) in BUILD (default build-bench) and a CPU with avx512f.
#   bash docs/data/perf/results-2026-12-02-default-micro-avx512.sh > docs/data/perf/results-2026-12-02-default-micro-avx512.txt
set -euo pipefail
cd "$(dirname "$0")/../../.."
BUILD=${BUILD:-build-bench}
echo "== $(date -u +%FT%TZ) $(grep -m1 'model name' /proc/cpuinfo) | flags: $(grep -m1 -o 'avx512f' /proc/cpuinfo || echo 'no avx512f')"
for dim in 2 3; do for rep in 1 2 3; do for simd in avx512 avx2 0; do
  echo -n "dim=$dim rep=$rep SNL_SIMD=$simd load=$(cut -d' ' -f1 /proc/loadavg): "
  if [ "$simd" = avx512 ]; then unset SNL_SIMD; else export SNL_SIMD=$simd; fi
  SNL_MICRO_NETWORK=default SNL_MICRO_DIM=$dim SNL_MICRO_SENSORS=1000000 \
    "$BUILD"/bin/snl_micro --benchmark_filter='BM_Iteration<k.*>/1' 2>&1 | grep -E "^BM" | awk '{printf "%s %s ms  ", $1, $2}'
  echo
done; done; done
