#!/usr/bin/python3
"""Figures 6-7 of seed 001 for snl's consensus solvers (docs/consensus.md).

Converts `snl consensus solve` result files (format snl-consensus-result) into
one CSV per method (the history columns), then draws from the CSVs only:

  * PNG 1: (a) absolute error max_p |x_p - x*| and (b) F - F_min, against
    primal iterations: the first-order methods' running averages (what 001
    plots; their iterates dotted) and Newton's iterates.
  * PNG 2: the same against messages per node (what the primal count hides).

With --splitting-rate PROB.h5 ... (family exp) it prints instead, for the
first Newton step from x = 0, the contraction of 001's dual splitting on the
solver's BFS tree: lambda_min of (D + Bbar)^-1 M (M = A H^-1 A^T), the
iteration's rate 1 - lambda_min, and ln(1e12) / lambda_min, the dual iterations
that reduce the dual error 1e12-fold.

Usage:
  plot_consensus.py --splitting-rate PROB.h5 ...
  plot_consensus.py --results newton-tree=R1.h5 ... --csv-dir DIR --prefix fig67 \
                    --png FIG.png --png-messages FIG_MSG.png
  plot_consensus.py --methods newton-tree,... --csv-dir DIR --prefix fig67 --png ...   (CSVs only)
Runs with Debian's /usr/bin/python3 (numpy, h5py, matplotlib).
"""
import argparse
import csv
import os
import sys

import numpy as np

COLUMNS = ["iteration", "dual_iterations", "messages_per_node", "reals_per_node", "F", "F_running_average",
           "max_abs_error", "max_abs_error_running_average"]
STYLE = {"newton-tree": ("C0", "Newton (spanning tree)"), "newton-path": ("C1", "Newton (Hamilton path)"),
         "subgradient": ("C2", "distributed subgradient"), "incremental": ("C3", "incremental"),
         "newton-tree-exact": ("C4", "Newton (spanning tree), exact dual"), "central": ("k", "central Newton")}


def to_csv(result, path):
    import h5py
    with h5py.File(result, "r") as f:
        if f.attrs.get("format") != "snl-consensus-result":
            sys.exit(f"{result}: not an snl-consensus-result file")
        h = f["history"]
        missing = [c for c in COLUMNS if c not in h]
        if missing:
            sys.exit(f"{result}: history lacks {missing}")
        cols = {c: np.asarray(h[c][()]) for c in COLUMNS}
        meta = {k: f.attrs[k] for k in ("method", "dual", "termination", "iterations", "dual_iterations",
                                        "messages_per_node") if k in f.attrs}
    with open(path, "w", newline="") as out:
        out.write("# " + ", ".join(f"{k}={v.decode() if isinstance(v, bytes) else v}" for k, v in meta.items()) + "\n")
        w = csv.writer(out)
        w.writerow(COLUMNS)
        for r in range(len(cols["iteration"])):
            w.writerow([repr(float(cols[c][r])) if cols[c].dtype.kind == "f" else int(cols[c][r]) for c in COLUMNS])


def read_csv(path):
    with open(path) as f:
        rows = [line for line in f if not line.startswith("#")]
    r = csv.DictReader(rows)
    data = {c: [] for c in r.fieldnames}
    for row in r:
        for c in r.fieldnames:
            data[c].append(float(row[c]))
    return {c: np.asarray(v) for c, v in data.items()}


def draw(series, xkey, xlabel, png, title, steps=False):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.6))
    fstar = min(float(np.nanmin(d["F"])) for d in series.values())
    # Against messages, x stays put while a primal iteration spends its
    # messages (Newton: its dual iterations): steps, not straight lines.
    ds = "steps-post" if steps else "default"
    for m, d in series.items():
        color, label = STYLE.get(m, (None, m))
        x = d[xkey] + (1 if xkey == "iteration" else 0)  # log axis: iteration k plotted at k + 1
        # Newton's iterates themselves (the solver keeps no running average of
        # them); the first-order methods' running averages (what 001 plots), and
        # their plain iterates dotted.
        avg = not m.startswith("newton") and not np.all(np.isnan(d["F_running_average"]))
        err = d["max_abs_error_running_average"] if avg else d["max_abs_error"]
        fval = d["F_running_average"] if avg else d["F"]
        tag = ", running average" if avg else ", iterate"
        ax1.plot(x, np.maximum(err, 1e-16), color=color, label=label + tag, drawstyle=ds)
        ax2.plot(x, np.maximum(fval - fstar, 1e-16), color=color, label=label + tag, drawstyle=ds)
        if avg:
            ax1.plot(x, np.maximum(d["max_abs_error"], 1e-16), color=color, ls=":", lw=0.8, label=label + ", iterate",
                     drawstyle=ds)
            ax2.plot(x, np.maximum(d["F"] - fstar, 1e-16), color=color, ls=":", lw=0.8, label=label + ", iterate",
                     drawstyle=ds)
    for ax in (ax1, ax2):
        ax.set_xscale("log", nonpositive="mask")  # no messages yet: not drawn
        ax.set_yscale("log")
        ax.set_xlabel(xlabel)
        ax.grid(True, which="both", alpha=0.3)
    ax1.set_ylabel("absolute error  max_p |x_p - x*|")
    ax2.set_ylabel(f"F - F_min  (F_min = {fstar:.10g})")
    ax1.set_title("(a) absolute error")
    ax2.set_title("(b) objective value")
    ax2.legend(fontsize=7, loc="upper right")
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    print(f"wrote {png}")


