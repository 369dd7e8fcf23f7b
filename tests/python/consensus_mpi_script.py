"""Run by test_consensus.py under `mpirun -np K`: solves a problem from arrays
given whole on rank 0, and built on every rank; every rank writes its x to
OUT.npz.RANK (x is returned on every rank).
  consensus_mpi_script.py IN.npz OUT.npz"""
import sys

import numpy as np
import snl

d = np.load(sys.argv[1])
mk = lambda: snl.consensus.Problem(d["edges"], "logistic", features=d["a"], labels=d["y"], owner=d["owner"])  # noqa: E731
root = snl.consensus.solve(mk() if snl.rank() == 0 else None)
everywhere = snl.consensus.solve(mk())
np.savez(f"{sys.argv[2]}.{snl.rank()}.npz", root=root.x, all=everywhere.x, ranks=np.array(root.summary["ranks"]))
