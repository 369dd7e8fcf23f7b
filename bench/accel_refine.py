#!/usr/bin/python3
"""Summary of bench/accel_refine.sh: per network, MM and mm-accel from the same
relaxation output. 'final' is the lower of the two runs' last ML costs; a run
reaches it when its ML cost is within 1e-6 (relative) of it. Writes
OUT/summary.csv and prints a markdown table; 'ms/it. vs MM' is the
refinement's time per iteration over MM's in the same run, and 'load' the
1-minute load average before it (OUT/NAME.ALG.uptime.txt)."""
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
    last = {alg: float(rows[-1]["ml_cost"]) for alg, (_, rows) in runs.items()}
    rj = json.load(open(relax))
    for alg, (j, rows) in runs.items():
        hit = first_within(rows, final)
        own = first_within(rows, float(rows[-1]["ml_cost"]))
        other = first_within(rows, last["mm" if alg == "mm-accel" else "mm-accel"])
        its = j["iterations"]
        up = os.path.join(out, f"{name}.{alg}.uptime.txt")
        load = open(up).read().split("load average:")[1].split(",")[0].strip() if os.path.exists(up) else ""
        table.append({
            "network": name, "sensors": j["num_sensors"], "method": alg, "ranks": j["ranks"],
            "relaxation_iterations": rj["iterations"], "iterations_run": its,
            "final_ml_cost": rows[-1]["ml_cost"], "best_final_ml_cost": repr(final),
            "comms_to_best_1e-6": hit["communications"] if hit else "",
            "comms_to_own_final_1e-6": own["communications"] if own else "",
            "comms_to_other_final_1e-6": other["communications"] if other else "",
            "final_rmse": rows[-1]["rmse"],
            "ms_per_iteration": repr(1e3 * j["iterate_seconds"] / its) if its else "",
            "load_average_1min": load,
        })
    mm_ms = float(table[-2]["ms_per_iteration"])
    for t in table[-2:]:
        t["ms_per_iteration_vs_mm"] = repr(float(t["ms_per_iteration"]) / mm_ms)
with open(os.path.join(out, "summary.csv"), "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=list(table[0].keys()))
    w.writeheader()
    w.writerows(table)
print("| network | n | method | ranks | relaxation it. | refinement it. run | final ML cost | "
      "messages/sensor to within 1e-6 of the better final cost | to within 1e-6 of its own | final RMSE | ms/iteration | "
      "ms/it. vs MM | load |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
for t in table:
    c = t["comms_to_best_1e-6"]
    print(f"| {t['network']} | {t['sensors']} | {t['method']} | {t['ranks']} | {t['relaxation_iterations']} | "
          f"{t['iterations_run']} | {float(t['final_ml_cost']):.10g} | "
          f"{int(float(c)) if c else 'not reached'} | {int(float(t['comms_to_own_final_1e-6']))} | "
          f"{float(t['final_rmse']):.5g} | {float(t['ms_per_iteration']):.3g} | "
          f"{float(t['ms_per_iteration_vs_mm']):.2f} | {t['load_average_1min'] or '-'} |")
