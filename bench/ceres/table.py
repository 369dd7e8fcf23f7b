#!/usr/bin/python3
"""Tables of docs/ceres.md from the raw outputs of bench/ceres/compare.sh.

usage: /usr/bin/python3 bench/ceres/table.py OUT   (OUT/n<N>/...; prints Markdown)

The common targets are relative excesses over the lowest final ML cost reached by
any run at that n (TARGETS); a run reaches a target at the first history record
(every 10 iterations for snl, every LM iteration for Ceres) with ML cost at or below it.
"""
import csv, glob, json, os, re, sys

TARGETS = (1e-2, 1e-4)
METHODS = (("mm", "snl MM"), ("mm-accel", "snl mm-accel"), ("ceres", "Ceres LM"))


def log_info(path):
    """(cpu seconds, load average before) from a compare.sh log."""
    cpu = load = None
    if os.path.exists(path):
        for line in open(path):
            m = re.search(r"time: ([\d.]+) s wall, ([\d.]+) s user, ([\d.]+) s sys", line)
            if m:
                cpu = float(m.group(2)) + float(m.group(3))
            m = re.search(r"# before: .*load average: ([\d.]+)", line)
            if m and load is None:
                load = float(m.group(1))
    return cpu, load


def history(path):
    with open(path) as f:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]


def first_reach(hist, target):
    for row in hist:
        if row["ml_cost"] <= target:
            return row["iteration"], row["elapsed"]
    return None, None


def fmt(x, f):
    return "not reached" if x is None else format(x, f)


def runs_of(d):
    runs = []
    for alg, label in METHODS:
        for j in sorted(glob.glob(os.path.join(d, alg + ".*.json"))):
            m = re.match(r".*/" + re.escape(alg) + r"\.(\d+)\.json$", j)
            if not m:
                continue
            rep = int(m.group(1))
            js = json.load(open(j))
            hist = history(os.path.join(d, "%s.%d.history.csv" % (alg, rep)))
            cpu, load = log_info(os.path.join(d, "%s.%d.log" % (alg, rep)))
            runs.append(dict(alg=alg, label=label, rep=rep, js=js, hist=hist, cpu=cpu, load=load))
    return runs


def table_for(n, d):
    r0 = json.load(open(os.path.join(d, "R0.json")))
    runs = runs_of(d)
    if not runs:
        return
    fmin = min(r["js"]["ml_cost"] for r in runs)
    print("### n = %s\n" % n)
    cpu0, load0 = log_info(os.path.join(d, "R0.log"))
    print("Common start (relaxation, %s rank(s)): %d iterations, %s, ML cost %.10g, RMSE (localizable) %.6g, "
          "solve %.1f s wall%s%s. Lowest final ML cost f_min = %.10g.\n" % (
              r0["ranks"], r0["iterations"], r0["termination"], r0["ml_cost"], r0["rmse_localizable"],
              r0["solve_seconds"], "" if cpu0 is None else ", %.1f s CPU" % cpu0,
              "" if load0 is None else ", load %.1f" % load0, fmin))
    crlb = os.path.join(d, "crlb.json")
    if os.path.exists(crlb):
        c = json.load(open(crlb))
        if c.get("crlb_defined"):
            print("CRLB (`snl eval --crlb --fim-at truth`): RMSE bound %.6g over the %d sensors of the anchored rigid "
                  "part.\n" % (c["crlb_rmse"], c["crlb_sensors"]))
        else:
            print("CRLB (`snl eval --crlb --fim-at truth`): not computed: %s.\n" % c.get("crlb_reason", "?"))
    hdr = ["method", "rep", "load", "iters", "term", "solve_s", "cpu_s"]
    hdr += ["iters to %g" % t for t in TARGETS] + ["s to %g" % t for t in TARGETS]
    hdr += ["final ML cost", "excess", "rmse_loc"]
    print("| " + " | ".join(hdr) + " |")
    print("|" + "---|" * len(hdr))
    for r in runs:
        js = r["js"]
        reach = [first_reach(r["hist"], fmin * (1 + t)) for t in TARGETS]
        row = [r["label"], str(r["rep"]), fmt(r["load"], ".1f"), str(js["iterations"]), js["termination"],
               "%.2f" % js["solve_seconds"], fmt(r["cpu"], ".2f")]
        row += [fmt(i, ".0f") for i, _ in reach] + [fmt(s, ".2f") for _, s in reach]
        row += ["%.10g" % js["ml_cost"], "%.2e" % (js["ml_cost"] / fmin - 1), "%.6g" % js["rmse_localizable"]]
        print("| " + " | ".join(row) + " |")
    print()
    # ratios within one rep (the same locked batch): time to each target relative to mm-accel
    print("Time to target relative to mm-accel in the same batch (>1: slower than mm-accel):\n")
    print("| rep | " + " | ".join("%s to %g" % (lab, t) for _, lab in METHODS if _ != "mm-accel" for t in TARGETS) + " |")
    print("|---|" + "---|" * (2 * len(TARGETS)))
    for rep in sorted({r["rep"] for r in runs}):
        by = {r["alg"]: r for r in runs if r["rep"] == rep}
        if "mm-accel" not in by:
            continue
        cells = []
        for alg, _ in METHODS:
            if alg == "mm-accel":
                continue
            for t in TARGETS:
                a = first_reach(by["mm-accel"]["hist"], fmin * (1 + t))[1]
                b = first_reach(by[alg]["hist"], fmin * (1 + t))[1] if alg in by else None
                cells.append("-" if a is None or b is None else "%.2f" % (b / a))
        print("| %d | %s |" % (rep, " | ".join(cells)))
    print()


def main():
    out = sys.argv[1]
    dirs = sorted(glob.glob(os.path.join(out, "n*")), key=lambda p: int(os.path.basename(p)[1:]))
    for d in dirs:
        if os.path.exists(os.path.join(d, "R0.json")):
            table_for(os.path.basename(d)[1:], d)


if __name__ == "__main__":
    main()
