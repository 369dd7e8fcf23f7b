"""Under mpirun: the same script on 2 ranks gives the CLI's positions bit for
bit (network whole on rank 0, read by every rank, an mpi4py communicator);
Ctrl-C (SIGINT) raises KeyboardInterrupt on every rank, serial and on 2 ranks."""
import os
import re
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import snl
from conftest import BENCH, clean_env, cli_positions, mpiexec, same_bits

HERE = os.path.dirname(os.path.abspath(__file__))


def test_two_ranks_bit_identical_to_cli_and_one_rank(tmp_path):
    pytest.importorskip("mpi4py")
    cli1 = cli_positions(BENCH, tmp_path / "r1.h5")
    cli2 = cli_positions(BENCH, tmp_path / "r2.h5", np_=2)
    one = snl.solve(snl.Network.from_file(BENCH)).positions
    out = tmp_path / "p.npz"
    p = subprocess.run(mpiexec(2) + [sys.executable, os.path.join(HERE, "mpi_script.py"), BENCH, str(out)],
                       capture_output=True, text=True, timeout=300, env=clean_env())
    assert p.returncode == 0, p.stderr
    d = np.load(out)
    assert int(d["ranks"]) == 2
    for key in ("root", "all", "comm", "split"):
        assert same_bits(d[key], cli1), key
    assert same_bits(cli2, cli1) and same_bits(one, cli1)


def interrupt(cmd, ranks, tmp_path):
    """Starts cmd, waits for every rank's first record, sends SIGINT to rank 0's process."""
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=clean_env())
    pids = {}
    try:
        return signal_when_started(proc, ranks, pids)
    finally:
        if proc.poll() is None:  # never leave a run of 10^7 iterations behind
            proc.terminate()  # mpirun ends its ranks
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()
            for pid in pids.values():
                try:
                    os.kill(pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass


def signal_when_started(proc, ranks, pids):
    deadline = time.time() + 120
    while len(pids) < ranks and time.time() < deadline:
        line = proc.stdout.readline()
        if not line:
            break
        for r, pid in re.findall(r"started (\d+) (\d+)", line):  # the ranks' lines may share one
            pids[int(r)] = int(pid)
    assert len(pids) == ranks, proc.stderr.read() if proc.poll() is not None else "no start"
    os.kill(pids[0], signal.SIGINT)
    try:
        out, err = proc.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        pytest.fail("a rank hung after SIGINT")
    return proc.returncode, out, err


def test_ctrl_c_serial(tmp_path):
    rc, out, err = interrupt([sys.executable, os.path.join(HERE, "interrupt_script.py")], 1, tmp_path)
    assert rc == 0 and "interrupted 0" in out, err
    assert "finished" not in out


def test_ctrl_c_two_ranks(tmp_path):
    cmd = mpiexec(2) + [sys.executable, os.path.join(HERE, "interrupt_script.py")]
    rc, out, err = interrupt(cmd, 2, tmp_path)
    assert rc == 0, err
    assert "interrupted 0" in out and "interrupted 1" in out, out + err


def test_bad_argument_on_one_rank_raises_on_both(tmp_path):
    script = (
        "import sys, snl\n"
        "out = open(sys.argv[1] + '.' + str(snl.rank()), 'w')\n"  # one file per rank: no interleaving
        "net = snl.generate(100, seed=2)\n"
        "opts = {'grad_tol': 1e-3} if snl.rank() == 1 else {}\n"
        "try:\n"
        "    snl.solve(net, algorithm='mm', max_iter=50, **opts)\n"
        "    out.write('solved\\n')\n"
        "except ValueError as e:\n"
        "    out.write(f'raised {e}\\n')\n"
        "r = snl.solve(net, algorithm='mm', max_iter=50)\n"  # both ranks go on together
        "out.write(f'then solved {r.summary[\"iterations\"]}\\n')\n")
    base = str(tmp_path / "out")
    p = subprocess.run(mpiexec(2) + [sys.executable, "-c", script, base], capture_output=True, text=True,
                       timeout=120, env=clean_env())
    assert p.returncode == 0, p.stderr
    r0 = open(base + ".0").read().splitlines()
    r1 = open(base + ".1").read().splitlines()
    assert r0 == ["raised solve: invalid arguments on another rank", "then solved 50"], r0
    assert r1[0].startswith("raised --grad-tol is not honoured by --algorithm mm") and r1[1] == "then solved 50", r1
