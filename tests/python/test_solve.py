"""snl.solve from Python against `snl solve`: the same positions bit for bit,
the same option checks; callbacks; warm starts (snl.track)."""
import h5py
import numpy as np
import pytest

import snl
from conftest import BENCH, SOURCE, cli_positions, run, same_bits, snl_exe


def arrays_network(path):
    """The network of a file rebuilt from its arrays (edges over sensors and anchors)."""
    with h5py.File(path, "r") as f:
        n = int(f.attrs["num_sensors"])
        edges = np.concatenate([f["sensor_edges"][()], f["anchor_edges"][()] + [0, n]])
        ranges = np.concatenate([f["sensor_ranges"][()], f["anchor_ranges"][()]])
        truth = f["truth"][()] if "truth" in f else None
        return snl.Network(anchors=f["anchors"][()], n_sensors=n, edges=edges, ranges=ranges,
                           dim=int(f.attrs["dim"]), truth=truth)


def test_default_algorithm_is_the_clis():
    assert snl.DEFAULT_ALGORITHM == "dv-pipeline"
    assert snl.solve(snl.generate(30, seed=3), max_iter=5).summary["algorithm"] == snl.DEFAULT_ALGORITHM


@pytest.mark.parametrize("args", [[], ["--algorithm", "pipeline"], ["--algorithm", "mm", "--init", "random"]])
def test_benchmark_bit_identical_to_cli(tmp_path, args):
    cli = cli_positions(BENCH, tmp_path / "r.h5", *args)
    kw = {"algorithm": args[1]} if args else {}
    init = "random" if "--init" in args else None
    for net in (snl.Network.from_file(BENCH), arrays_network(BENCH)):
        r = snl.solve(net, init=init, **kw)
        assert same_bits(r.positions, cli)
    # The comparison can fail: one ulp off one coordinate is caught.
    bad = cli.copy()
    bad[7, 1] = np.nextafter(bad[7, 1], np.inf)
    assert not same_bits(r.positions, bad)


def test_generated_3d_bit_identical_to_cli(tmp_path):
    g = tmp_path / "g3.h5"
    run([snl_exe(), "generate", "--sensors", "300", "--dim", "3", "--seed", "7", "-o", str(g), "-q"])
    net = snl.generate(300, dim=3, seed=7)
    ref = snl.Network.from_file(g)
    for name in ("anchors", "sensor_edges", "sensor_ranges", "anchor_edges", "anchor_ranges", "truth"):
        assert same_bits(getattr(net, name), getattr(ref, name)), name
    cli = cli_positions(g, tmp_path / "r.h5", "--max-iter", "300")
    assert same_bits(snl.solve(net, max_iter=300).positions, cli)
    # Saved and read back: the same network, the same positions.
    net.save(tmp_path / "saved.h5")
    assert same_bits(cli_positions(tmp_path / "saved.h5", tmp_path / "r2.h5", "--max-iter", "300"), cli)


def test_options_as_keywords_match_cli(tmp_path):
    args = ["--algorithm", "pipeline", "--max-iter", "150", "--tol", "0", "--stop", "papers", "--seed", "5",
            "--partition", "metis", "--refine", "mm"]
    cli = cli_positions(BENCH, tmp_path / "r.h5", *args)
    r = snl.solve(snl.Network.from_file(BENCH), algorithm="pipeline", max_iter=150, tol=0, stop="papers", seed=5,
                  partition="metis", refine="mm")
    assert same_bits(r.positions, cli)
    assert r.summary["iterations"] == 300  # two phases of max_iter with tol 0
    assert not same_bits(snl.solve(snl.Network.from_file(BENCH), algorithm="pipeline", max_iter=150, tol=0,
                                   stop="papers", seed=5, partition="metis", refine="mm-accel").positions, cli)


