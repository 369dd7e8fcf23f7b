#!/usr/bin/python3
"""Summary of bench/accel_refine.sh: per network, MM and mm-accel from the same
relaxation output. 'final' is the lower of the two runs' last ML costs; a run
reaches it when its ML cost is within 1e-6 (relative) of it. Writes
OUT/summary.csv and prints a markdown table."""
import csv, glob, json, os, sys

out = sys.argv[1]
REL = 1e-6


def first_within(rows, target):
    for r in rows:
        if float(r["ml_cost"]) <= target * (1 + REL):
            return r
    return None


lines, table = [], []
for relax in sorted(glob.glob(os.path.join(out, "*.relax.json"))):
    name = os.path.basename(relax)[: -len(".relax.json")]
    runs = {}
    for alg in ("mm", "mm-accel"):
        j = json.load(open(os.path.join(out, f"{name}.{alg}.json")))
        rows = list(csv.DictReader(open(os.path.join(out, f"{name}.{alg}.history.csv"))))
        runs[alg] = (j, rows)
    final = min(float(rows[-1]["ml_cost"]) for _, rows in runs.values())
    rj = json.load(open(relax))
    for alg, (j, rows) in runs.items():
        hit = first_within(rows, final)
        own = first_within(rows, float(rows[-1]["ml_cost"]))
        its = j["iterations"]
        table.append({
            "network": name, "sensors": j["num_sensors"], "method": alg, "ranks": j["ranks"],
            "relaxation_iterations": rj["iterations"], "iterations_run": its,
            "final_ml_cost": rows[-1]["ml_cost"], "best_final_ml_cost": repr(final),
            "comms_to_best_1e-6": hit["communications"] if hit else "",
            "comms_to_own_final_1e-6": own["communications"] if own else "",
            "final_rmse": rows[-1]["rmse"],
            "ms_per_iteration": repr(1e3 * j["iterate_seconds"] / its) if its else "",
        })
with open(os.path.join(out, "summary.csv"), "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=list(table[0].keys()))
    w.writeheader()
    w.writerows(table)
print("| network | n | method | ranks | relaxation it. | refinement it. run | final ML cost | "
      "messages/sensor to within 1e-6 of the better final cost | to within 1e-6 of its own | final RMSE | ms/iteration |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
for t in table:
    c = t["comms_to_best_1e-6"]
    print(f"| {t['network']} | {t['sensors']} | {t['method']} | {t['ranks']} | {t['relaxation_iterations']} | "
          f"{t['iterations_run']} | {float(t['final_ml_cost']):.10g} | "
          f"{int(float(c)) if c else 'not reached'} | {int(float(t['comms_to_own_final_1e-6']))} | "
          f"{float(t['final_rmse']):.5g} | {float(t['ms_per_iteration']):.3g} |")
