#!/usr/bin/env bash
# dv-pipeline (the default) against the papers' pipeline (relaxation, then
# 000's MM, 003's stopping rule) on small networks in the papers' setting:
# N sensors in the unit square, the 4 corner anchors, average degree DEG,
# sigma in SIGMAS, seeds 1..SEEDS. Prints one row per network (final ML costs,
# RMSE) and the counts of lower, equal (within 1e-9 relative) and higher.
#   N=50 DEG=6.1 SEEDS=20 bench/dv_vs_papers.sh > docs/data/quality/dv_vs_papers.txt
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
SNL=${SNL:-$ROOT/build/bin/snl}
N=${N:-50} DEG=${DEG:-6.1} SEEDS=${SEEDS:-20} SIGMAS=${SIGMAS:-"0.01 0.05 0.1"}
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
echo "# dv_vs_papers: $(date -u +%Y-%m-%dT%H:%MZ) $(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo '?') N=$N DEG=$DEG"
echo "sigma,seed,dv_ml_cost,papers_ml_cost,dv_rmse,papers_rmse"
for s in $SIGMAS; do
  for seed in $(seq 1 "$SEEDS"); do
    "$SNL" generate -o "$T/n.h5" --sensors "$N" --avg-degree "$DEG" --anchors corners --sigma "$s" --seed "$seed" -q
    "$SNL" solve "$T/n.h5" -o "$T/a.h5" -q --json "$T/a.json" --max-iter 30000
    "$SNL" solve "$T/n.h5" -o "$T/b.h5" -q --json "$T/b.json" --max-iter 30000 --algorithm pipeline --refine mm --stop papers
    /usr/bin/python3 -c "import json,sys; a=json.load(open(sys.argv[1])); b=json.load(open(sys.argv[2])); print(f\"$s,$seed,{a['ml_cost']:.10g},{b['ml_cost']:.10g},{a['rmse']:.6g},{b['rmse']:.6g}\")" "$T/a.json" "$T/b.json"
  done
done | tee "$T/rows.csv"
/usr/bin/python3 - "$T/rows.csv" <<'PY'
import csv, sys
rows = list(csv.reader(open(sys.argv[1])))
by = {}
for s, seed, a, b, ra, rb in rows:
    a, b = float(a), float(b)
    k = "lower" if a < b * (1 - 1e-9) else "higher" if a > b * (1 + 1e-9) else "equal"
    by.setdefault(s, {"lower": 0, "equal": 0, "higher": 0})[k] += 1
for s, c in by.items():
    print(f"# sigma {s}: dv-pipeline lower {c['lower']}, equal {c['equal']}, higher {c['higher']} (of {sum(c.values())})")
PY
