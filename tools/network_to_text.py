#!/usr/bin/python3
"""Writes a network file's measurements as the text tables `snl import` reads
(docs/formats.md, "Text files"): OUT/edges.csv (i,j,range[,sigma]),
OUT/anchor_edges.txt (whitespace-separated i anchor range[ sigma]),
OUT/anchors.csv and, when the network has truth, OUT/truth.csv.
Values are written with 17 significant digits, so `snl import` reads back the
same numbers. Usage: network_to_text.py NET.h5 OUT_DIR"""
import os
import sys

import h5py


def main(net_path, out):
    os.makedirs(out, exist_ok=True)
    f = h5py.File(net_path, "r")
    src = os.path.basename(net_path)
    g = "{:.17g}".format

    def edges(name, columns, sep, rows_key, ranges_key, sigmas_key):
        e, r = f[rows_key][:], f[ranges_key][:]
        s = f[sigmas_key][:] if sigmas_key in f else None
        with open(os.path.join(out, name), "w") as o:
            o.write(f"# {ranges_key} of {src} (0-based ids)\n")
            o.write(sep.join(columns + (["sigma"] if s is not None else [])) + "\n")
            for k in range(len(r)):
                row = [str(e[k, 0]), str(e[k, 1]), g(r[k])] + ([g(s[k])] if s is not None else [])
                o.write(sep.join(row) + "\n")

    def points(name, key, what):
        x = f[key][:]
        with open(os.path.join(out, name), "w") as o:
            o.write(f"# {what} of {src}, one row each (row k: id k)\n")
            o.write(",".join("xyz"[: x.shape[1]]) + "\n")
            for row in x:
                o.write(",".join(g(v) for v in row) + "\n")

    edges("edges.csv", ["i", "j", "range"], ",", "sensor_edges", "sensor_ranges", "sensor_sigmas")
    edges("anchor_edges.txt", ["i", "anchor", "range"], " ", "anchor_edges", "anchor_ranges", "anchor_sigmas")
    points("anchors.csv", "anchors", "anchor positions")
    if "truth" in f:
        points("truth.csv", "truth", "true sensor positions")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
