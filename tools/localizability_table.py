#!/usr/bin/python3
"""Markdown tables of docs/generator.md from docs/data/localizability.jsonl
(bench/localizability.sh): the mean fraction of localizable sensors per
(dimension, n, degree), and how many draws were fully localizable.
  tools/localizability_table.py [docs/data/localizability.jsonl]
"""
import collections
import json
import sys


def main():
    path = sys.argv[1] if len(sys.argv) > 1 else "docs/data/localizability.jsonl"
    runs = collections.defaultdict(list)
    for line in open(path):
        r = json.loads(line)
        runs[(r["dim"], r["rigidity"] == "windows" and r["n"] <= 20000, r["n"], r["avg_degree"])].append(r)
    for dim in sorted({k[0] for k in runs}):
        for check in (False, True):
            keys = [k for k in runs if k[0] == dim and k[1] == check]
            if not keys:
                continue
            ns = sorted({k[2] for k in keys})
            degs = sorted({k[3] for k in keys})
            title = f"{dim}D" + (" (windowed rigidity test on the exact test's draws)" if check else "")
            print(f"\n{title}: localizable sensors, mean % over draws [fully localizable draws / draws]; "
                  "rigidity: " + ", ".join(f"n={n}: {runs[next(k for k in keys if k[2] == n)][0]['rigidity']}"
                                           for n in ns) + "\n")
            print("| degree | " + " | ".join(f"n = {n:,}" for n in ns) + " |")
            print("|---" * (len(ns) + 1) + "|")
            for d in degs:
                cells = []
                for n in ns:
                    rs = runs.get((dim, check, n, d))
                    if not rs:
                        cells.append("")
                        continue
                    frac = 100 * sum(r["localizable_fraction"] for r in rs) / len(rs)
                    full = sum(r["not_localizable"] == 0 for r in rs)
                    cells.append(f"{frac:.4f} [{full}/{len(rs)}]")
                print(f"| {d:g} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
