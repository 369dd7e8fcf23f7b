"""The same script serial or under mpirun (docs/python.md):
  PYTHONPATH=build-py/python mpirun -np 2 /usr/bin/python3 python/examples/mpi_solve.py NET.h5
The network is read by every rank; a network built from arrays may instead be
given on rank 0 only (None on the others). Every rank gets all positions."""
import sys

import snl

net = snl.Network.from_file(sys.argv[1])
r = snl.solve(net, progress=lambda rec: None)
if snl.rank() == 0:
    s = r.summary
    print(f"{s['ranks']} ranks: {s['termination']} after {s['iterations']} iterations, RMSE {s['rmse']:.6f}, "
          f"{s['mpi_bytes']} MPI bytes, partition {s['partition']}")
    print("first positions:", r.positions[:2].tolist())
