#!/usr/bin/python3
"""003 Figs. 3 and 4: RMSE against sigma, and RMSE against run time at sigma = 0.1,
for EDM completion, the SDP relaxation, ESDP and the disk relaxation (003 eq. 6,
Algorithm 1 to ||grad f_hat|| <= 1e-6), on one fixed 50-sensor network (the
geometry of inputs/net50_s0.01.h5) with fresh noise (003 eq. 28) each trial.

  /usr/bin/python3 repro/repro_003_fig34.py [SNL] [TRIALS] [NETWORK TAG]
writes docs/data/repro_003_fig34{TAG}.csv and docs/repro_003_fig3{TAG}.png, docs/repro_003_fig4{TAG}.png
(network B: inputs/net50_allanchors_s0.01.h5 _B).
"""
import csv, json, os, subprocess, sys, tempfile
import h5py, numpy as np

SNL = sys.argv[1] if len(sys.argv) > 1 else "build/bin/snl"
TRIALS = int(sys.argv[2]) if len(sys.argv) > 2 else 10
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BASE = os.path.join(ROOT, sys.argv[3]) if len(sys.argv) > 3 else os.path.join(ROOT, "inputs", "net50_s0.01.h5")
TAG = sys.argv[4] if len(sys.argv) > 4 else ""
SIGMAS = [0.01, 0.05, 0.1, 0.3]
METHODS = {
    "edm": ["--algorithm", "edm"],
    "sdp": ["--algorithm", "sdp"],
    "esdp": ["--algorithm", "esdp"],
    "disk": ["--algorithm", "relaxation", "--grad-tol", "1e-6", "--tol", "0", "--max-iter", "200000"],
}


def noisy_copy(src, dst, sigma, seed):
    """The network with every range redrawn as |true distance + sigma N(0,1)| (003 eq. 28)."""
    rng = np.random.default_rng(seed)
    with h5py.File(src, "r") as f, h5py.File(dst, "w") as g:
        for k, v in f.attrs.items():
            g.attrs[k] = v
        for k in f:
            f.copy(k, g)
        x, a = f["truth"][:], f["anchors"][:]
        se, ae = f["sensor_edges"][:], f["anchor_edges"][:]
        d = np.linalg.norm(x[se[:, 0]] - x[se[:, 1]], axis=1)
        r = np.linalg.norm(x[ae[:, 0]] - a[ae[:, 1]], axis=1)
        g["sensor_ranges"][...] = np.abs(d + sigma * rng.standard_normal(d.shape))
        g["anchor_ranges"][...] = np.abs(r + sigma * rng.standard_normal(r.shape))
        if "sigma" in g:
            g["sigma"][...] = sigma


def main():
    out = os.path.join(ROOT, "docs", "data", "repro_003_fig34" + TAG + ".csv")
    rows = []
    with tempfile.TemporaryDirectory() as w:
        for si, sigma in enumerate(SIGMAS):
            for t in range(TRIALS):
                net = os.path.join(w, "net.h5")
                noisy_copy(BASE, net, sigma, 1000 * si + t)
                for name, args in METHODS.items():
                    js = os.path.join(w, "r.json")
                    subprocess.run([SNL, "solve", net, "-o", os.path.join(w, "r.h5"), "--json", js, "-q"] + args,
                                   check=True)
                    j = json.load(open(js))
                    rows.append({"sigma": sigma, "trial": t, "method": name, "rmse": j["rmse"],
                                 "ml_cost": j["ml_cost"], "solve_seconds": j["solve_seconds"],
                                 "iterations": j["iterations"],
                                 "relaxation_objective": j.get("relaxation_objective", j["relaxed_cost"])})
    with open(out, "w", newline="") as f:
        wr = csv.DictWriter(f, fieldnames=list(rows[0]))
        wr.writeheader()
        wr.writerows(rows)
    plot(rows)


def plot(rows):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    # RMSE over trials as 003 eq. (29): sqrt(mean over trials of the squared per-sensor RMSE).
    agg = lambda m, s, key: [r[key] for r in rows if r["method"] == m and r["sigma"] == s]
    fig, ax = plt.subplots(figsize=(5, 3.6))
    for m in METHODS:
        ax.plot(SIGMAS, [np.sqrt(np.mean(np.square(agg(m, s, "rmse")))) for s in SIGMAS], "o-", label=m)
    ax.set_xlabel("sigma"), ax.set_ylabel("RMSE"), ax.legend(), ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(ROOT, "docs", "repro_003_fig3" + TAG + ".png"), dpi=110)
    fig, ax = plt.subplots(figsize=(5, 3.6))
    for m in METHODS:
        ax.plot(agg(m, 0.1, "solve_seconds"), agg(m, 0.1, "rmse"), "o", label=m, alpha=0.7)
    ax.set_xscale("log"), ax.set_xlabel("solve time [s] (shared 2-core machine)"), ax.set_ylabel("RMSE")
    ax.legend(), ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(ROOT, "docs", "repro_003_fig4" + TAG + ".png"), dpi=110)


if __name__ == "__main__":
    main()
