#!/usr/bin/python3
"""000 Figs. 1-3 (a): mean positioning error per sensor against communications
(reals per sensor), one panel per sigma, one curve per method, from an
`snl experiment` trajectory CSV.   plot_mpe_vs_comm.py TRAJECTORY.csv OUT.png"""
import csv, sys
from collections import defaultdict
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

data = defaultdict(lambda: defaultdict(list))
with open(sys.argv[1]) as f:
    for r in csv.DictReader(f):
        data[(float(r["sigma"]), r["algorithm"])][float(r["reals_per_sensor"])].append(float(r["mpe"]))
sigmas = sorted({k[0] for k in data})
fig, axs = plt.subplots(1, len(sigmas), figsize=(4.2 * len(sigmas), 3.4), squeeze=False)
for ax, s in zip(axs[0], sigmas):
    for (s2, alg), byx in sorted(data.items()):
        if s2 != s:
            continue
        xs = sorted(byx)
        ax.plot(xs, [np.mean(byx[x]) for x in xs], label=alg)
    ax.set_title(f"sigma = {s}"), ax.set_xlabel("reals per sensor"), ax.set_ylabel("MPE per sensor")
    ax.grid(alpha=0.3), ax.legend()
fig.tight_layout()
fig.savefig(sys.argv[2], dpi=100)
