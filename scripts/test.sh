#!/usr/bin/env bash
# Sets up, builds and runs every test: the Release build's full ctest suite,
# then the ASan+UBSan build's suite. Exit status non-zero on any failure.
set -euo pipefail
cd "$(dirname "$0")/.."
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
JOBS=$(nproc)

scripts/setup.sh build
(cd build && ctest --output-on-failure -j "$JOBS")

if [ "${SNL_SKIP_SANITIZE:-0}" != 1 ]; then
  echo "== sanitizer build (ASan + UBSan) =="
  scripts/setup.sh build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSNL_SANITIZE=ON
  # Open MPI's own allocations are reported as leaks; memory errors and UB are what we check.
  export ASAN_OPTIONS=detect_leaks=0:abort_on_error=0 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
  # The long end-to-end fault scenarios (repeated kills, restarts) ran above on the
  # Release build; under the sanitizers they would only repeat the same code paths
  # ten times slower; the install test builds an uninstrumented consumer; the Slurm
  # test exercises the batch scripts, not the library. Every
  # unit, MPI and other CLI test runs here.
  (cd build-asan && ctest --output-on-failure -j "$JOBS" -E "${SNL_ASAN_EXCLUDE:-cli.kill_restart|cli.checkpoint_restart|cli.install_consumer|fuzz|slurm.jobs}")
fi
