#!/usr/bin/python3
"""Prints every number that docs/results.md and docs/experiments.md
derive from their kept tables (ratios, ranges, counts), so each
such number comes from a file in docs/data/ and this command.

Usage: /usr/bin/python3 tools/doc_claims.py [--trajectories TRAJ_A.csv TRAJ_B.csv]
  --trajectories: the trajectory CSVs of the two Table I experiments
  (docs/experiments.md gives the commands; too large to keep) for the
  monotonicity counts.
"""
import collections
import csv
import math
import os
import sys

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "docs", "data")


def md_rows(name):
    """Rows of a markdown table file (header row first), cells stripped."""
    rows = []
    for line in open(os.path.join(DATA, name)):
        if line.startswith("|") and not line.startswith("|---"):
            rows.append([c.strip() for c in line.strip().strip("|").split("|")])
    return rows


def results_md():
    print("== docs/results.md (docs/data/examples_table.md, docs/data/benchmarks_table.md)")
    for r in md_rows("examples_table.md"):
        if r[0] == "network":
            continue
        net, gap, apriori, rmse, crlb = r[0], float(r[4]), float(r[5]), float(r[6]), float(r[8])
        print(f"  {net}: a-priori / certificate = {apriori / gap:.1f}, RMSE / CRLB RMSE = {rmse / crlb:.3f}")
    rows = [r for r in md_rows("benchmarks_table.md") if r[0] != "network"]
    for net in ("test10-500", "test20-1000"):
        rel = next(r for r in rows if r[0] == net and r[1].startswith("relaxation"))
        pipe = next(r for r in rows if r[0] == net and r[1].startswith("pipeline"))
        print(f"  {net}: RMSE relaxation / pipeline = {float(rel[8]) / float(pipe[8]):.2f}, "
              f"a-priori / certificate = {float(rel[7]) / float(rel[6]):.1f}")


def groups(name):
    g = collections.defaultdict(list)
    for r in csv.DictReader(open(os.path.join(DATA, name))):
        g[(float(r["sigma"]), r["algorithm"])].append(r)
    return g


def experiments_md(traj):
    print("== docs/experiments.md (docs/data/table1_*.csv, table1_*.txt, fig5_*.csv, fig7_*.csv)")
    paper = {0.01: (0.0053, 0.0059, 1.5698e-4), 0.05: (0.0143, 0.0154, 0.0031), 0.10: (0.0210, 0.0221, 0.0096)}
    tables = {"A": "table1_net50.csv", "B": "table1_net50_allanchors.csv"}
    stats = {}
    for net, f in tables.items():
        g = groups(f)
        mm = g_above = 0
        for (sigma, alg), rs in sorted(g.items()):
            mean = lambda c: sum(float(r[c]) for r in rs) / len(rs)
            stats[(net, sigma, alg)] = (mean("mpe"), mean("ml_cost") / 50)
            if alg == "mm":
                mm += len(rs)
                g_above += sum(float(r["ml_cost"]) > float(r["ml_cost_start"]) for r in rs)
        print(f"  {net}: MM runs {mm}, final ML cost above the start in {g_above}")
    for sigma, (p_mm, p_bb, p_cost) in paper.items():
        a_mm, a_cost = stats[("A", sigma, "mm")]
        b_mm, b_cost = stats[("B", sigma, "mm")]
        b_bb = stats[("B", sigma, "bb")][0]
        print(f"  sigma {sigma}: MPE A MM / paper MM = {a_mm / p_mm:.1f}; B MM {b_mm:.5f} vs BB {b_bb:.5f}; "
              f"paper cost/sensor {p_cost:.4g} between A {a_cost:.4g} and B {b_cost:.4g}: "
              f"{min(a_cost, b_cost) <= p_cost <= max(a_cost, b_cost)}")
    # Communications to converge: the aggregate tables' last column.
    for net, f in (("A", "table1_net50.txt"), ("B", "table1_all.txt")):
        reach = {}
        for line in open(os.path.join(DATA, f)):
            w = line.split()
            if len(w) > 8 and w[1] in ("mm", "bb") and "reached" in line:
                reach[(w[0], w[1])] = float(w[8])
        for sigma in ("0.01", "0.05", "0.1"):
            print(f"  {net} sigma {sigma}: reals to reach, MM / BB = {reach[(sigma, 'mm')] / reach[(sigma, 'bb')]:.2f}")
    for net, f in (("B", "fig7_async_B.csv"), ("A", "fig7_async_A.csv")):
        g = groups(f)
        for sigma in (0.01, 0.05, 0.1):
            c = {alg: sum(float(r["ml_cost"]) for r in g[(sigma, alg)]) / len(g[(sigma, alg)])
                 for alg in ("relaxation", "async-exact")}
            print(f"  fig7 {net} sigma {sigma}: (exact async - Alg. 1) / Alg. 1 ML cost = "
                  f"{(c['async-exact'] - c['relaxation']) / c['relaxation']:+.3f}")
    if traj:
        for net, f in zip(("A", "B"), traj):
            trajectory_counts(net, f)


def trajectory_counts(net, path):
    """Runs whose recorded ML cost rises somewhere along the trajectory (strictly,
    and by more than a relative 1e-9 and 1e-6), and the largest spike over the
    run's final cost, per sigma."""
    seq = collections.defaultdict(list)
    with open(path) as fh:
        for r in csv.DictReader(fh):
            seq[(r["sigma"], r["trial"], r["algorithm"])].append(float(r["ml_cost"]))
    for alg in ("mm", "bb"):
        runs = {k: v for k, v in seq.items() if k[2] == alg}
        counts = [sum(any(b > a * (1 + thr) for a, b in zip(v, v[1:])) for v in runs.values())
                  for thr in (0.0, 1e-9, 1e-6)]
        print(f"  {net} trajectories: {alg} cost rises in {counts[0]} / {counts[1]} / {counts[2]} of {len(runs)} runs "
              f"(strictly / by > 1e-9 relative / by > 1e-6)")
        for sigma in sorted({k[0] for k in runs}, key=float):
            spike = max(max(v) / v[-1] for k, v in runs.items() if k[0] == sigma)
            print(f"    sigma {sigma}: largest recorded cost / final cost of a run = {spike:.3g}")


def main(argv):
    traj = argv[argv.index("--trajectories") + 1:][:2] if "--trajectories" in argv else None
    results_md()
    experiments_md(traj)


if __name__ == "__main__":
    main(sys.argv[1:])
