"""snl.evaluate and snl.crlb against `snl eval` (--json, --crlb): the same numbers."""
import json

import h5py
import numpy as np
import pytest

import snl
from conftest import BENCH, run, same_bits, snl_exe


def test_evaluate_and_crlb_match_cli(tmp_path):
    g = tmp_path / "g.h5"
    net = snl.generate(200, seed=11)
    net.save(g)
    res = tmp_path / "r.h5"
    run([snl_exe(), "solve", str(g), "-o", str(res), "-q", "--max-iter", "100"])
    run([snl_exe(), "eval", str(g), str(res), "--crlb", "--json", str(tmp_path / "e.json")])
    cli = json.loads((tmp_path / "e.json").read_text())
    with h5py.File(res, "r") as f:
        x = f["positions"][()]
        cov_cli = f["crlb/covariance"][()]
        covered = f["crlb/covered"][()].astype(bool)
    ev = snl.evaluate(net, x)
    for key in ("rmse", "mpe", "rmse_localizable", "mpe_localizable", "ml_cost", "relaxed_cost"):
        assert ev[key] == cli[key], key
    # A result's positions and an array give the same evaluation.
    r = snl.solve(net, max_iter=100)
    assert same_bits(r.positions, x) and snl.evaluate(net, r)["rmse"] == ev["rmse"]
    assert snl.evaluate(net, x + 1e-3)["rmse"] != ev["rmse"]
    cov = snl.crlb(net)
    assert cov.shape == (net.n_sensors, 2, 2)
    assert same_bits(cov[covered], cov_cli[covered])
    assert np.isnan(cov[~covered]).all()
    rmse = np.sqrt(np.trace(cov[covered], axis1=1, axis2=2).sum() / covered.sum())
    assert rmse == pytest.approx(cli["crlb_rmse"], rel=1e-12)
    # Another sigma scales the bound.
    assert np.allclose(snl.crlb(net, sigma=2 * net.sigma)[covered], 4 * cov[covered])


def test_localizable_set_of_a_network_with_an_unanchored_sensor():
    net = snl.Network.from_file(BENCH)
    n = net.n_sensors
    # One more sensor, measured only by a sensor-sensor edge to... nothing: isolated.
    extra = snl.Network(anchors=net.anchors, n_sensors=n + 1, edges=net.edges + (net.edges >= n),
                        ranges=net.ranges, truth=np.vstack([net.truth, [[0.5, 0.5]]]))
    ev = snl.evaluate(extra, np.vstack([net.truth, [[0.5, 0.5]]]))
    assert not ev["localizable"][n] and ev["num_localizable"] == ev["localizable"].sum()
    assert ev["localizable"].sum() < n + 1
