#!/usr/bin/env bash
# How many gradient evaluations (halo exchanges) limited-memory BFGS would
# need, against ml-agd's iterations, to bring the ML cost from dv-pipeline's
# settled point (--smooth-iter 200 relaxation iterations from the
# distance-vector start, then --settle-iter 200 of mm-accel) down to each
# cost ml-agd records on its way to its stopping rule (docs/performance.md,
# "What is left"). ml-agd runs in snl (NP ranks); L-BFGS is SciPy's L-BFGS-B
# (no bounds, M corrections, its Moré-Thuente line search) on the same cost,
# 1/2 sum (|x_i - x_j| - d_ij)^2 over the sensor and anchor ranges, in numpy
# on one process: a probe of the iteration count, not a timing.
# Needs Debian's python3-scipy, python3-h5py and python3-numpy (/usr/bin/python3).
#   NP=2 WORK=/tmp/lbp bench/lbfgs_probe.sh > docs/data/quality/lbfgs_probe.txt
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
SNL=${SNL:-$ROOT/build/bin/snl}
NP=${NP:-2}
M=${M:-10}
WORK=${WORK:-$(mktemp -d /tmp/snl_lbp.XXXXXX)}
NETS=${NETS:-"100000:1 100000:2 1000000:1"}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
mkdir -p "$WORK"
echo "# lbfgs_probe: $(date -u +%Y-%m-%dT%H:%MZ) $(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo '?') np=$NP m=$M"
echo "| sensors | seed | ml-agd iterations | ML cost reached | L-BFGS iterations to reach it | L-BFGS gradient evaluations | evaluations / ml-agd iterations |"
echo "|---|---|---|---|---|---|---|"
for ns in $NETS; do
  n=${ns%%:*} s=${ns##*:}
  net=$WORK/net_${n}_$s.h5
  [ -f "$net" ] || "$SNL" generate -o "$net" --sensors "$n" --seed "$s" -q
  mpirun -np "$NP" "$SNL" solve "$net" -o "$WORK/smooth.h5" -q --algorithm relaxation --init dv --max-iter 200 --tol 0
  mpirun -np "$NP" "$SNL" solve "$net" -o "$WORK/settled.h5" -q --algorithm mm-accel --init "$WORK/smooth.h5" \
    --max-iter 200 --tol 0
  mpirun -np "$NP" "$SNL" solve "$net" -o "$WORK/agd.h5" -q --algorithm ml-agd --init "$WORK/settled.h5" \
    --history-every 50
  /usr/bin/python3 - "$net" "$WORK/settled.h5" "$WORK/agd.h5" "$n" "$s" "$M" <<'PY'
import sys
import h5py
import numpy as np
import scipy.optimize as so

net, start, agd, n, s, m = sys.argv[1:7]
f = h5py.File(net, "r")
E, R = f["sensor_edges"][...], f["sensor_ranges"][...]
AE, AR, A = f["anchor_edges"][...], f["anchor_ranges"][...], f["anchors"][...]
x0 = h5py.File(start, "r")["positions"][...]
N, p = x0.shape
i, j, ai, aa = E[:, 0], E[:, 1], AE[:, 0], AE[:, 1]
h = h5py.File(agd, "r")["history"]
marks = [(int(k), c) for k, c in zip(h["iteration"][...], h["ml_cost"][...]) if k > 0]


def cost_grad(z):
    x = z.reshape(N, p)
    dx = x[i] - x[j]
    nr = np.sqrt((dx * dx).sum(1))
    r = nr - R
    da = x[ai] - A[aa]
    na = np.sqrt((da * da).sum(1))
    ra = na - AR
    gd = (r / np.maximum(nr, 1e-300))[:, None] * dx
    ga = (ra / np.maximum(na, 1e-300))[:, None] * da
    g = np.empty_like(x)
    for c in range(p):
        g[:, c] = np.bincount(i, gd[:, c], N) - np.bincount(j, gd[:, c], N) + np.bincount(ai, ga[:, c], N)
    return 0.5 * (r @ r) + 0.5 * (ra @ ra), g.ravel()


evals, last, reached = [0], [0.0], []  # reached: (iterations, evaluations) at each accepted iterate


def counted(z):
    evals[0] += 1
    out = cost_grad(z)
    last[0] = out[0]
    return out


class Reached(Exception):
    pass


def each_iterate(_):
    reached.append((len(reached) + 1, evals[0], last[0]))
    if last[0] <= marks[-1][1]:
        raise Reached  # ml-agd's final cost


try:
    so.minimize(counted, x0.ravel(), jac=True, method="L-BFGS-B", callback=each_iterate,
                options=dict(maxcor=int(m), maxiter=4 * marks[-1][0], gtol=0, ftol=0, maxfun=8 * marks[-1][0]))
except Reached:
    pass
for k, c in marks:
    hit = next((r for r in reached if r[2] <= c), None)
    its, ev = (hit[0], hit[1]) if hit else ("not reached", "-")
    ratio = f"{ev / k:.2f}" if hit else "-"
    print(f"| {n} | {s} | {k} | {c:.10f} | {its} | {ev} | {ratio} |", flush=True)
PY
done
