#!/usr/bin/env bash
# Where each stopping rule stops, and how far from the optimum (ML cost, RMSE
# over the localizable sensors): the papers' rule (relative change of x,
# 1e-6) and the gradient rule (relative gradient, 1e-5, the default), each
# with MM and mm-accel as the pipeline's refinement, against a reference run
# (gradient rule at 1e-9, mm-accel, up to 20000 iterations per phase).
# JSON summaries to OUT, a markdown table to OUT/summary.md.
#   bench/stop_rule.sh OUT RANKS NET.h5...
# The issue's network: snl generate -o n1e5.h5 --sensors 100000 --anchors 1000
#   --avg-degree 10 --sigma 0.0003 --seed 1
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=$1 NP=$2; shift 2
SNL=${SNL:-build/bin/snl}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
mkdir -p "$OUT"
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
for net in "$@"; do
  name=$(basename "$net" .h5)
  s() { local tag=$1; shift; mpirun -np "$NP" "$SNL" solve "$net" -o "$T/r.h5" -q --json "$OUT/$name.$tag.json" --algorithm pipeline "$@"; }
  # SKIP: tags already in OUT (a long network's runs can be made one at a time).
  for run in "gradient.mm-accel --stop gradient --refine mm-accel" \
             "reference --stop gradient --refine mm-accel --tol 1e-9 --max-iter 20000" \
             "papers.mm --stop papers --refine mm" "papers.mm-accel --stop papers --refine mm-accel" \
             "gradient.mm --stop gradient --refine mm"; do
    set -- $run; tag=$1; shift
    [ -f "$OUT/$name.$tag.json" ] || s $tag "$@"
  done
done
/usr/bin/python3 - "$OUT" > "$OUT/summary.md" <<'PY'
import glob, json, os, sys
out = sys.argv[1]
print("| network | rule | refinement | iterations | termination | ML cost | (f - f_ref) / f_ref | RMSE (localizable) | RMSE / RMSE_ref | messages/sensor |")
print("|---|---|---|---|---|---|---|---|---|---|")
for ref in sorted(glob.glob(os.path.join(out, "*.reference.json"))):
    name = os.path.basename(ref)[: -len(".reference.json")]
    r = json.load(open(ref))
    for tag in ["papers.mm", "papers.mm-accel", "gradient.mm", "gradient.mm-accel", "reference"]:
        if not os.path.exists(os.path.join(out, f"{name}.{tag}.json")):
            continue
        j = json.load(open(os.path.join(out, f"{name}.{tag}.json")))
        rule, ref_alg = tag.split(".", 1) if tag != "reference" else ("gradient 1e-9", "mm-accel")
        print(f"| {name} | {rule} | {ref_alg} | {j['iterations']} | {j['termination']} | {j['ml_cost']:.8g} | "
              f"{(j['ml_cost'] - r['ml_cost']) / r['ml_cost']:.2e} | {j['rmse_localizable']:.6g} | "
              f"{j['rmse_localizable'] / r['rmse_localizable']:.4f} | {j['communications_per_sensor']:.0f} |")
PY
cat "$OUT/summary.md"