def test_async_free_mode_and_target_cost_as_keywords():
    # Free mode is not reproducible across ranks, but serially a seed repeats
    # its bits; it reaches the relaxation's cost, and target_cost stops early.
    net = snl.Network.from_file(BENCH)
    a = snl.solve(net, algorithm="async", mode="free", max_iter=300, seed=3)
    b = snl.solve(net, algorithm="async", mode="free", max_iter=300, seed=3)
    assert same_bits(a.positions, b.positions)
    assert a.summary["free_epochs_fastest_rank"] == 300
    replay = snl.solve(net, algorithm="async", max_iter=300, seed=3)  # the replay: its own draws, as far
    assert not same_bits(a.positions, replay.positions)
    assert a.summary["relaxed_cost"] <= 1.05 * replay.summary["relaxed_cost"] < a.summary["initial_cost"] / 100
    relax = snl.solve(net, algorithm="relaxation", tol=1e-9, max_iter=20000)
    target = 2 * relax.summary["relaxed_cost"]
    t = snl.solve(net, algorithm="relaxation", max_iter=20000, tol=0, target_cost=target, straggler_delay=0.0)
    assert t.summary["iterations"] < 20000 and t.summary["relaxed_cost"] <= target


def test_summary_and_history():
    net = snl.Network.from_file(BENCH)
    r = snl.solve(net, algorithm="pipeline", max_iter=200)
    s, h = r.summary, r.history
    for key in ("termination", "iterations", "ml_cost", "relaxed_cost", "gap_certificate",
                "communications_per_sensor", "mpi_bytes", "solve_seconds", "rmse"):
        assert key in s, key
    assert np.isfinite(s["gap_certificate"])
    assert isinstance(h["cost"], np.ndarray) and len(h["cost"]) == len(h["phase"]) > 0
    assert h["total_iteration"][-1] == s["iterations"]
    assert set(h["phase"]) == {"relaxation", "mm-accel"}
    ev = snl.evaluate(net, r)
    assert ev["rmse"] == s["rmse"] and ev["ml_cost"] == s["ml_cost"]
    assert ev["localizable"].shape == (net.n_sensors,) and ev["localizable"].dtype == bool


def test_callback_stops_the_run():
    net = snl.Network.from_file(BENCH)
    seen = []

    def stop_at_5(rec):
        seen.append(rec["total_iteration"])
        return rec["total_iteration"] >= 5

    progress = []
    r = snl.solve(net, algorithm="mm", max_iter=1000, tol=0, history_every=1, callback=stop_at_5,
                  progress=progress.append)
    assert r.summary["termination"] == "USER_ABORT" or "ABORT" in r.summary["termination"].upper()
    assert r.summary["iterations"] == 5 and seen[-1] == 5
    assert len(progress) == len(seen) and progress[-1]["total_iteration"] == 5
    # Without the callback the same run goes on.
    assert snl.solve(net, algorithm="mm", max_iter=50, tol=0).summary["iterations"] == 50


def test_callback_exception_propagates():
    def boom(rec):
        raise RuntimeError("from the callback")

    with pytest.raises(RuntimeError, match="from the callback"):
        snl.solve(snl.Network.from_file(BENCH), algorithm="mm", max_iter=100, tol=0, callback=boom)


def test_track_is_solve_from_the_previous_positions():
    frames = [snl.generate(200, seed=1), snl.generate(200, seed=1, sigma=0.02)]
    rs = snl.track(frames, algorithm="mm-accel", max_iter=200)
    first = snl.solve(frames[0], algorithm="mm-accel", max_iter=200)
    second = snl.solve(frames[1], algorithm="mm-accel", max_iter=200, init=first.positions)
    assert same_bits(rs[0].positions, first.positions) and same_bits(rs[1].positions, second.positions)
    cold = snl.solve(frames[1], algorithm="mm-accel", max_iter=200)
    assert not same_bits(cold.positions, second.positions)
    assert rs[1].summary["start"] == "positions" and cold.summary["start"] == "random"
    # warm_algorithm: the frames after the first.
    rw = snl.track(frames, algorithm="mm-accel", warm_algorithm="ml-agd", max_iter=200)
    assert same_bits(rw[0].positions, first.positions)
    assert rw[1].summary["algorithm"] == "ml-agd"
    assert same_bits(rw[1].positions, snl.solve(frames[1], algorithm="ml-agd", max_iter=200, init=first).positions)
    # warm_tol: the --tol of the frames after the first.
    rt = snl.track(frames, algorithm="mm-accel", warm_algorithm="ml-agd", warm_tol=1e-2, max_iter=200)
    assert same_bits(rt[0].positions, first.positions)
    loose = snl.solve(frames[1], algorithm="ml-agd", max_iter=200, tol=1e-2, init=first)
    assert same_bits(rt[1].positions, loose.positions)
    assert rt[1].summary["iterations"] < rw[1].summary["iterations"]


