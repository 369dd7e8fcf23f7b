#!/usr/bin/python3
"""Markdown rows of docs/performance.md's partition tables from bench/setup_ab.sh
records: n, ranks, partition, rep, setup s, partition s (its graph + the call),
graph build s, edge cut, ghosts, ms per relaxation and MM iteration, peak RSS of
the largest rank (MiB), positions equal to the first A run's. With --phases:
n, ranks, build, rep, setup s, merge, partition (its graph + the call), the
graph build's edge exchange, lists, order and CSR, peak RSS, positions, then
the block rows, the neighbour slots and the values' rounds (0.00 for a build
without them).
    /usr/bin/python3 bench/setup_ab_rows.py [--phases] W/records.jsonl ..."""
import json
import sys

phases = len(sys.argv) > 1 and sys.argv[1] == "--phases"
for f in sys.argv[1 + phases:]:
    print("##", f)
    for line in open(f):
        r = json.loads(line)
        if phases:
            g = r.get("setup_partition.bfs_graph_seconds", r.get("setup_partition.metis_graph_seconds", 0))
            call = r.get("setup_partition.bfs_seconds", r.get("setup_partition.metis_seconds", 0))
            ph = [r.get(f"setup_graph.{k}_seconds", 0) for k in ("exchange", "lists", "order", "csr")]
            print(f"| {r['n'] // 1000000}M | {r['ranks']} | {r['build']} | {r['rep']} | {r['setup_seconds']:.2f} | "
                  f"{r['setup_merge_seconds']:.2f} | {r['setup_partition_seconds']:.2f} ({g:.2f} + {call:.2f}) | "
                  + " | ".join(f"{x:.2f}" for x in ph) + f" | {max(r['peak_rss_bytes_per_rank']) / 2**20:.0f} | "
                  f"{'yes' if r['positions_equal_first_A'] else 'NO'} | "
                  f"{r.get('setup_rows_seconds', 0):.2f} | {r.get('setup_graph.slots_seconds', 0):.2f} | "
                  f"{r.get('setup_graph.values_seconds', 0):.2f} |")
            continue
        call = r.get("setup_partition.metis_seconds", r.get("setup_partition.bfs_seconds", 0))
        g = r.get("setup_partition.metis_graph_seconds", r.get("setup_partition.bfs_graph_seconds", 0))
        print(f"| {r['n'] // 1000000}M | {r['ranks']} | {r['partition']} | {r['rep']} | {r['setup_seconds']:.2f} | "
              f"{r['setup_partition_seconds']:.2f} ({g:.2f} + {call:.2f}) | {r['setup_graph_seconds']:.2f} | "
              f"{r['edge_cut']} | {r['ghosts']} | {r['relaxation_ms_per_iteration']:.1f} | "
              f"{r['mm_ms_per_iteration']:.1f} | {max(r['peak_rss_bytes_per_rank']) / 2**20:.0f} | "
              f"{'yes' if r['positions_equal_first_A'] else 'NO'} |")
