#!/usr/bin/python3
"""Per-sensor position errors of the compared results (docs/ceres.md).

usage: /usr/bin/python3 bench/ceres/errors.py WORK/nN   (reads net.h5, R0.h5, mm.h5, mm-accel.h5, ceres.h5)
Prints, per result, the RMSE over the localizable sensors, the median error, the RMSE
without the 1% largest errors and how many sensors are off by more than 10 sigma.
"""
import os, sys
import h5py
import numpy as np

d = sys.argv[1]
net = h5py.File(os.path.join(d, "net.h5"), "r")
truth = net["truth"][:]
sigma = float(net["sigma"][()])
flags = net["localizability/flags"][:] if "localizability/flags" in net else np.zeros(len(truth))
loc = flags == 0
print("n=%d localizable=%d sigma=%g" % (len(truth), loc.sum(), sigma))
print("result rmse_loc median_err rmse_without_worst_1% sensors_err>10sigma max_err")
for name in ("R0", "mm", "mm-accel", "ceres"):
    p = os.path.join(d, name + ".h5")
    if not os.path.exists(p):
        continue
    e = np.linalg.norm(h5py.File(p, "r")["positions"][:] - truth, axis=1)[loc]
    s = np.sort(e)
    keep = s[: int(0.99 * len(s))]
    print("%s %.6g %.6g %.6g %d %.4g" % (name, np.sqrt(np.mean(e ** 2)), np.median(e), np.sqrt(np.mean(keep ** 2)),
                                        (e > 10 * sigma).sum(), e.max()))
