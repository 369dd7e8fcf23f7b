"""Markdown tables of bench/quality_weights.sh's CSV files (docs/quality.md).
    /usr/bin/python3 bench/quality_tables.py docs/data/quality
"""
import csv
import sys
from collections import defaultdict

out = sys.argv[1]
rows = list(csv.DictReader(open(f"{out}/benchmarks.csv")))
print("| network | run | iterations (all phases) | termination | ML cost (the run's weights) | RMSE | RMSE (localizable) | weighted CRLB (localizable) | RMSE / CRLB |")
print("|---|---|---|---|---|---|---|---|---|")
for r in rows:
    rl, c = float(r["rmse_localizable"]), float(r["crlb_rmse_localizable"])
    print(f"| {r['network']} | {r['run']} | {r['iterations']} | {r['termination']} | {float(r['ml_cost']):.6g} | "
          f"{float(r['rmse']):.5f} | {rl:.5f} | {c:.5f} ({r['localizable']} sensors) | {rl / c:.2f} |")
print()
rows = list(csv.DictReader(open(f"{out}/nlos.csv")))
acc = defaultdict(list)
for r in rows:
    acc[(float(r["nlos_fraction"]), r["loss"])].append(float(r["rmse_localizable"]))
trials = len({r["seed"] for r in rows})
base = sum(acc[(0.0, "l2")]) / len(acc[(0.0, "l2")])
losses = sorted({k[1] for k in acc}, key=lambda s: (s != "l2", s))
print(f"| NLOS fraction | " + " | ".join(f"RMSE {l} (mean of {trials})" for l in losses) +
      " | " + " | ".join(f"{l} / outlier-free l2" for l in losses) + " |")
print("|---|" + "---|" * (2 * len(losses)))
for f in sorted({k[0] for k in acc}):
    m = [sum(acc[(f, l)]) / len(acc[(f, l)]) for l in losses]
    print(f"| {f:.0%} | " + " | ".join(f"{v:.5f}" for v in m) + " | " + " | ".join(f"{v / base:.2f}" for v in m) + " |")
