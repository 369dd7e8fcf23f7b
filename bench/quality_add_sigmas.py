"""Copy of a benchmark network with sigma_e = NF * true distance written to
sensor_sigmas / anchor_sigmas (the model the file's noise was drawn from; an
oracle, since a real network only knows its measured ranges).
    /usr/bin/python3 bench/quality_add_sigmas.py IN.h5 OUT.h5 NF
"""
import shutil
import sys

import h5py
import numpy as np

src, dst, nf = sys.argv[1], sys.argv[2], float(sys.argv[3])
shutil.copy(src, dst)
with h5py.File(dst, "r+") as f:
    X, A = f["truth"][()], f["anchors"][()]
    se, ae = f["sensor_edges"][()].astype(int), f["anchor_edges"][()].astype(int)
    f["sensor_sigmas"] = nf * np.linalg.norm(X[se[:, 0]] - X[se[:, 1]], axis=1)
    f["anchor_sigmas"] = nf * np.linalg.norm(X[ae[:, 0]] - A[ae[:, 1]], axis=1)
