"""Rows of a bench/setup_warm_ab.sh record file: per run (build, pair) and
repetition, the setup and its phases in seconds (0.00: a phase the build does
not have), the graph build's temporaries
and the peak RSS (largest rank), then per build the range over the first
repetitions (fresh memory) and over the later ones (warm pages).
    /usr/bin/python3 bench/setup_warm_rows.py W/warm.jsonl"""
import json
import sys

COLS = [("merge", "merge"), ("rows", "rows"), ("partition.bfs_graph", "partition's graph"),
        ("partition.bfs", "bfs passes"), ("graph.slots", "slots"), ("graph.exchange", "exchange"),
        ("graph.lists", "lists"), ("graph.order", "order"), ("graph.csr", "csr"), ("graph.values", "values"),
        ("anchors", "anchors"),
        ("connectivity", "connectivity")]


def main(path):
    recs = [json.loads(l) for l in open(path) if l.startswith("{")]
    print("| build | pair | rep | read s | setup s | " + " | ".join(c[1] for c in COLS) +
          " | build temporaries (MiB) | peak RSS (MiB) |")
    print("|" + "---|" * (7 + len(COLS)))
    for r in recs:
        p = r["phases"]
        print(f"| {r['build']} | {r['pair']} | {r['rep']} | {r['read_seconds']:.2f} | {r['setup_seconds']:.2f} | " +
              " | ".join(f"{p.get(k, 0):.2f}" for k, _ in COLS) +
              f" | {r['graph_build_bytes'] / 2**20:.0f} | {r['peak_rss_bytes'] / 2**20:.0f} |")
    print()
    for b in sorted({r["build"] for r in recs}):
        for name, sel in (("first (fresh memory)", lambda r: r["rep"] == 0), ("later (warm)", lambda r: r["rep"] > 0)):
            rs = [r for r in recs if r["build"] == b and sel(r)]
            if not rs:
                continue
            def rng(f):
                v = [f(r) for r in rs]
                return f"{min(v):.2f}-{max(v):.2f}"
            print(f"{b}, {name}, {len(rs)} repetitions: setup {rng(lambda r: r['setup_seconds'])} s; " +
                  ", ".join(f"{lab} {rng(lambda r, k=k: r['phases'].get(k, 0))}" for k, lab in COLS))


if __name__ == "__main__":
    main(sys.argv[1])
