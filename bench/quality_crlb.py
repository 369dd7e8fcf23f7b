"""Weighted CRLB of a network with multiplicative noise, sigma_e = nf * d_e
(true distances): RMSE bound sqrt(trace(J^-1) / n_loc) over the localizable
sensors, J = sum_e u_e u_e^T / sigma_e^2 (003's CRLB with per-range sigmas),
as a dense inverse (numpy; fine at 10^3 sensors). Localizable: at least p + 1
measurements and a component with an anchor measurement; the other sensors
and their ranges are left out. Prints "bound,count".
    /usr/bin/python3 bench/quality_crlb.py NETWORK.h5 NF
"""
import sys

import h5py
import numpy as np


def main(path, nf):
    f = h5py.File(path, "r")
    X = f["truth"][()]
    A = f["anchors"][()]
    se = f["sensor_edges"][()].astype(int)
    ae = f["anchor_edges"][()].astype(int)
    n, p = X.shape
    deg = np.bincount(se.ravel(), minlength=n) + np.bincount(ae[:, 0], minlength=n)
    keep = deg >= p + 1
    # anchored components (union-find over kept sensors)
    parent = list(range(n))

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a
    for i, j in se:
        if keep[i] and keep[j]:
            parent[find(i)] = find(j)
    anchored = {find(i) for i in ae[:, 0] if keep[i]}
    keep &= np.array([find(i) in anchored for i in range(n)])
    idx = -np.ones(n, int)
    idx[keep] = np.arange(keep.sum())
    m = int(keep.sum())
    J = np.zeros((m * p, m * p))
    for i, j in se:
        if not (keep[i] and keep[j]):
            continue
        d = X[i] - X[j]
        r = np.linalg.norm(d)
        u = np.outer(d, d) / (r * r) / (nf * r) ** 2
        a, b = idx[i] * p, idx[j] * p
        J[a:a + p, a:a + p] += u
        J[b:b + p, b:b + p] += u
        J[a:a + p, b:b + p] -= u
        J[b:b + p, a:a + p] -= u
    for i, k in ae:
        if not keep[i]:
            continue
        d = X[i] - A[k]
        r = np.linalg.norm(d)
        a = idx[i] * p
        J[a:a + p, a:a + p] += np.outer(d, d) / (r * r) / (nf * r) ** 2
    bound = np.sqrt(np.trace(np.linalg.inv(J)) / m)
    print(f"{bound:.6g},{m}")


if __name__ == "__main__":
    main(sys.argv[1], float(sys.argv[2]))
