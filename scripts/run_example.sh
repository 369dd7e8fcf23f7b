#!/usr/bin/env bash
# Sets up snl (dependencies + build) and runs the main job on a bundled example:
# the pipeline (disk relaxation, then the default refinement, mm-accel) on 2 MPI ranks, an
# evaluation with the Cramér-Rao bound, and a plot.
#   scripts/run_example.sh [NETWORK.h5] [RANKS]
set -euo pipefail
cd "$(dirname "$0")/.."
NET=${1:-inputs/net50_s0.05.h5}
NP=${2:-2}
scripts/setup.sh build
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
mkdir -p results
name=$(basename "$NET" .h5)
build/bin/snl info "$NET"
# Up to 30000 iterations per phase: the refinements' step 1/L is short on the 50-sensor examples.
mpirun -np "$NP" build/bin/snl solve "$NET" -o "results/$name.h5" --json "results/$name.json" --max-iter 30000
build/bin/snl eval "$NET" "results/$name.h5" --crlb
/usr/bin/python3 tools/plot_result.py "$NET" "results/$name.h5" -o "results/$name.png"
echo "results: results/$name.h5 (positions, history), results/$name.json (summary), results/$name.png (plot)"
