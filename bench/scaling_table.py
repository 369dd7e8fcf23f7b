#!/usr/bin/env python3
"""Prints the one table of bench/scaling.sh from its records (JSON lines).

The bytes an iteration moves come from the solver itself
(`<alg>_traffic_bytes_per_iteration` in its --json; the model is in
docs/performance.md and in each algorithm's traffic_bytes_per_iteration()):
every array the iteration streams counted once, writes as one transfer (like
STREAM), gathered neighbour rows once (RCM locality). With n sensors, g ghosts,
D = 2E directed sensor edges, A anchor pairs and p = 2 this is
  relaxation (one fused pass):                 80 n + 16 g + 12 D + 12 A
  mm:                                          48 n + 16 g + 45 D + 44 A
Older records (before the fused, SIMD kernels) lack the field; for them the
model of that implementation is used:
  relaxation: 192 n + 16 g + 12 D + 12 A      mm: 88 n + 24 g + 44 D + 44 A
bound = bytes / STREAM triad bandwidth on the run's own number of ranks, the
mean of the two readings taken just before and just after that solve (the
VM's shared bandwidth moves within minutes; records without them use the one
reading of all cores at the start of the script). cap = the bandwidth cap on
the scaling of this run, B_R / (R B_1) with the readings around this run and
around its 1-rank run (weak: the 1M one): the par_eff of a loop at the
memory bound on both rank counts.

Bandwidth yardstick: bytes actually moved per second by the STREAM triad,
which bench/stream_triad.cpp measures with non-temporal stores at 24 bytes
per element (records with "stream_def": "nt_24B"). Older records hold the
plain-store triad counted at 24 bytes, which moved 32 (write-allocate): their
readings are restated x 32/24 here (docs/performance.md "Machine and
yardstick"); the GB/s column shows the
readings as used.
"""
import json
import sys

PLAIN_TO_MOVED = 32.0 / 24.0  # old plain-store readings -> bytes actually moved


def moved(gbs, rec):
    """A STREAM reading of rec in the current yardstick."""
    return gbs if rec.get("stream_def") == "nt_24B" else gbs * PLAIN_TO_MOVED


def model_bytes(d):
    key = d["algorithm"] + "_traffic_bytes_per_iteration"
    if key in d:
        return d[key]
    n, g = d["num_sensors"], d["ghosts"]
    D, A = 2 * d["sensor_pairs"], d["anchor_pairs"]
    if d["algorithm"] == "relaxation":
        return 192 * n + 16 * g + 12 * D + 12 * A
    if d["algorithm"] == "mm":
        return 88 * n + 24 * g + 44 * D + 44 * A
    return float("nan")


def main(path):
    recs = [json.loads(l) for l in open(path) if l.strip()]
    stream = dict(next(r for r in recs if r.get("stream")))
    if stream.get("stream_def") != "nt_24B":
        print(f"(plain-store STREAM readings, restated x {PLAIN_TO_MOVED:.4f}: bytes actually moved)")
    for k in ("gbs_1", "gbs_all"):
        stream[k] = moved(stream[k], stream)
    for r in recs:
        if "stream_before_gbs" in r:
            r["stream_before_gbs"] = moved(r["stream_before_gbs"], r)
            r["stream_after_gbs"] = moved(r["stream_after_gbs"], r)
    gens = {r["n"]: r for r in recs if r.get("gen")}
    runs = [r for r in recs if "algorithm" in r]
    if any(r.get("weak") for r in recs):  # weak scaling, 1M sensors per rank: strong runs of that size count too
        runs += [dict(r, kind="weak") for r in runs
                 if r["kind"] == "strong" and r["num_sensors"] == 1000000 * r["ranks"]]
    print(f"STREAM triad at the start: {stream['gbs_1']:.2f} GB/s (1 rank), {stream['gbs_all']:.2f} GB/s "
          f"({stream['nproc']} ranks); GB/s below: the readings just before/after each solve, on its ranks")
    # A loop at the memory bound on 1 and on N ranks scales by the bandwidths' ratio.
    print(f"bandwidth cap on strong scaling 1 -> {stream['nproc']} ranks: "
          f"{stream['gbs_all'] / (stream['nproc'] * stream['gbs_1']):.2f} (par_eff of a memory-bound loop)")
    for n, g in sorted(gens.items()):
        print(f"generate n={n}: {g['generate_seconds']:.2f} s + write {g['gen_write_seconds']:.2f} s, "
              f"peak RSS {g['gen_rss_kib'] / 2**20:.2f} GiB (rank 0, serial)")
    hdr = ["kind", "n", "ranks", "alg", "part", "read_s", "setup_s", "iter_s", "ms/iter", "model_MB",
           "GB/s", "bound_ms", "ratio", "par_eff", "cap", "RSS_GiB", "ghosts", "halo_KB/it", "wait", "write_s",
           "B/sensor"]

    def run_bw(r):  # GB/s for this run's bound
        if "stream_before_gbs" in r:
            return 0.5 * (r["stream_before_gbs"] + r["stream_after_gbs"])
        return stream["gbs_all"]

    # The 1-rank run of each size and method: the base of par_eff and cap (weak: the 1M one).
    base1 = {(r["num_sensors"], r["algorithm"]): r for r in runs if r["ranks"] == 1}
    rows = []
    for r in sorted(runs, key=lambda r: (r["kind"], r["num_sensors"], r["algorithm"], r["ranks"])):
        it = r["iterations"]
        ms = 1e3 * r["iterate_seconds"] / it
        mb = model_bytes(r)
        gbs = run_bw(r)
        bound_ms = mb / gbs / 1e6
        weak = r["kind"] == "weak"
        b1 = base1.get((1000000 if weak else r["num_sensors"], r["algorithm"]))
        eff = float("nan")
        if b1 is not None:
            eff = b1["iterate_seconds"] / ((1 if weak else r["ranks"]) * r["iterate_seconds"])
        cap = float("nan")
        if b1 is not None and "stream_before_gbs" in r and "stream_before_gbs" in b1:
            cap = gbs / (r["ranks"] * run_bw(b1))
        gbs_txt = (f"{r['stream_before_gbs']:.0f}/{r['stream_after_gbs']:.0f}" if "stream_before_gbs" in r
                   else f"{gbs:.0f}")
        rows.append([r["kind"], r["num_sensors"], r["ranks"], r["algorithm"], r["partition"],
                     f"{r['read_seconds']:.2f}", f"{r['setup_seconds']:.2f}", f"{r['iterate_seconds']:.1f}",
                     f"{ms:.2f}", f"{mb / 1e6:.0f}", gbs_txt, f"{bound_ms:.2f}", f"{ms / bound_ms:.2f}",
                     f"{eff:.2f}", f"{cap:.2f}", f"{r['peak_rss_bytes_total'] / 2**30:.2f}", r["ghosts"],
                     f"{r['halo_bytes_per_iteration'] / 1e3:.1f}", f"{r['iterate_wait_fraction']:.3f}",
                     f"{r['write_seconds']:.2f}", f"{r['state_bytes_per_sensor']:.0f}"])
    w = [max(len(str(x)) for x in col) for col in zip(hdr, *rows)]
    line = lambda cells: "| " + " | ".join(str(c).rjust(k) for c, k in zip(cells, w)) + " |"
    print(line(hdr))
    print("|" + "|".join("-" * (k + 2) for k in w) + "|")
    for row in rows:
        print(line(row))


if __name__ == "__main__":
    main(sys.argv[1])
