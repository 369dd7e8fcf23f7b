"""003 Fig. 6 / Table II from repro/repro_003_fig6.sh's per-trial CSV: per sigma and
method the RMSE (003 eq. 29 over the trials), the mean communications per sensor
(messages) and iterations, the mean final ML cost, and for esdp-dist the relative
distance of its ESDP objective from the centralized ESDP's of the same trial.
With a third argument (the run at the Table II counts, a fixed number of
iterations) its table too.
Usage: /usr/bin/python3 repro/repro_003_fig6.py TRIALS.csv OUT.png [FIXED.csv]"""
import collections
import csv
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

rows = list(csv.DictReader(open(sys.argv[1])))
by = collections.defaultdict(list)
for r in rows:
    by[(float(r["sigma"]), r["algorithm"])].append(r)
sigmas = sorted({k[0] for k in by})
methods = ["relaxation", "esdp-dist"]
label = {"relaxation": "Algorithm 1", "esdp-dist": "distributed ESDP", "esdp": "centralized ESDP (DSDP)"}


def mean(v):
    return sum(v) / len(v)


def stats(rs):
    return {
        "trials": len(rs),
        "rmse": math.sqrt(mean([float(r["rmse"]) ** 2 for r in rs])),
        "messages": mean([float(r["messages_per_sensor"]) for r in rs]),
        "iterations": mean([float(r["iterations"]) for r in rs]),
        "ml": mean([float(r["ml_cost"]) for r in rs]),
    }


print("| sigma | method | trials | RMSE | communications per sensor (mean) | iterations (mean) | mean ML cost |")
print("|---|---|---|---|---|---|---|")
S = {}
for s in sigmas:
    for m in methods:
        st = S[(s, m)] = stats(by[(s, m)])
        print(f"| {s:g} | {label[m]} | {st['trials']} | {st['rmse']:.4f} | {st['messages']:.0f} | "
              f"{st['iterations']:.0f} | {st['ml']:.5f} |")
conv = sum(int(r["iterations"]) < 200000 for r in rows if r["algorithm"] == "esdp-dist")
print(f"\nesdp-dist runs stopped by the rule (not the budget): {conv} of "
      f"{sum(r['algorithm'] == 'esdp-dist' for r in rows)}")

if len(sys.argv) > 3:
    fx = collections.defaultdict(list)
    for r in csv.DictReader(open(sys.argv[3])):
        fx[(float(r["sigma"]), r["algorithm"])].append(r)
    print("\nAt 003's Table II counts (fixed iterations):\n")
    print("| sigma | method | trials | RMSE | communications per sensor | mean ML cost |")
    print("|---|---|---|---|---|---|")
    for s in sigmas:
        for m in ("relaxation", "esdp-dist"):
            st = stats(fx[(s, m)])
            print(f"| {s:g} | {label[m]} | {st['trials']} | {st['rmse']:.4f} | {st['messages']:.0f} | {st['ml']:.5f} |")

fig, ax = plt.subplots(1, 2, figsize=(10, 4))
for m, mk in zip(methods, "os^"):
    ax[0].plot(sigmas, [S[(s, m)]["rmse"] for s in sigmas], marker=mk, label=label[m])
    ax[1].plot(sigmas, [S[(s, m)]["messages"] for s in sigmas], marker=mk, label=label[m])
ax[0].set_xlabel("sigma")
ax[0].set_ylabel("RMSE (003 eq. 29)")
ax[0].set_title("003 Fig. 6: network 1 (10 sensors)")
ax[1].set_xlabel("sigma")
ax[1].set_ylabel("communications per sensor")
ax[1].set_yscale("log")
ax[1].set_title("Table II: to relative improvement 1e-6")
for a in ax:
    a.grid(True, alpha=0.3)
    a.legend()
fig.tight_layout()
fig.savefig(sys.argv[2], dpi=100)
