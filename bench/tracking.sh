#!/usr/bin/env bash
# Tracking from Python (docs/python.md): per frame, a solve warm-started from
# the last frame (python/examples/tracking.py, --warm-algorithm ml-agd) against
# a cold start (the default algorithm from its own start): time and RMSE.
# Serial, then on NP ranks (the same script under mpirun); each with the
# solver's default tolerance for the warm frames, then with WARM_TOL.
#   BUILD=build bench/tracking.sh > docs/data/python/tracking-run1.txt   (runs 1-3)
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${BUILD:-$ROOT/build-py}
PY=${PY:-/usr/bin/python3}
NP=${NP:-2}
ARGS=${ARGS:-"--sensors 2000 --frames 10 --step 0.002 --seed 1"}
WARM_TOL=${WARM_TOL:-1e-3}
export PYTHONPATH=$BUILD/python${PYTHONPATH:+:$PYTHONPATH}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
echo "# tracking: $(date -u +%Y-%m-%dT%H:%MZ) $(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo '?') $(nproc) cores; $ARGS"
for extra in "" "--warm-tol $WARM_TOL"; do
  # shellcheck disable=SC2086
  "$PY" "$ROOT/python/examples/tracking.py" $ARGS $extra
  # shellcheck disable=SC2086
  mpirun -np "$NP" "$PY" "$ROOT/python/examples/tracking.py" $ARGS $extra
done