def splitting_rate(path):
    """(n, tree depth, lambda_min) of the splitting at x = 0 on the BFS tree
    that newton-tree uses (root 0; parent = smallest-id neighbour one level up)."""
    import h5py
    import scipy.sparse as sp
    import scipy.sparse.linalg as sla
    with h5py.File(path, "r") as f:
        if f.attrs["family"] != "exp":
            sys.exit(f"{path}: --splitting-rate handles family exp only")
        n = int(f.attrs["num_nodes"])
        e = f["edges"][()]
        a, b, c, d = (f[k][()] for k in ("exp_a", "exp_b", "exp_c", "exp_d"))
    G = sp.coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n))
    G = (G + G.T).tocsr()
    G.sort_indices()
    level = np.full(n, -1)
    parent = np.full(n, -1)
    level[0] = 0
    frontier, lev = np.array([0]), 0
    while len(frontier):
        nxt = np.unique(np.concatenate([G.indices[G.indptr[u]:G.indptr[u + 1]] for u in frontier]))
        nxt = nxt[level[nxt] < 0]
        level[nxt] = lev + 1
        for v in nxt:
            nb = G.indices[G.indptr[v]:G.indptr[v + 1]]
            parent[v] = nb[level[nb] == lev].min()
        frontier, lev = nxt, lev + 1
    h = 1.0 / (a * b * b + c * d * d)  # H_p^-1 at x = 0
    kids = np.flatnonzero(parent >= 0)
    m = len(kids)
    rows = np.r_[np.arange(m), np.arange(m)]
    A = sp.coo_matrix((np.r_[np.ones(m), -np.ones(m)], (rows, np.r_[kids, parent[kids]])), shape=(m, n)).tocsr()
    M = (A @ sp.diags(h) @ A.T).tocsr()
    D = M.diagonal()
    Bbar = np.asarray(abs(M - sp.diags(D)).sum(axis=1)).ravel()
    lam = sla.eigsh(M.tocsc(), k=1, M=sp.diags(D + Bbar).tocsc(), sigma=0, which="LM",
                    return_eigenvectors=False)[0]
    return n, int(level.max()), float(lam)


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "--splitting-rate":
        print(f"# {'n':>8} {'depth':>6} {'lambda_min':>11} {'rate':>12} {'iters_1e-12':>12}")
        for path in sys.argv[2:]:
            n, depth, lam = splitting_rate(path)
            print(f"{n:>10} {depth:>6} {lam:>11.4e} {1 - lam:>12.10f} {np.log(1e12) / lam:>12.4g}", flush=True)
        return
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--results", nargs="*", default=[], help="METHOD=RESULT.h5 pairs")
    ap.add_argument("--methods", default="", help="comma-separated methods (with CSVs already in --csv-dir)")
    ap.add_argument("--csv-dir", required=True)
    ap.add_argument("--prefix", default="fig67")
    ap.add_argument("--png", required=True)
    ap.add_argument("--png-messages")
    ap.add_argument("--title", default="001 Figs. 6-7 (reconstruction): 100 nodes, family exp")
    a = ap.parse_args()
    os.makedirs(a.csv_dir, exist_ok=True)
    methods = [m for m in a.methods.split(",") if m]
    for item in a.results:
        m, _, path = item.partition("=")
        if not path:
            sys.exit(f"--results wants METHOD=FILE, got {item!r}")
        csv_path = os.path.join(a.csv_dir, f"{a.prefix}_{m}.csv")
        to_csv(path, csv_path)
        print(f"wrote {csv_path}")
        methods.append(m)
    if not methods:
        sys.exit("nothing to plot: give --results or --methods")
    series = {m: read_csv(os.path.join(a.csv_dir, f"{a.prefix}_{m}.csv")) for m in methods}
    draw(series, "iteration", "primal iteration + 1", a.png, a.title + ": against primal iterations")
    if a.png_messages:
        draw(series, "messages_per_node", "messages per node (cumulative)", a.png_messages,
             a.title + ": against messages per node", steps=True)


if __name__ == "__main__":
    main()
