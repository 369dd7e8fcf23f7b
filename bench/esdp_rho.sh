#!/usr/bin/env bash
# esdp-dist's ADMM penalty rho against its communications and end point on
# 003's network 1 (inputs/net10_s0.05.h5), stopped by the relative improvement
# 1e-6 (at most 100000 iterations), beside the centralized esdp's objective.
# Writes docs/data/esdp_rho.csv. Usage: bench/esdp_rho.sh [SNL]
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
SNL=${1:-$ROOT/build/bin/snl}
NET=$ROOT/inputs/net10_s0.05.h5
W=$(mktemp -d "${TMPDIR:-/tmp}/esdp_rho.XXXXXX")
trap 'rm -rf "$W"' EXIT
j() { /usr/bin/python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(','.join(repr(d[k]) for k in sys.argv[2:]))" "$@"; }
"$SNL" solve "$NET" -o "$W/c.h5" --algorithm esdp --json "$W/c.json" -q
echo "rho,iterations,communications_per_sensor,objective,esdp_objective,rmse"
for rho in 0.1 0.3 1 3 10; do
  "$SNL" solve "$NET" -o "$W/d.h5" --algorithm esdp-dist --stop papers --tol 1e-6 --max-iter 100000 \
    --esdp-rho $rho --json "$W/d.json" -q
  echo "$rho,$(j "$W/d.json" iterations communications_per_sensor relaxation_objective),$(j "$W/c.json" relaxation_objective),$(j "$W/d.json" rmse)"
done
