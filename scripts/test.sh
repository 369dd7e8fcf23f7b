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
  # Under the sanitizers every unit and MPI test runs (the library's code paths on
  # 1-3 ranks), with the CLI tests that drive the library's own error and
  # determinism paths. The long end-to-end scenarios (repeated kills, restarts,
  # signals, option and bad-file matrices, Slurm jobs) ran above on
  # the Release build; under the sanitizers they would repeat the same library
  # paths many times, ten times slower. The install test builds an uninstrumented
  # consumer.
  (cd build-asan && ctest --output-on-failure -j "$JOBS" -E "${SNL_ASAN_EXCLUDE:-cli.kill_restart|cli.checkpoint_restart|cli.checkpoint_options|cli.signals|cli.solve_consensus_signal|cli.option_matrix|cli.consensus_bad_input|cli.surface_experiment|cli.surface_solve_options|cli.install_consumer|fuzz|slurm.jobs}")
fi
