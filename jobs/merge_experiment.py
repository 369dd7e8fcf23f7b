#!/usr/bin/python3
"""Merge the per-task CSVs of jobs/experiment_array.sbatch into one table.

    /usr/bin/python3 jobs/merge_experiment.py merged.csv DIR/task-*.csv

Each input is named task-<id>.seed-<seed>.csv; the output has the columns
task,seed followed by snl experiment's columns, rows ordered by task id and
then as in each file. Inputs must share one header. Standard library only.
"""
import csv
import os
import re
import sys

NAME = re.compile(r"task-(\d+)\.seed-(\d+)\.csv$")


def read_task(path):
    """(task, seed, header, rows) of one per-task CSV."""
    m = NAME.search(os.path.basename(path))
    if not m:
        sys.exit(f"merge_experiment: {path}: not named task-<id>.seed-<seed>.csv")
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if not rows:
        sys.exit(f"merge_experiment: {path}: empty file")
    return int(m.group(1)), int(m.group(2)), rows[0], rows[1:]


def main(argv):
    if len(argv) < 3:
        sys.exit(__doc__)
    out, inputs = argv[1], argv[2:]
    tasks = sorted((read_task(p) for p in inputs), key=lambda t: t[0])
    header = tasks[0][2]
    ids = [t[0] for t in tasks]
    if len(set(ids)) != len(ids):
        sys.exit("merge_experiment: a task id appears twice")
    for task, _, h, _ in tasks:
        if h != header:
            sys.exit(f"merge_experiment: task {task} has another header than task {tasks[0][0]}")
    tmp = out + ".tmp"
    with open(tmp, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["task", "seed"] + header)
        n = 0
        for task, seed, _, rows in tasks:
            for r in rows:
                w.writerow([task, seed] + r)
                n += 1
    os.replace(tmp, out)
    print(f"merge_experiment: {len(tasks)} tasks, {n} rows -> {out}")


if __name__ == "__main__":
    main(sys.argv)
