#!/usr/bin/python3
"""Markdown rows of docs/performance.md's "Parallel setup" tables from
bench/setup_scaling.sh records: ranks, partition, setup s, merge, partition,
graph, peak RSS per rank (MiB), max / mean, edge cut, ghosts, positions equal
to the METIS run on the first rank count. One table per network size.
    /usr/bin/python3 bench/setup_scaling_rows.py W/records.jsonl"""
import json
import sys

rows = [json.loads(line) for line in open(sys.argv[1])]
for n in sorted({r["n"] for r in rows}):
    print(f"\n{n // 1000000}M sensors:\n")
    print("| ranks | partition | setup s | merge | partition | graph | peak RSS per rank (MiB) | max / mean | edge cut "
          "| ghosts | positions = METIS, 1 rank |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    first = True
    for r in (r for r in rows if r["n"] == n):
        rss = [x / 2**20 for x in r["peak_rss_bytes_per_rank"]]
        same = "(reference)" if first else ("yes" if r["positions_equal_metis_first"] else "NO")
        first = False
        print(f"| {r['ranks']} | {r['partition']} | {r['setup_seconds']:.2f} | {r['setup_merge_seconds']:.2f} | "
              f"{r['setup_partition_seconds']:.2f} | {r['setup_graph_seconds']:.2f} | "
              f"{', '.join(f'{x:.0f}' for x in rss)} | {max(rss) / (sum(rss) / len(rss)):.2f} | {r['edge_cut']} | "
              f"{r['ghosts']} | {same} |")
