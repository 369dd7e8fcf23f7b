"""003 Fig. 7 in f_hat: per network, sigma and method the mean final f_hat (003 eq. 6,
the disk relaxation's cost, the paper's measure) over the trials, with the mean
ML cost beside it, from the per-trial CSVs of repro/repro_003_fig7.sh.
Usage: /usr/bin/python3 repro/repro_003_fig7.py A.csv B.csv OUT.png"""
import collections
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

label = {"relaxation": "Algorithm 1 (parallel)", "async-exact": "Algorithm 2, exact update",
         "async": "Algorithm 2, inexact update (eq. 20)"}
fig, axes = plt.subplots(1, 2, figsize=(10, 4))
print("| network | sigma | Alg. 1: f_hat / ML cost | Alg. 2 exact: f_hat / ML cost | Alg. 2 inexact: f_hat / ML cost "
      "| f_hat: (Alg. 2 exact - Alg. 1) / Alg. 1 |")
print("|---|---|---|---|---|---|")
for ax, (net, path) in zip(axes, (("A", sys.argv[1]), ("B", sys.argv[2]))):
    by = collections.defaultdict(list)
    for r in csv.DictReader(open(path)):
        by[(float(r["sigma"]), r["algorithm"])].append(r)
    sigmas = sorted({k[0] for k in by})
    mean = {k: (sum(float(r["fhat"]) for r in v) / len(v), sum(float(r["ml_cost"]) for r in v) / len(v))
            for k, v in by.items()}
    for s in sigmas:
        cells = " | ".join(f"{mean[(s, m)][0]:.4g} / {mean[(s, m)][1]:.4f}" for m in ("relaxation", "async-exact", "async"))
        gap = (mean[(s, "async-exact")][0] - mean[(s, "relaxation")][0]) / mean[(s, "relaxation")][0]
        print(f"| {net} | {s:g} | {cells} | {gap:+.2e} |")
    for m, mk in zip(("relaxation", "async-exact", "async"), "os^"):
        ax.plot(sigmas, [mean[(s, m)][0] for s in sigmas], marker=mk, label=label[m])
    ax.set_xlabel("sigma")
    ax.set_ylabel("mean final f_hat (003 eq. 6)")
    ax.set_yscale("log")
    ax.set_title(f"003 Fig. 7, network {net}: 400 reals per sensor")
    ax.grid(True, alpha=0.3)
    ax.legend()
fig.tight_layout()
fig.savefig(sys.argv[3], dpi=100)
