#!/usr/bin/python3
"""Restates the ratios "measured time / bandwidth bound" of the recorded runs
under docs/data/perf/ with the current bandwidth yardstick.

The records were taken with the old bench/stream_triad, a plain-store triad
counted at 24 bytes per element. Its stores read every line for ownership
first, so the memory really moved 32 bytes per element: the bandwidth the
triad achieved is 32/24 = 4/3 of the printed figure. The solver's traffic
model (docs/performance.md "The traffic model") counts a written array as one
transfer, and the kernels write their rows with non-temporal stores, so the
bound uses the bytes-actually-moved bandwidth, which the current
stream_triad measures directly (triad_nt_gbs, non-temporal stores, 24 B).
For an old reading G:

    G_restated = G * 32 / 24,   bound_restated = model_bytes / G_restated,
    ratio_restated = ratio_old * 32 / 24.

Usage: /usr/bin/python3 tools/restate_ratios.py [FILE...]
  FILE: a record of jobs/bench10m.sbatch (*.txt with "STREAM triad (2 ranks)")
  or of bench/scaling.sh (*.jsonl); job records must come from the old
  stream_triad (before 2026-12-01: they carry no tag), scaling records tagged
  "stream_def": "nt_24B" are taken as they are. Without files: every file that
  docs/performance.md cites for a ratio.
Prints one row per solve: the old reading(s), the old ratio (mean of the
readings, as the scripts computed it) and the restated one.
"""
import json
import os
import re
import sys

PLAIN_BYTES, MOVED_BYTES = 24.0, 32.0  # per triad element: as printed / as moved (write-allocate)
FACTOR = MOVED_BYTES / PLAIN_BYTES

PERF = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "docs", "data", "perf")
CITED = [
    "results-2026-11-29-tblock-bench10m-s1.txt",
    "results-2026-11-29-tblock-bench10m-s8.txt",
    "results-2026-11-29-final-scaling10m-1.jsonl",
    "results-2026-11-29-final-scaling10m-2.jsonl",
    "results-2026-11-29-final-scaling1m.jsonl",
    "results-2026-11-29-final-scaling1m-rep2.jsonl",
    "results-2026-11-29-final-scaling1m-rep3.jsonl",
    "results-2026-11-29-tblock8-scaling.jsonl",
    "results-2026-11-29-tblock8-scaling1m-rep2.jsonl",
    "results-2026-11-29-tblock8-scaling1m-rep3.jsonl",
]


def row(name, kind, n, ranks, alg, ms, model, readings, block):
    gbs = sum(readings) / len(readings)
    old = ms / (model / gbs / 1e6)
    new = ms / (model / (gbs * FACTOR) / 1e6)
    rd = "/".join(f"{g:.1f}" for g in readings)
    return (f"| {name} | {kind} | {n} | {ranks} | {alg} | {block} | {ms:.2f} | {model / 1e6:.0f} | {rd} | "
            f"{old:.2f} | {gbs * FACTOR:.1f} | {new:.2f} |")


def bench10m_rows(path):
    """jobs/bench10m.sbatch: the pipeline runs iterations/2 of each method."""
    text = open(path).read()
    val = lambda k: float(re.search(rf"^{re.escape(k)}: (\S+)", text, re.M).group(1))
    readings = [float(g) for g in re.findall(r"^STREAM triad \(2 ranks\)(?: after the solve)?: (\S+) GB/s", text, re.M)]
    iters = val("iterations") / 2
    block = int(val("temporal_block")) if re.search(r"^temporal_block:", text, re.M) else 1
    out = []
    for alg in ("relaxation", "mm"):
        ms = 1e3 * val(f"{alg}_iterate_seconds") / iters
        out.append(row(os.path.basename(path), "job", int(val("num_sensors")), int(val("ranks")), alg, ms,
                       val(f"{alg}_traffic_bytes_per_iteration"), readings, block))
    return out


def scaling_rows(path):
    """bench/scaling.sh: readings around each solve (stream_before/after_gbs)."""
    recs = [json.loads(l) for l in open(path) if l.strip()]
    start = next(r for r in recs if r.get("stream"))
    out = []
    for r in recs:
        if "algorithm" not in r:
            continue
        key = r["algorithm"] + "_traffic_bytes_per_iteration"
        if key not in r:
            continue  # records before the model field: not restated (no ratio of them is cited)
        readings = ([r["stream_before_gbs"], r["stream_after_gbs"]] if "stream_before_gbs" in r
                    else [start["gbs_all"]])
        if r.get("stream_def") == "nt_24B":  # already the current yardstick: undo the restatement
            readings = [g / FACTOR for g in readings]
        ms = 1e3 * r["iterate_seconds"] / r["iterations"]
        out.append(row(os.path.basename(path), r["kind"], r["num_sensors"], r["ranks"], r["algorithm"], ms,
                       r[key], readings, r.get("temporal_block", 1)))
    return out


def main(paths):
    paths = paths or [os.path.join(PERF, f) for f in CITED]
    print(f"# restated bound: old plain-store STREAM reading x {MOVED_BYTES:.0f}/{PLAIN_BYTES:.0f} "
          f"(bytes actually moved); ratio = ms per iteration / (model bytes / bandwidth)")
    print("| file | kind | n | ranks | alg | S | ms/it | model MB | old GB/s | old ratio | restated GB/s | restated ratio |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for p in paths:
        for line in (scaling_rows(p) if p.endswith(".jsonl") else bench10m_rows(p)):
            print(line)


if __name__ == "__main__":
    main(sys.argv[1:])
