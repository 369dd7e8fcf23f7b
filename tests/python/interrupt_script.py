"""Run by test_mpi.py: a long solve that test_mpi.py interrupts with SIGINT.
Each rank prints `started <rank> <pid>` at its first record, then
`interrupted <rank>` when the solve raises KeyboardInterrupt."""
import os
import sys

import snl

net = snl.generate(2000, seed=3)
rank = snl.rank()
started = []


def announce(rec):
    if not started:
        started.append(1)
        os.write(1, f"started {rank} {os.getpid()}\n".encode())  # one write: ranks' lines stay whole


try:
    snl.solve(net, algorithm="mm", max_iter=10**7, tol=0, callback=announce)
    os.write(1, f"finished {rank}\n".encode())
except KeyboardInterrupt:
    os.write(1, f"interrupted {rank}\n".encode())
    sys.exit(0)