def test_init_file_matches_cli(tmp_path):
    net = snl.Network.from_file(BENCH)
    x0 = net.truth + 0.01
    with h5py.File(tmp_path / "x0.h5", "w") as f:
        f["positions"] = x0
    cli = cli_positions(BENCH, tmp_path / "r.h5", "--algorithm", "mm", "--init", str(tmp_path / "x0.h5"))
    assert same_bits(snl.solve(net, algorithm="mm", init=x0).positions, cli)


def test_csv_tables_are_the_imported_network(tmp_path):
    t = lambda f: str(__import__("os").path.join(SOURCE, "inputs", "text", f))  # noqa: E731
    csv = snl.Network.from_csv(t("edges.csv"), t("anchor_edges.txt"), t("anchors.csv"), truth=t("truth.csv"),
                               sigma=0.01)
    h5 = snl.Network.from_file(f"{SOURCE}/inputs/net10_s0.01.h5")
    for name in ("anchors", "sensor_edges", "sensor_ranges", "anchor_edges", "anchor_ranges", "truth"):
        assert same_bits(getattr(csv, name), getattr(h5, name)), name
    cli = cli_positions(f"{SOURCE}/inputs/net10_s0.01.h5", tmp_path / "r.h5")
    assert same_bits(snl.solve(csv).positions, cli)
    assert same_bits(snl.Network.from_file(t("edges.csv"), anchor_edges=t("anchor_edges.txt"),
                                           anchors=t("anchors.csv")).anchors, h5.anchors)
    with pytest.raises(ValueError, match="self-loop"):
        bad = tmp_path / "bad.csv"
        bad.write_text("i,j,range\n0,1,0.36\n4,4,0.2\n")
        snl.Network.from_csv(bad, t("anchor_edges.txt"), t("anchors.csv"))


def test_not_a_network_is_a_type_error():
    with pytest.raises(TypeError):
        snl.solve("net.h5")
    with pytest.raises(ValueError):
        snl.Network(anchors=[[0, 0]], n_sensors=2.5, edges=[[0, 2]], ranges=[1.0])


def test_gil_released_while_solving():
    import threading
    import time
    net = snl.generate(2000, seed=5)
    count, done = [0], threading.Event()

    def spin():
        while not done.is_set():
            count[0] += 1

    t = threading.Thread(target=spin)
    t.start()
    try:
        c0, t0 = count[0], time.perf_counter()
        time.sleep(0.2)  # the thread alone: its rate
        rate = (count[0] - c0) / (time.perf_counter() - t0)
        before = count[0]
        # No record before the end (history_every past max_iter): no Python runs inside the solve.
        r = snl.solve(net, algorithm="mm", max_iter=10000, tol=0, history_every=10**6)
        during = count[0] - before
    finally:
        done.set()
        t.join()
    seconds = r.summary["solve_seconds"]
    assert seconds > 0.3
    # Held, the GIL would let the thread run for a switch interval or two (5 ms each), not the solve's time.
    assert during > 0.1 * rate * seconds, (during, rate, seconds)


def test_checkpoint_and_restart_resume_bit_for_bit(tmp_path):
    net = snl.Network.from_file(BENCH)
    ck = str(tmp_path / "ck.h5")
    opts = dict(algorithm="mm", max_iter=200, tol=0)
    full = snl.solve(net, **opts)
    stopped = snl.solve(net, checkpoint=ck, checkpoint_every=50, callback=lambda r: r["total_iteration"] >= 120,
                        **opts)
    assert stopped.summary["iterations"] == 120 and not same_bits(stopped.positions, full.positions)
    resumed = snl.solve(net, restart=ck, **opts)  # from iteration 100
    assert resumed.summary["start"] == "restart" and resumed.summary["iterations"] == 200
    assert same_bits(resumed.positions, full.positions)
    with pytest.raises(ValueError, match="max-iter"):
        snl.solve(net, restart=ck, algorithm="mm", max_iter=300, tol=0)
