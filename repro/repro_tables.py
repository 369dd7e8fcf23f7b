#!/usr/bin/python3
"""Prints the tables of docs/reproduction.md from the raw files in docs/data/.
  /usr/bin/python3 repro/repro_tables.py"""
import csv, os
from collections import defaultdict
import numpy as np

D = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "docs", "data")


def table000(name, n=50):
    p = os.path.join(D, name)
    if not os.path.exists(p):
        return
    g = defaultdict(list)
    for r in csv.DictReader(open(p)):
        g[(float(r["sigma"]), r["algorithm"])].append(r)
    paper = {0.01: (0.0053, 0.0059), 0.05: (0.0143, 0.0154), 0.1: (0.0210, 0.0221)}
    print(f"\n{name}: MPE per sensor (mean over trials) / mean ML cost per sensor")
    print("| sigma | paper: MM | paper: BB | MM | bb (ML-cost variant) | bb-calafiore | relaxation (start) |")
    print("|---|---|---|---|---|---|---|")
    for s in sorted({k[0] for k in g}):
        cell = lambda a: "%.4f / %.5f" % (np.mean([float(r["mpe"]) for r in g[(s, a)]]),
                                          np.mean([float(r["ml_cost"]) for r in g[(s, a)]]) / n)
        print(f"| {s} | {paper[s][0]} | {paper[s][1]} | {cell('mm')} | {cell('bb')} | {cell('bb-calafiore')} | {cell('relaxation')} |")


def fig34():
    p = os.path.join(D, "repro_003_fig34.csv")
    if not os.path.exists(p):
        return
    g = defaultdict(list)
    for r in csv.DictReader(open(p)):
        g[(float(r["sigma"]), r["method"])].append(r)
    methods = ["edm", "sdp", "esdp", "disk"]
    print("\n003 Fig. 3: RMSE (003 eq. 29 over the trials) / median solve seconds")
    print("| sigma | " + " | ".join(methods) + " |")
    print("|---|" + "---|" * len(methods))
    for s in sorted({k[0] for k in g}):
        cells = []
        for m in methods:
            rs = g[(s, m)]
            rmse = np.sqrt(np.mean([float(r["rmse"]) ** 2 for r in rs]))
            cells.append("%.4f / %.3g s" % (rmse, np.median([float(r["solve_seconds"]) for r in rs])))
        print(f"| {s} | " + " | ".join(cells) + " |")


table000("repro_000_table1.csv")
table000("repro_000_table1_B.csv")
fig34()


def backends():
    p = os.path.join(D, "sdp_backends.csv")
    if not os.path.exists(p):
        return
    t = defaultdict(dict)
    for r in csv.DictReader(open(p)):
        t[(int(r["sensors"]), r["relaxation"])][r["solver"]] = (r["seconds"], r["objective_or_status"])
    print("\nSDP solvers: CPU seconds (status)")
    print("| sensors | relaxation | DSDP in snl | DSDP executable | CSDP executable |")
    print("|---|---|---|---|---|")
    for k in sorted(t):
        c = lambda s: "%s (%s)" % t[k][s] if s in t[k] else "-"
        print(f"| {k[0]} | {k[1]} | {c('dsdp-in-snl')} | {c('dsdp5-exe')} | {c('csdp-exe')} |")


backends()
