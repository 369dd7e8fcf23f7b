#!/usr/bin/python3
"""Plots an snl result: estimated vs true positions, and the convergence history.

Uses Debian's /usr/bin/python3 (python3-h5py, python3-numpy, python3-matplotlib).
  tools/plot_result.py NET.h5 RESULT.h5 -o FIGURE.png
"""
import argparse

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

PHASES = {0: "relaxation", 1: "mm", 2: "bb"}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("network")
    ap.add_argument("result")
    ap.add_argument("-o", "--output", required=True)
    ap.add_argument("--max-points", type=int, default=20000, help="subsample larger networks for the map")
    a = ap.parse_args()
    with h5py.File(a.network, "r") as f:
        anchors = f["anchors"][...]
        truth = f["truth"][...] if "truth" in f else None
        edges = f["sensor_edges"][...]
    with h5py.File(a.result, "r") as f:
        x = f["positions"][...]
        alg = f.attrs["algorithm"]
        alg = alg.decode() if isinstance(alg, bytes) else str(alg)
        hist = {k: f["history"][k][...] for k in f["history"]} if "history" in f else {}
    n, p = x.shape
    fig, axes = plt.subplots(1, 2, figsize=(13, 6))
    ax = axes[0]
    idx = np.arange(n)
    if n > a.max_points:
        idx = np.random.default_rng(0).choice(n, a.max_points, replace=False)
    if n <= 2000:
        for i, j in edges:
            ax.plot(x[[i, j], 0], x[[i, j], 1], color="0.85", lw=0.5, zorder=0)
    if truth is not None:
        for i in idx:
            ax.plot([truth[i, 0], x[i, 0]], [truth[i, 1], x[i, 1]], color="tab:red", lw=0.8, zorder=1)
        ax.scatter(truth[idx, 0], truth[idx, 1], s=14, facecolors="none", edgecolors="k", label="true position", zorder=2)
    ax.scatter(x[idx, 0], x[idx, 1], s=10, color="tab:blue", label="estimate", zorder=3)
    ax.scatter(anchors[:, 0], anchors[:, 1], s=80, marker="s", color="tab:green", label="anchor", zorder=4)
    ax.set_aspect("equal")
    title = f"{a.result}: {alg}, n={n}"
    if truth is not None:
        rmse = np.sqrt(np.mean(np.sum((x - truth) ** 2, axis=1)))
        title += f", RMSE={rmse:.4g}"
    ax.set_title(title, fontsize=9)
    ax.legend(loc="upper right", fontsize=8)
    ax = axes[1]
    if hist:
        comm = hist.get("communications", hist.get("iteration"))
        phase = hist.get("phase", np.zeros_like(comm))
        for code in np.unique(phase):
            sel = phase == code
            ax.semilogy(comm[sel], hist["ml_cost"][sel], label=f"ML cost f ({PHASES.get(int(code), '?')})")
            ax.semilogy(comm[sel], np.maximum(hist["cost"][sel], 1e-300), "--",
                        label=f"objective of {PHASES.get(int(code), '?')}")
        if "rmse" in hist:
            ax2 = ax.twinx()
            ax2.plot(comm, hist["rmse"], color="tab:gray", lw=1, label="RMSE")
            ax2.set_ylabel("RMSE")
            ax2.legend(loc="center right", fontsize=8)
        ax.set_xlabel("communications per sensor")
        ax.set_ylabel("cost")
        ax.legend(loc="upper right", fontsize=8)
        ax.set_title("convergence", fontsize=9)
    fig.tight_layout()
    fig.savefig(a.output, dpi=110)
    print(f"wrote {a.output}")


if __name__ == "__main__":
    main()
