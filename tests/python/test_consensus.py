"""snl.consensus from Python: problems from arrays (own samples per node),
x against independent numpy optima, bit-identical to `snl consensus solve`
(1 and 2 ranks), bad inputs raise and leave the interpreter alive."""
import os
import subprocess
import sys

import numpy as np
import pytest

import snl
from conftest import clean_env, mpiexec, run, same_bits, snl_exe

HERE = os.path.dirname(os.path.abspath(__file__))


def own_samples(n=60, q=3, per=8, seed=3, logistic=True):
    """A ring plus chords over n nodes, and per samples of each node."""
    rng = np.random.default_rng(seed)
    edges = [(i, (i + 1) % n) for i in range(n)] + [(i, (i + 7) % n) for i in range(0, n, 5)]
    a = rng.standard_normal((n * per, q))
    w = rng.standard_normal(q)
    if logistic:
        y = np.where(a @ w + 0.5 * rng.standard_normal(n * per) > 0, 1.0, -1.0)
    else:
        y = a @ w + 0.1 * rng.standard_normal(n * per)
    owner = np.repeat(np.arange(n), per)
    return np.array(edges), a, y, owner


def newton_logistic(a, y, lam):
    """sum_s log(1 + exp(-y a.x)) + lam/2 x.x, by numpy Newton to rounding level."""
    x = np.zeros(a.shape[1])
    for _ in range(100):
        m = -y * (a @ x)
        s = 1 / (1 + np.exp(-m))
        g = a.T @ (s * -y) + lam * x
        h = (a * (s * (1 - s))[:, None]).T @ a + lam * np.eye(a.shape[1])
        dx = np.linalg.solve(h, -g)
        x += dx
        if np.abs(dx).max() < 1e-15:
            break
    return x


def test_logistic_on_own_samples_reaches_the_numpy_optimum():
    edges, a, y, owner = own_samples()
    p = snl.consensus.Problem(edges, "logistic", features=a, labels=y, owner=owner, lam=0.7)
    r = snl.consensus.solve(p)
    assert r.summary["converged"] and r.summary["dual"] == "cg"
    assert r.x.shape == (60, 3)
    assert np.abs(r.x - newton_logistic(a, y, 0.7)).max() < 1e-8
    assert r.summary["iterations"] <= 15


def test_least_squares_reaches_the_normal_equations_and_every_method_runs():
    edges, a, y, owner = own_samples(logistic=False)
    p = snl.consensus.Problem(edges, "least_squares", features=a, labels=y, owner=owner, lam=0.5)
    xs = np.linalg.solve(2 * a.T @ a + 0.5 * np.eye(3), 2 * a.T @ y)
    for kw in ({}, {"dual": "exact"}, {"dual": "splitting", "dual_max_iter": 100000}, {"method": "central"}):
        r = snl.consensus.solve(p, **kw)
        assert np.abs(r.x - xs).max() < 1e-8, kw
    r = snl.consensus.solve(p, method="subgradient", max_iter=50)
    assert r.summary["iterations"] == 50 and len(r.history["F"]) == 51


def test_bit_identical_to_the_cli(tmp_path):
    import h5py
    prob = tmp_path / "p.h5"
    run([snl_exe(), "consensus", "generate", "-o", str(prob), "--nodes", "150", "--family", "logistic",
         "--dim", "3", "--seed", "5", "-q"])
    g = snl.consensus.generate(150, family="logistic", dim=3, seed=5)
    f = snl.consensus.Problem.from_file(prob)
    assert same_bits(g.features, f.features) and same_bits(g.edges, f.edges)
    for np_ in (1, 2):
        out = tmp_path / f"r{np_}.h5"
        run((mpiexec(np_) if np_ > 1 else []) + [snl_exe(), "consensus", "solve", str(prob), "-o", str(out), "-q"])
        with h5py.File(out, "r") as h:
            cli = h["x"][()]
        assert same_bits(snl.consensus.solve(f).x, cli), np_
        assert same_bits(snl.consensus.solve(g).x, cli), np_


def test_two_ranks_bit_identical_to_one(tmp_path):
    pytest.importorskip("mpi4py")
    edges, a, y, owner = own_samples()
    np.savez(tmp_path / "in.npz", edges=edges, a=a, y=y, owner=owner)
    one = snl.consensus.solve(snl.consensus.Problem(edges, "logistic", features=a, labels=y, owner=owner)).x
    out = tmp_path / "out.npz"
    p = subprocess.run(mpiexec(2) + [sys.executable, os.path.join(HERE, "consensus_mpi_script.py"),
                                     str(tmp_path / "in.npz"), str(out)],
                       capture_output=True, text=True, timeout=300, env=clean_env())
    assert p.returncode == 0, p.stderr
    for rank in (0, 1):
        d = np.load(f"{out}.{rank}.npz")
        assert int(d["ranks"]) == 2
        assert same_bits(d["root"], one) and same_bits(d["all"], one), f"rank {rank}"


@pytest.mark.parametrize("change, word", [
    (lambda d: d.update(features=np.where(np.arange(d["features"].size).reshape(d["features"].shape) == 4,
                                          np.nan, d["features"])), "features"),
    (lambda d: d.update(labels=d["labels"] * 0.5), "labels"),
    (lambda d: d.update(owner=np.where(np.arange(d["owner"].size) == 3, -1, d["owner"])), "owner"),
    (lambda d: d.update(edges=np.vstack([d["edges"], [[2, 2]]])), "self-loop"),
    (lambda d: d.update(edges=d["edges"][:, :1]), "edges"),
    (lambda d: d.update(features=d["features"][:-1]), "labels"),
    (lambda d: d.update(lam=0.0), "lambda"),
])
def test_bad_problems_raise_value_error(change, word):
    edges, a, y, owner = own_samples()
    d = {"edges": edges, "features": a, "labels": y, "owner": owner, "lam": 1.0}
    change(d)
    with pytest.raises(ValueError, match=word):
        snl.consensus.Problem(d.pop("edges"), "logistic", **d)


def test_bad_options_raise_and_a_raising_callback_stops_the_run():
    edges, a, y, owner = own_samples()
    p = snl.consensus.Problem(edges, "logistic", features=a, labels=y, owner=owner)
    with pytest.raises(ValueError, match="--step"):
        snl.consensus.solve(p, method="subgradient", step="armijo")
    with pytest.raises(ValueError, match="--damping"):
        snl.consensus.solve(p, damping=0.5)
    with pytest.raises(TypeError, match="unknown option"):
        snl.consensus.solve(p, dual_tolerance=1e-9)
    seen = []

    def progress(rec):
        seen.append(rec["iteration"])
        if rec["iteration"] == 2:
            raise RuntimeError("enough")

    with pytest.raises(RuntimeError, match="enough"):
        snl.consensus.solve(p, progress=progress)
    assert seen == [0, 1, 2]
    assert snl.consensus.solve(p).summary["converged"]  # the interpreter and MPI still work
