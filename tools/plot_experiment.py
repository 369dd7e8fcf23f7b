#!/usr/bin/python3
"""Plots an `snl experiment` trajectory CSV: mean ML cost over the trials versus
communications (reals per sensor), one panel per sigma, one curve per method.

Uses Debian's /usr/bin/python3 (python3-numpy, python3-matplotlib).
  tools/plot_experiment.py TRAJECTORY.csv -o FIGURE.png [--title TEXT]
"""
import argparse
import csv
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("trajectory")
    ap.add_argument("-o", "--output", required=True)
    ap.add_argument("--title", default="")
    a = ap.parse_args()
    # (sigma, algorithm) -> reals -> list of ML costs (one per trial)
    data = defaultdict(lambda: defaultdict(list))
    with open(a.trajectory) as f:
        for r in csv.DictReader(f):
            data[(float(r["sigma"]), r["algorithm"])][float(r["reals_per_sensor"])].append(float(r["ml_cost"]))
    sigmas = sorted({k[0] for k in data})
    fig, axes = plt.subplots(1, len(sigmas), figsize=(5 * len(sigmas), 4), squeeze=False)
    for ax, s in zip(axes[0], sigmas):
        for (sig, alg), series in sorted(data.items()):
            if sig != s:
                continue
            xs = np.array(sorted(series))
            ys = np.array([np.mean(series[x]) for x in xs])
            ax.loglog(np.maximum(xs, 1), ys, label=alg.upper() if alg != "relaxation" else alg)
        ax.set_title(f"sigma = {s}", fontsize=10)
        ax.set_xlabel("communications (reals per sensor)")
        ax.set_ylabel("mean ML cost f")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
    if a.title:
        fig.suptitle(a.title, fontsize=10)
    fig.tight_layout()
    fig.savefig(a.output, dpi=110)
    print(f"wrote {a.output}")


if __name__ == "__main__":
    main()
