"""003 Table I / Fig. 2 from the per-trial files of bench/repro_003_table1.sh.

usage: repro_003_table1.py WORKDIR TRIALS CSV TXT PNG
"""
import json
import sys

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

CENTER, ANCHORS, SIGMA = 3.0, np.array([2.0, 4.0, 5.0]), 0.25
PAPER = {"true_gap": 0.0367, "gap_certificate": 0.0487, "apriori_bound": 3.0871}


def costs(x, r):
    """f and f_hat of the star on the grid x (003 eqs. 2 and 6)."""
    z = np.abs(x[:, None] - ANCHORS[None, :])
    return 0.5 * ((z - r) ** 2).sum(1), 0.5 * (np.maximum(z - r, 0) ** 2).sum(1)


def main(work, trials, csv, txt, png):
    rows = []
    for t in range(1, trials + 1):
        e = json.load(open(f"{work}/eval_{t}.json"))
        with h5py.File(f"{work}/res_{t}.h5", "r") as res, h5py.File(f"{work}/net_{t}.h5", "r") as net:
            xs = [float(res["positions"][0, 0]), *map(float, net["anchor_ranges"][:])]
        rows.append([t, e["global_ml_optimum"], e["relaxed_cost"], e["true_gap"], e["gap_certificate"],
                     e["apriori_bound"], e["ml_cost"], xs[0], *xs[1:]])
    a = np.array(rows)
    hdr = "trial,f_star,f_hat,true_gap,gap_certificate,apriori_bound,f_at_x_hat,x_hat,r1,r2,r3"
    np.savetxt(csv, a, delimiter=",", header=hdr, comments="", fmt="%.17g")
    m, s = a.mean(0), a.std(0, ddof=1) / np.sqrt(len(a))
    with open(txt, "w") as f:
        f.write(f"003 Table I: 1-D star (sensor at {CENTER}, anchors at {list(ANCHORS)}), sigma {SIGMA}, {trials} trials\n")
        f.write("quantity          ours (mean +- std. error)   paper\n")
        for name, col in (("true_gap", 3), ("gap_certificate", 4), ("apriori_bound", 5)):
            f.write(f"{name:<17} {m[col]:.4f} +- {s[col]:.4f}            {PAPER[name]}\n")
        f.write(f"trials with f_hat* > 0 (disks do not meet): {int((a[:, 2] > 0).sum())}\n")
        f.write(f"trials where the certificate exceeds the true gap by > 1e-9: {int((a[:, 4] - a[:, 3] > 1e-9).sum())}\n")
        f.write(f"max of true_gap - certificate (must be <= 0 up to rounding): {(a[:, 3] - a[:, 4]).max():.3g}\n")
    print(open(txt).read(), end="")
    fig, ax = plt.subplots(1, 2, figsize=(11, 4))
    x = np.linspace(0, 7, 1401)
    r = a[0, 8:11]
    f, fh = costs(x, r)
    ax[0].plot(x, f, "--", label="f(x), ML cost (eq. 2)")
    ax[0].plot(x, fh, ":", lw=2, label=r"$\hat f(x)$, disk relaxation (eq. 6)")
    ax[0].plot(ANCHORS, 0 * ANCHORS, "ks", label="anchors")
    ax[0].axvline(CENTER, color="gray", lw=0.8, label="true sensor position")
    ax[0].set(xlabel="x", ylabel="cost", title=f"Fig. 2: star, trial 1 (ranges {np.round(r, 3).tolist()})", ylim=(0, 6))
    ax[0].legend(fontsize=8)
    ax[1].hist([a[:, 3], a[:, 4]], bins=40, label=[r"true gap $f^*-\hat f^*$", "certificate (eq. 22)"])
    ax[1].set(xlabel="value", ylabel="trials", title=f"Table I: {trials} trials, sigma {SIGMA}")
    ax[1].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(png, dpi=110)


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4], sys.argv[5])
