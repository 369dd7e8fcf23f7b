"""Run by test_mpi.py under `mpirun -np K`: solves a network four ways and
writes rank 0's positions to OUT.npz (compared there with 1 rank and the CLI).
  mpi_script.py NETWORK OUT.npz [keyword=value ...]"""
import sys

import numpy as np
import snl

path, out = sys.argv[1], sys.argv[2]
opts = {k: (int(v) if v.lstrip("-").isdigit() else v) for k, v in (a.split("=", 1) for a in sys.argv[3:])}
rank = snl.rank()
# Given whole on rank 0 only, from arrays.
whole = None
if rank == 0:
    f = snl.Network.from_file(path)
    whole = snl.Network(anchors=f.anchors, n_sensors=f.n_sensors, edges=f.edges, ranges=f.ranges, dim=f.dim,
                        truth=f.truth)
r_root = snl.solve(whole, **opts)
# Read from the file by every rank.
net = snl.Network.from_file(path)
r_all = snl.solve(net, **opts)
# An mpi4py communicator (a duplicate of the world).
try:
    from mpi4py import MPI
    comm = MPI.COMM_WORLD.Dup()
    r_comm = snl.solve(net, comm=comm, **opts).positions
    comm.Free()
    # One rank per communicator: each rank solves alone.
    own = MPI.COMM_WORLD.Split(rank, 0)
    r_split = snl.solve(net, comm=own, **opts)
    assert r_split.summary["ranks"] == 1
    own.Free()
except ImportError:
    r_comm = r_split = None
assert r_root.summary["ranks"] == snl.size()
if rank == 0:
    arrays = {"root": r_root.positions, "all": r_all.positions, "ranks": np.array(r_all.summary["ranks"])}
    if r_comm is not None:
        arrays["comm"] = r_comm
        arrays["split"] = r_split.positions
    np.savez(out, **arrays)
