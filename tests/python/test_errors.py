"""Every bad input raises a Python exception (ValueError for bad data and
options, with the file reader's message), and the interpreter goes on."""
import shutil
import subprocess

import h5py
import numpy as np
import pytest

import snl
from conftest import BENCH, clean_env, snl_exe


@pytest.fixture(scope="module")
def net():
    return snl.Network.from_file(BENCH)


def build(net, **change):
    kw = dict(anchors=net.anchors, n_sensors=net.n_sensors, edges=net.edges, ranges=net.ranges, dim=net.dim)
    kw.update(change)
    return snl.Network(**kw)


def with_value(a, index, value):
    a = np.array(a, copy=True)
    a[index] = value
    return a


def test_valid_arrays_build(net):
    assert build(net).n_sensors == net.n_sensors  # the base of every case below is valid


def test_same_message_as_the_file_reader(net, tmp_path):
    bad = tmp_path / "bad.h5"
    shutil.copy(BENCH, bad)
    with h5py.File(bad, "a") as f:
        f["sensor_ranges"][5] = -1.0
    cli = subprocess.run([snl_exe(), "info", str(bad)], capture_output=True, text=True, env=clean_env())
    assert cli.returncode != 0
    line = cli.stderr.strip().splitlines()[-1]
    assert line.startswith("snl: error: ")
    with pytest.raises(ValueError) as file_err:
        snl.Network.from_file(bad)
    assert str(file_err.value) == line[len("snl: error: "):]
    with pytest.raises(ValueError) as array_err:
        build(net, ranges=with_value(net.ranges, 5, -1.0))
    assert str(file_err.value) == f"{bad}: {array_err.value}"


BAD_NETWORKS = {
    "anchors shape": lambda n: build(n, anchors=n.anchors[:, :1]),
    "anchors 1-d": lambda n: build(n, anchors=n.anchors.ravel()),
    "anchor NaN": lambda n: build(n, anchors=with_value(n.anchors, (2, 0), np.nan)),
    "anchor Inf": lambda n: build(n, anchors=with_value(n.anchors, (2, 1), np.inf)),
    "edges 3 columns": lambda n: build(n, edges=np.c_[n.edges, n.edges[:, :1]]),
    "edges float": lambda n: build(n, edges=n.edges + 0.5),
    "edges strings": lambda n: build(n, edges=np.array([["a", "b"]])),
    "edges ragged": lambda n: build(n, edges=[[0, 1], [2]]),
    "ranges short": lambda n: build(n, ranges=n.ranges[:-1]),
    "range NaN": lambda n: build(n, ranges=with_value(n.ranges, 3, np.nan)),
    "range negative": lambda n: build(n, ranges=with_value(n.ranges, 3, -0.5)),
    "range 2-d": lambda n: build(n, ranges=n.ranges[:, None]),
    "index negative": lambda n: build(n, edges=with_value(n.edges, (4, 0), -1)),
    "index too large": lambda n: build(n, edges=with_value(n.edges, (4, 1), n.n_sensors + n.n_anchors)),
    "index huge": lambda n: build(n, edges=with_value(n.edges, (4, 1), 2**62)),
    "self-loop": lambda n: build(n, edges=with_value(n.edges, (0, 1), n.edges[0, 0])),
    "anchor to anchor": lambda n: build(n, edges=with_value(n.edges, 0, [n.n_sensors, n.n_sensors + 1])),
    "n_sensors 0": lambda n: build(n, n_sensors=0),
    "dim 4": lambda n: build(n, dim=4),
    "sigma negative": lambda n: build(n, sigmas=-1.0),
    "sigmas length": lambda n: build(n, sigmas=np.ones(3)),
    "sigmas zero": lambda n: build(n, sigmas=np.zeros(len(n.ranges))),
    "truth shape": lambda n: build(n, truth=np.zeros((3, 2))),
    "truth NaN": lambda n: build(n, truth=with_value(np.zeros((n.n_sensors, 2)), (1, 1), np.nan)),
    "missing file": lambda n: snl.Network.from_file("/nonexistent/net.h5"),
    "not a network file": lambda n: snl.Network.from_file(__file__[:-3] + ".h5"),
}


@pytest.mark.parametrize("case", sorted(BAD_NETWORKS))
def test_bad_network_raises(net, case):
    with pytest.raises(ValueError):
        BAD_NETWORKS[case](net)


BAD_SOLVES = {
    "unknown algorithm": (ValueError, dict(algorithm="nope")),
    "option not honoured": (ValueError, dict(algorithm="mm", grad_tol=1e-3)),
    "temporal block not honoured": (ValueError, dict(algorithm="bb", temporal_block=4)),
    "free mode not honoured": (ValueError, dict(algorithm="relaxation", mode="free")),
    "unknown mode": (ValueError, dict(algorithm="async", mode="sometimes")),
    "negative straggler delay": (ValueError, dict(straggler_delay=-1.0)),
    "bad stop rule": (ValueError, dict(stop="sometimes")),
    "bad partition": (ValueError, dict(partition="zigzag")),
    "bad weights": (ValueError, dict(weights="heavy")),
    "negative seed": (ValueError, dict(seed=-1)),
    "bad init name": (ValueError, dict(init="warm")),
    "init shape": (ValueError, dict(init=np.zeros((3, 2)))),
    "init for a one-shot method": (ValueError, dict(algorithm="sdp", init=np.zeros((490, 2)))),
    "unknown keyword": (TypeError, dict(max_iterations=5)),
    "wrong type": (TypeError, dict(max_iter="many")),
    "checkpoint_every without checkpoint": (ValueError, dict(checkpoint_every=10)),
}


@pytest.mark.parametrize("case", sorted(BAD_SOLVES))
def test_bad_solve_raises(net, case):
    exc, kw = BAD_SOLVES[case]
    with pytest.raises(exc):
        snl.solve(net, max_iter=kw.pop("max_iter", 5), **kw)


def test_unhonoured_option_message_is_the_registrys(net):
    with pytest.raises(ValueError, match="grad-tol|grad_tol"):
        snl.solve(net, algorithm="mm", grad_tol=1e-3)


def test_bad_generate_and_evaluate_raise(net):
    with pytest.raises(ValueError):
        snl.generate(0)
    with pytest.raises(ValueError):
        snl.generate(50, anchors="many")
    with pytest.raises(TypeError):
        snl.generate(50, colour="red")
    with pytest.raises(ValueError):
        snl.evaluate(net, np.zeros((4, 2)))
    with pytest.raises(ValueError):
        snl.crlb(snl.generate(50, seed=2), sigma=-2.0)


def test_interpreter_alive_after_every_error(net):
    # Everything above ran in this process; it still solves.
    assert snl.solve(net, algorithm="mm", max_iter=3, tol=0).summary["iterations"] == 3
