"""Tracking moving sensors across frames: each frame's solve warm-started from
the previous frame's positions, against a cold start (docs/python.md).

Sensors take a Gaussian random walk (reflected at the region's edges), anchors
stay fixed; each frame's measurements are the pairs within the link radius,
ranged with Gaussian noise. Prints, per frame, the time and RMSE of the warm
and the cold solve; with --warm-tol, also of a cold solve at that tolerance,
so that the warm start is not credited with what the looser tolerance gives.
  python3 tracking.py [--sensors N] [--frames F] [--step S] [--warm-algorithm A] [--warm-tol T] [--seed K]
Under mpirun every rank runs the same script; rank 0 prints."""
import argparse
import time

import numpy as np
from scipy.spatial import cKDTree

import snl


def measure(truth, anchors, radius, sigma, rng):
    """A network of the sensors at `truth`: every pair within `radius`, ranges with noise sigma."""
    n = len(truth)
    ss = cKDTree(truth).query_pairs(radius, output_type="ndarray")
    sa = [(i, n + k) for k, nb in enumerate(cKDTree(truth).query_ball_point(anchors, radius)) for i in nb]
    edges = np.concatenate([ss.reshape(-1, 2), np.array(sa, dtype=np.int64).reshape(-1, 2)])
    pts = np.vstack([truth, anchors])
    d = np.linalg.norm(pts[edges[:, 0]] - pts[edges[:, 1]], axis=1)
    ranges = np.abs(d + sigma * rng.standard_normal(len(d)))
    return snl.Network(anchors=anchors, n_sensors=n, edges=edges, ranges=ranges, sigmas=sigma, truth=truth)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sensors", type=int, default=2000)
    ap.add_argument("--frames", type=int, default=10)
    ap.add_argument("--step", type=float, default=0.002, help="random-walk standard deviation per frame")
    ap.add_argument("--warm-algorithm", default="ml-agd", help="the warm frames' method (cold: the default)")
    ap.add_argument("--warm-tol", type=float, default=None,
                    help="--tol of the warm frames (default: the solver's; a frame starting near its answer "
                         "can stop at a looser tolerance with the same RMSE)")
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    root = snl.rank() == 0
    # Frame 0's geometry, radius and noise are the generator's (snl generate's defaults).
    base = snl.generate(a.sensors, seed=a.seed)
    radius = float(np.sqrt(np.max(np.sum((base.truth[base.sensor_edges[:, 0]] -
                                          base.truth[base.sensor_edges[:, 1]]) ** 2, axis=1))))
    rng = np.random.default_rng(a.seed)
    truth, anchors, sigma = base.truth.copy(), base.anchors, base.sigma
    side = float(anchors.max())  # the region [0, side]^2: its corners are anchors
    if root:
        print(f"# {a.sensors} sensors, {len(anchors)} anchors, radius {radius:.4g}, sigma {sigma}, "
              f"step {a.step}, {snl.size()} ranks; warm: {a.warm_algorithm} from the last frame"
              f"{'' if a.warm_tol is None else f' (tol {a.warm_tol})'}, "
              f"cold: {snl.DEFAULT_ALGORITHM} from its own start")
        print(f"{'frame':>5} {'warm_s':>8} {'warm_iter':>9} {'warm_rmse':>10} {'cold_s':>8} {'cold_iter':>9} "
              f"{'cold_rmse':>10}" + ("" if a.warm_tol is None else
                                      f" {'coldT_s':>8} {'coldT_iter':>10} {'coldT_rmse':>10}"))
    prev = None
    rows = []
    for t in range(a.frames):
        if t > 0:
            walked = truth + a.step * rng.standard_normal(truth.shape)
            truth = side - np.abs(side - np.abs(walked))  # reflected into [0, side]
        net = measure(truth, anchors, radius, sigma, rng)
        t0 = time.perf_counter()
        cold = snl.solve(net)
        t1 = time.perf_counter()
        if prev is None:
            warm, t2 = cold, t1  # frame 0: nothing to start from
        else:
            warm = snl.solve(net, algorithm=a.warm_algorithm, init=prev,
                             **({} if a.warm_tol is None else {"tol": a.warm_tol}))
            t2 = time.perf_counter()
        prev = warm
        row = (t, t2 - t1 if t else t1 - t0, warm.summary["iterations"], warm.summary["rmse"], t1 - t0,
               cold.summary["iterations"], cold.summary["rmse"])
        if a.warm_tol is not None:  # the cold solve at the warm frames' tolerance
            t3 = time.perf_counter()
            cold_t = snl.solve(net, tol=a.warm_tol)
            row += (time.perf_counter() - t3, cold_t.summary["iterations"], cold_t.summary["rmse"])
        rows.append(row)
        if root:
            print(f"{row[0]:5d} {row[1]:8.4f} {row[2]:9d} {row[3]:10.6f} {row[4]:8.4f} {row[5]:9d} {row[6]:10.6f}"
                  + ("" if len(row) == 7 else f" {row[7]:8.4f} {row[8]:10d} {row[9]:10.6f}"))
    if root and len(rows) > 1:
        w = np.array(rows[1:])
        print(f"# frames 1..{a.frames - 1} mean: warm {w[:, 1].mean():.4f} s, rmse {w[:, 3].mean():.6f}; "
              f"cold {w[:, 4].mean():.4f} s, rmse {w[:, 6].mean():.6f}; "
              f"warm/cold time {w[:, 1].mean() / w[:, 4].mean():.3f}"
              + ("" if a.warm_tol is None else
                 f"; cold at tol {a.warm_tol}: {w[:, 7].mean():.4f} s, rmse {w[:, 9].mean():.6f}, "
                 f"warm/cold time {w[:, 1].mean() / w[:, 7].mean():.3f}"))


if __name__ == "__main__":
    main()
