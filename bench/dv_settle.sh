#!/usr/bin/env bash
# dv-pipeline's --settle-iter (the mm-accel iterations before ml-agd) against
# the final ML cost, RMSE and time (docs/dv-pipeline.md), on default
# networks (`snl generate --sensors N --seed S`); 1000000 settles to
# convergence (mm-accel's stopping rule ends the run; ml-agd then stops at once).
# A last row per network: ml-agd started at the true positions, the local
# minimum nearest the truth (an oracle start, for scale).
#   NP=2 WORK=/tmp/dvs bench/dv_settle.sh > docs/data/quality/dv_settle.txt
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
SNL=${SNL:-$ROOT/build/bin/snl}
NP=${NP:-2}
WORK=${WORK:-$(mktemp -d /tmp/snl_dvs.XXXXXX)}
NETS=${NETS:-"10000:1 10000:2 10000:3 100000:1 100000:2"}
SETTLES=${SETTLES:-"100 200 400 1000000"}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
mkdir -p "$WORK"
echo "# dv_settle: $(date -u +%Y-%m-%dT%H:%MZ) $(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo '?') np=$NP"
echo "| sensors | seed | --settle-iter | iterations (all phases) | ML cost | excess over the row's lowest | RMSE | wall s |"
echo "|---|---|---|---|---|---|---|---|"
for ns in $NETS; do
  n=${ns%%:*} s=${ns##*:}
  net=$WORK/net_${n}_$s.h5
  [ -f "$net" ] || "$SNL" generate -o "$net" --sensors "$n" --seed "$s" -q
  for S in $SETTLES; do
    mpirun -np "$NP" "$SNL" solve "$net" -o "$WORK/r.h5" -q --settle-iter "$S" --json "$WORK/r_${n}_${s}_$S.json"
  done
  /usr/bin/python3 -c "import h5py,sys; t=h5py.File(sys.argv[1],'r')['truth'][()]; h5py.File(sys.argv[2],'w')['positions']=t" \
    "$net" "$WORK/truth.h5"
  mpirun -np "$NP" "$SNL" solve "$net" -o "$WORK/r.h5" -q --algorithm ml-agd --init "$WORK/truth.h5" \
    --json "$WORK/r_${n}_${s}_truth.json"
  /usr/bin/python3 - "$WORK" "$n" "$s" "$SETTLES" <<'PY'
import json, sys
work, n, s, settles = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4].split()
d = {S: json.load(open(f"{work}/r_{n}_{s}_{S}.json")) for S in settles}
best = min(r["ml_cost"] for r in d.values())
d["ml-agd from the truth"] = json.load(open(f"{work}/r_{n}_{s}_truth.json"))
for S, r in d.items():
    print(f"| {n} | {s} | {S} | {r['iterations']} | {r['ml_cost']:.10g} | {(r['ml_cost'] - best) / best:.1e} | "
          f"{r['rmse']:.6f} | {r['wall_seconds']:.2f} |")
PY
done
