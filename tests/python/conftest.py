"""Shared fixtures of the Python tests: the CLI, its environment, scratch dirs."""
import os
import shutil
import subprocess

import pytest

SOURCE = os.environ.get("SNL_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
BENCH = os.path.join(SOURCE, "inputs", "benchmarks", "test10-500.h5")


def snl_exe():
    exe = os.environ.get("SNL")
    if not exe or not os.path.exists(exe):
        pytest.skip("SNL (the snl executable) is not set; run through ctest")
    return exe


def mpiexec(np_):
    mpi = os.environ.get("MPIEXEC") or shutil.which("mpirun")
    if not mpi:
        pytest.skip("no mpirun")
    return [mpi, os.environ.get("MPIEXEC_NUMPROC_FLAG", "-np"), str(np_), "--oversubscribe"]


def clean_env():
    """os.environ as at start-up: without the PMIX_/OMPI_ variables that MPI_Init
    (a singleton, at `import snl`) put in the C environment, which a child mpirun
    would take for its own job's."""
    return dict(os.environ)


def run(cmd, **kw):
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=300, env=clean_env(), **kw)
    assert p.returncode == 0, f"{cmd} failed ({p.returncode}):\n{p.stdout}\n{p.stderr}"
    return p


def cli_positions(network, out, *args, np_=1):
    import h5py
    pre = mpiexec(np_) if np_ > 1 else []
    run(pre + [snl_exe(), "solve", str(network), "-o", str(out), "-q", *args])
    with h5py.File(out, "r") as f:
        return f["positions"][()]


def same_bits(a, b):
    """Equal bit for bit (not merely ==: -0.0 and 0.0 differ, NaN equals itself)."""
    return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()
