"""The tour of docs/python.md: a network from arrays, a solve, its summary and
history, evaluation, the Cramer-Rao bound, a callback that stops a run.
  PYTHONPATH=build-py/python /usr/bin/python3 python/examples/tour.py > docs/data/python/tour.txt"""
import os

import numpy as np

import snl

root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
# Four anchors at the corners, three sensors; edges over sensors 0..2 and anchors 3..6.
anchors = np.array([[0, 0], [1, 0], [0, 1], [1, 1]], dtype=float)
truth = np.array([[0.3, 0.4], [0.7, 0.6], [0.5, 0.2]])
edges = np.array([[0, 1], [0, 2], [1, 2]] + [[i, 3 + k] for i in range(3) for k in range(4)])
pts = np.vstack([truth, anchors])
noise = 0.01 * np.random.default_rng(1).standard_normal(len(edges))
ranges = np.abs(np.linalg.norm(pts[edges[:, 0]] - pts[edges[:, 1]], axis=1) + noise)
net = snl.Network(anchors=anchors, n_sensors=3, edges=edges, ranges=ranges, sigmas=0.01, truth=truth)
r = snl.solve(net)
print("small network:", net)
print("  default algorithm:", snl.DEFAULT_ALGORITHM, "->", r)
print("  positions:", np.array2string(r.positions, precision=4).replace("\n", ""))
print(f"  RMSE {r.summary['rmse']:.6f}")

bench = snl.Network.from_file(os.path.join(root, "inputs", "benchmarks", "test10-500.h5"))
r = snl.solve(bench, algorithm="pipeline")
s = r.summary
print("test10-500:", bench)
print(f"  pipeline: {s['termination']} after {s['iterations']} iterations, RMSE {s['rmse']:.6f}, "
      f"ML cost {s['ml_cost']:.6f}, gap certificate {s['gap_certificate']:.6g}, "
      f"{s['communications_per_sensor']:.0f} messages per sensor, {s['solve_seconds']:.3f} s")
print("  history columns:", ", ".join(r.history), f"({len(r.history['cost'])} records)")
ev = snl.evaluate(bench, r)
print(f"  evaluate: RMSE {ev['rmse']:.6f}, MPE {ev['mpe']:.6f}, localizable {ev['localizable'].sum()} of "
      f"{bench.n_sensors}")

g = snl.generate(500, seed=4)
cov = snl.crlb(g)
print("generated:", g, f"sigma {g.sigma}")
print(f"  CRLB: covariances {cov.shape}, RMSE bound {np.sqrt(np.nanmean(np.trace(cov, axis1=1, axis2=2))):.6f}")
r = snl.solve(g)
print(f"  solve: RMSE {r.summary['rmse']:.6f}")

stopped = snl.solve(g, algorithm="mm", tol=0, max_iter=10000, callback=lambda rec: rec["total_iteration"] >= 100)
print("  callback stop at 100:", stopped.summary["termination"], stopped.summary["iterations"], "iterations")
