#!/usr/bin/python3
"""Reads a bench/rss_timeline.sh log and the run's solve JSON and prints, per
process, its largest resident memory and when, and its largest before the
solve began (the first read + setup seconds of the JSON, counted from the
process's first sample): whether the run's peak RSS is the setup's or the
solve's.
  /usr/bin/python3 bench/rss_timeline.py rss.txt run.json
"""
import json
import sys


def main(log, run):
    j = json.load(open(run))
    before_solve = j["read_seconds"] + j["setup_seconds"]
    rows = [line.split() for line in open(log) if not line.startswith("#")]
    print(f"read {j['read_seconds']:.1f} s, setup {j['setup_seconds']:.1f} s, solve {j['solve_seconds']:.1f} s; "
          f"peak RSS per rank (JSON): {[round(x / 2**20) for x in j['peak_rss_bytes_per_rank']]} MiB")
    for pid in sorted(set(r[1] for r in rows)):
        samples = [(float(t), int(kib)) for t, p, kib in rows if p == pid]
        first = samples[0][0]
        peak = max(samples, key=lambda s: s[1])
        setup = max(kib for t, kib in samples if t < first + before_solve)
        print(f"pid {pid}: largest {peak[1] / 1024:.0f} MiB at {peak[0] - first:.1f} s; "
              f"largest before the solve {setup / 1024:.0f} MiB; {len(samples)} samples")


if __name__ == "__main__":
    main(*sys.argv[1:3])
