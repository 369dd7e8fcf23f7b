#!/usr/bin/python3
"""Plots an snl result: estimated vs true positions, and the convergence history.

When the result file holds per-sensor CRLB covariances (group crlb, written by
`snl eval --crlb`), the map also draws each covered sensor's 1-sigma ellipse
(the x-y marginal in 3D) around its true position (around the estimate when
the network has no truth or the covariances were taken at the estimate), and
marks the sensors outside the anchored rigid part with a cross.

Uses Debian's /usr/bin/python3 (python3-h5py, python3-numpy, python3-matplotlib).
  tools/plot_result.py NET.h5 RESULT.h5 -o FIGURE.png [--ellipse-scale K] [--no-ellipses]
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
    ap.add_argument("--ellipse-scale", type=float, default=1.0, help="draw K-sigma ellipses (default 1)")
    ap.add_argument("--no-ellipses", action="store_true", help="ignore the result's crlb group")
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
        crlb = None
        if "crlb" in f and not a.no_ellipses:
            at = f["crlb"].attrs.get("at", "truth")
            crlb = (f["crlb/covariance"][...], f["crlb/covered"][...].astype(bool),
                    at.decode() if isinstance(at, bytes) else str(at))
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
    if crlb is not None:
        draw_ellipses(ax, crlb, truth, x, idx, a.ellipse_scale)
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


def draw_ellipses(ax, crlb, truth, x, idx, k):
    """K-sigma ellipses of the x-y block of each covered sensor's covariance."""
    from matplotlib.collections import EllipseCollection
    cov, covered, at = crlb
    centre = truth if (truth is not None and at == "truth") else x
    sel = idx[covered[idx]]
    if len(sel):
        c2 = cov[sel][:, :2, :2]
        w, v = np.linalg.eigh(c2)  # ascending eigenvalues, columns = axes
        w = np.maximum(w, 0.0)
        major, minor = 2 * k * np.sqrt(w[:, 1]), 2 * k * np.sqrt(w[:, 0])
        angle = np.degrees(np.arctan2(v[:, 1, 1], v[:, 0, 1]))
        ax.add_collection(EllipseCollection(major, minor, angle, units="xy", offsets=centre[sel][:, :2],
                                            offset_transform=ax.transData, facecolors="none",
                                            edgecolors="tab:purple", linewidths=0.8, zorder=5))
        ax.plot([], [], color="tab:purple", lw=0.8, label=f"CRLB {k:g}-sigma ellipse (at the {at})")
    out = idx[~covered[idx]]
    if len(out):
        ax.scatter(centre[out, 0], centre[out, 1], s=40, marker="x", color="tab:orange", zorder=6,
                   label=f"outside the rigid part ({int((~covered).sum())})")


if __name__ == "__main__":
    main()
