#!/usr/bin/env python3
"""Plot of bench/async_straggler.sh: seconds to the target relaxed cost against
the straggler's delay, synchronous relaxation vs async --mode free, every run
a point (the line through the mean of the repetitions); runs that missed the
target drawn hollow.

  /usr/bin/python3 bench/plot_async_straggler.py docs/data/perf/async-straggler.csv -o docs/async_straggler.png
"""
import argparse
import csv

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("csv")
    ap.add_argument("-o", "--output", required=True)
    a = ap.parse_args()
    rows = list(csv.DictReader(open(a.csv)))
    target = rows[0]["target"] if rows else "?"
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    styles = {"relaxation": ("C0", "o", "synchronous relaxation (Nesterov)"), "free": ("C3", "s", "async --mode free")}
    for method, (color, marker, label) in styles.items():
        mine = [r for r in rows if r["method"] == method]
        delays = sorted({float(r["delay"]) for r in mine})
        means = []
        for d in delays:
            t = [float(r["seconds"]) for r in mine if float(r["delay"]) == d]
            means.append(sum(t) / len(t))
        ax.plot(delays, means, color=color, label=label)
        for r in mine:
            ok = r["reached"] == "yes"
            ax.plot(float(r["delay"]), float(r["seconds"]), marker=marker, color=color, linestyle="none",
                    markerfacecolor=color if ok else "none")
    ax.set_xscale("symlog", linthresh=0.01)
    ax.set_yscale("log")
    ax.set_xlabel("straggler delay (s per iteration of the last rank; free: per n_own activations)")
    ax.set_ylabel("seconds to f_hat <= target")
    n, np_ = (rows[0]["n"], rows[0]["np"]) if rows else ("?", "?")
    ax.set_title(f"Time to f_hat <= {target}: {n} sensors, {np_} ranks, from --init dv", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(a.output, dpi=110)


if __name__ == "__main__":
    main()
