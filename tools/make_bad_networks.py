#!/usr/bin/python3
"""Writes a corpus of broken network files for the end-to-end bad-input tests.

Uses Debian's /usr/bin/python3 with python3-h5py and python3-numpy.
  tools/make_bad_networks.py VALID.h5 OUTDIR [--random K] [--seed S]
Each file breaks one rule of the spec (docs/formats.md); further files are
random byte corruptions and truncations of VALID.h5. Prints one file name per line.
"""
import argparse
import os
import shutil

import h5py
import numpy as np


def copy_with(valid, out, edit):
    shutil.copyfile(valid, out)
    with h5py.File(out, "r+") as f:
        edit(f)


def replace(f, name, data):
    del f[name]
    f[name] = data


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("valid")
    ap.add_argument("outdir")
    ap.add_argument("--random", type=int, default=8)
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    os.makedirs(a.outdir, exist_ok=True)
    with h5py.File(a.valid, "r") as f:
        se = f["sensor_edges"][...]
        sr = f["sensor_ranges"][...]
        ae = f["anchor_edges"][...]
        ar = f["anchor_ranges"][...]
        n = int(f.attrs["num_sensors"])
        p = int(f.attrs["dim"])
        m = f["anchors"].shape[0]

    def mod(arr, row, col, val):
        arr = arr.copy()
        if col is None:
            arr[row] = val
        else:
            arr[row, col] = val
        return arr

    r = len(sr) // 2
    cases = {
        "wrong_format": lambda f: f.attrs.modify("format", "not-snl"),
        "wrong_version": lambda f: f.attrs.modify("version", 7),
        "bad_dim": lambda f: f.attrs.modify("dim", 4),
        "missing_sensor_edges": lambda f: f.__delitem__("sensor_edges"),
        "missing_anchors": lambda f: f.__delitem__("anchors"),
        "missing_format": lambda f: f.attrs.__delitem__("format"),
        "edges_wrong_shape": lambda f: replace(f, "sensor_edges", np.zeros((len(sr), 3), dtype=np.int64)),
        "ranges_wrong_length": lambda f: replace(f, "sensor_ranges", sr[:-1]),
        "anchors_wrong_shape": lambda f: replace(f, "anchors", np.zeros((m, p + 1))),
        "truth_wrong_shape": lambda f: replace(f, "truth", np.zeros((n + 1, p))),
        "nan_range": lambda f: replace(f, "sensor_ranges", mod(sr, r, None, np.nan)),
        "inf_anchor_range": lambda f: replace(f, "anchor_ranges", mod(ar, len(ar) - 1, None, np.inf)),
        "nan_anchor": lambda f: replace(f, "anchors", np.full((m, p), np.nan)),
        "negative_range": lambda f: replace(f, "sensor_ranges", mod(sr, r, None, -0.5)),
        "self_loop": lambda f: replace(f, "sensor_edges", mod(se, r, 1, se[r, 0])),
        "sensor_index_out_of_range": lambda f: replace(f, "sensor_edges", mod(se, r, 0, n)),
        "negative_sensor_index": lambda f: replace(f, "sensor_edges", mod(se, r, 1, -1)),
        "anchor_index_out_of_range": lambda f: replace(f, "anchor_edges", mod(ae, 0, 1, m)),
        "ranges_are_strings": lambda f: replace(f, "sensor_ranges", np.array([b"x"] * len(sr))),
        "no_anchors": lambda f: (replace(f, "anchors", np.zeros((0, p))),
                                 replace(f, "anchor_edges", np.zeros((0, 2), dtype=np.int64)),
                                 replace(f, "anchor_ranges", np.zeros(0))),
    }
    for name, edit in cases.items():
        out = os.path.join(a.outdir, name + ".h5")
        copy_with(a.valid, out, edit)
        print(out)
    # Not HDF5 at all; empty; truncations; random byte corruptions.
    with open(os.path.join(a.outdir, "not_hdf5.h5"), "w") as f:
        f.write("this is not an HDF5 file\n" * 10)
    print(os.path.join(a.outdir, "not_hdf5.h5"))
    open(os.path.join(a.outdir, "empty.h5"), "w").close()
    print(os.path.join(a.outdir, "empty.h5"))
    data = open(a.valid, "rb").read()
    rng = np.random.default_rng(a.seed)
    for k, frac in enumerate([0.1, 0.5, 0.9]):
        out = os.path.join(a.outdir, f"truncated_{k}.h5")
        with open(out, "wb") as f:
            f.write(data[: int(len(data) * frac)])
        print(out)
    for k in range(a.random):
        buf = bytearray(data)
        for _ in range(int(rng.integers(1, 64))):
            pos = int(rng.integers(0, len(buf)))
            buf[pos] = int(rng.integers(0, 256))
        out = os.path.join(a.outdir, f"corrupt_{k}.h5")
        with open(out, "wb") as f:
            f.write(bytes(buf))
        print(out)


if __name__ == "__main__":
    main()
