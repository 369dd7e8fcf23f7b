#!/usr/bin/env bash
# snl eval's numbers against an independent computation (numpy, written from
# the shared spec algorithms.md) on the files themselves:
#  - ML cost f and f_hat with the 1/2, the sum of nonconvex terms of the edges
#    inside their disk (003 eq. 22), the a-priori bound (eq. 23), RMSE and MPE
#    per sensor (1/n), and with --crlb the Cramér-Rao bound sqrt(tr(J^-1)/n),
#    J at the true positions with the network's sigma, and with --sigma;
#  - the same numbers on 1 and 2 ranks;
#  - on a network with a flexible part, --crlb bounds the anchored rigid part
#    and lists the sensors outside it (text and JSON), exit 0.
source "$(dirname "$0")/common.bash"
"$SNL" generate -o "$T/net.h5" --sensors 40 --avg-degree 6 --sigma 0.03 --seed 8 -q
"$SNL" solve "$T/net.h5" -o "$T/res.h5" --algorithm relaxation --max-iter 40 --tol 0 -q

check() {  # check NET RESULT JSON SIGMA: every number of the JSON against numpy
  "$PY" - "$@" <<'EOF' || fail "eval $1 $2: values differ from the direct computation"
import json, sys
import h5py, numpy as np
net, res, js, sigma = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4]
N, R, J = h5py.File(net, "r"), h5py.File(res, "r"), json.load(open(js))
x, t, A = R["positions"][:], N["truth"][:], N["anchors"][:]
se, sr = N["sensor_edges"][:], N["sensor_ranges"][:]
ae, ar = N["anchor_edges"][:], N["anchor_ranges"][:]
n, p = t.shape
assert len(np.unique(np.sort(se, axis=1), axis=0)) == len(se), "test needs a network without duplicate rows"
z = np.concatenate([np.linalg.norm(x[se[:, 0]] - x[se[:, 1]], axis=1),
                    np.linalg.norm(x[ae[:, 0]] - A[ae[:, 1]], axis=1)])
r = np.concatenate([sr, ar])
q = 0.5 * (z - r) ** 2
want = {"ml_cost": q.sum(), "relaxed_cost": q[z > r].sum(), "gap_certificate": q[z < r].sum(),
        "apriori_bound": 0.5 * (r ** 2).sum(),
        "rmse": np.sqrt(((x - t) ** 2).sum() / n), "mpe": np.linalg.norm(x - t, axis=1).sum() / n}
if sigma != "none":
    s = float(sigma) if sigma != "file" else float(N["sigma"][()])
    F = np.zeros((n * p, n * p))
    def add(i, j, u):
        P = np.outer(u, u) / s ** 2
        F[i*p:i*p+p, i*p:i*p+p] += P
        if j >= 0:
            F[j*p:j*p+p, j*p:j*p+p] += P
            F[i*p:i*p+p, j*p:j*p+p] -= P
            F[j*p:j*p+p, i*p:i*p+p] -= P
    for i, j in se:
        d = t[i] - t[j]; add(i, j, d / np.linalg.norm(d))
    for i, k in ae:
        d = t[i] - A[k]; add(i, -1, d / np.linalg.norm(d))
    assert np.linalg.matrix_rank(F) == n * p, "test network must be rigid"
    want["crlb_rmse"] = np.sqrt(np.trace(np.linalg.inv(F)) / n)
    assert J["crlb_defined"] is True
bad = [(k, J.get(k), v) for k, v in want.items() if not abs(J.get(k, np.inf) - v) <= 1e-10 * max(1.0, abs(v))]
for b in bad: print("  %s: eval %r, direct %r" % b, file=sys.stderr)
sys.exit(1 if bad else 0)
EOF
}

for np in 1 2; do
  mpi $np "$SNL" eval "$T/net.h5" "$T/res.h5" --crlb --json "$T/ev$np.json" > /dev/null
  check "$T/net.h5" "$T/res.h5" "$T/ev$np.json" file
done
"$SNL" eval "$T/net.h5" "$T/res.h5" --crlb --sigma 0.2 --json "$T/ev_s.json" > /dev/null
check "$T/net.h5" "$T/res.h5" "$T/ev_s.json" 0.2
"$SNL" eval "$T/net.h5" "$T/res.h5" --json "$T/ev_nc.json" > /dev/null
check "$T/net.h5" "$T/res.h5" "$T/ev_nc.json" none
grep -q crlb "$T/ev_nc.json" && fail "eval without --crlb reported a CRLB"

# Not rigid: two sensors, each with 3 measurements, joined by one range. s0 is
# pinned by two anchors; s1, s0 and s1's two anchors lie on the line y = 2, so
# s1 can move across it to first order. Every sensor passes the counting
# tests; only the Fisher information sees it.
"$PY" - "$T/flex.h5" <<'EOF'
import sys, h5py, numpy as np
with h5py.File(sys.argv[1], "w") as f:
    f.attrs["format"] = "snl-network"; f.attrs["version"] = 1; f.attrs["dim"] = 2; f.attrs["num_sensors"] = 2
    A = np.array([[0., 0.], [1., 0.], [0., 1.], [0., 2.], [2., 2.]])
    t = np.array([[0.3, 2.], [1., 2.]])
    f["anchors"] = A; f["truth"] = t; f["sigma"] = 0.01
    f["sensor_edges"] = np.array([[0, 1]], dtype=np.int64)
    f["sensor_ranges"] = np.array([np.linalg.norm(t[0] - t[1])])
    ae = np.array([[0, 0], [0, 1], [1, 3], [1, 4]], dtype=np.int64)
    f["anchor_edges"] = ae
    f["anchor_ranges"] = np.linalg.norm(t[ae[:, 0]] - A[ae[:, 1]], axis=1)
    f.create_dataset("positions", data=t)  # doubles as a result file
EOF
"$SNL" eval "$T/flex.h5" "$T/flex.h5" --crlb --json "$T/flex.json" > "$T/flex.out" || fail "eval --crlb on a flexible network failed"
# The bound covers the rigid part (s0: J = u1 u1^T + u2 u2^T over sigma^2) and
# lists s1 outside it; nothing is printed as nan.
grep -Eq "Cramer-Rao bound RMSE_CRLB = [0-9.e-]+ over the 1 sensor" "$T/flex.out" || fail "eval --crlb on a flexible network: $(cat "$T/flex.out")"
grep -q "1 sensor(s) outside it, no finite bound: 1" "$T/flex.out" || fail "eval --crlb did not list the flexible sensor: $(cat "$T/flex.out")"
grep -qi nan "$T/flex.out" && fail "eval printed nan: $(cat "$T/flex.out")"
"$PY" -c "
import json, sys, numpy as np
d = json.load(open(sys.argv[1]))
A = np.array([[0., 0.], [1., 0.]]); t = np.array([0.3, 2.])
J = sum(np.outer(u, u) for u in [(t - a) / np.linalg.norm(t - a) for a in A]) / 0.01 ** 2
want = np.sqrt(np.trace(np.linalg.inv(J)))
ok = d['crlb_defined'] is True and d['crlb_sensors'] == 1 and d['crlb_outside'] == [1] and abs(d['crlb_rmse'] - want) <= 1e-12 * want
sys.exit(0 if ok else 1)" \
  "$T/flex.json" || fail "eval --crlb JSON on a flexible network: $(cat "$T/flex.json")"
# RMSE/MPE over the localizable sensors: s3 has a single measurement (fewer
# than p+1), so it is left out; s0..s2 each measure three anchors.
"$PY" - "$T/few.h5" <<'EOF'
import sys, h5py, numpy as np
with h5py.File(sys.argv[1], "w") as f:
    f.attrs["format"] = "snl-network"; f.attrs["version"] = 1; f.attrs["dim"] = 2; f.attrs["num_sensors"] = 4
    A = np.array([[0., 0.], [1., 0.], [0., 1.], [1., 1.]])
    t = np.array([[0.2, 0.3], [0.7, 0.4], [0.5, 0.8], [0.9, 0.9]])
    f["anchors"] = A; f["truth"] = t; f["sigma"] = 0.01
    se = np.array([[0, 1], [1, 2], [2, 3]], dtype=np.int64)
    f["sensor_edges"] = se; f["sensor_ranges"] = np.linalg.norm(t[se[:, 0]] - t[se[:, 1]], axis=1)
    ae = np.array([[0, 0], [0, 1], [0, 2], [1, 1], [1, 3], [2, 2], [2, 3]], dtype=np.int64)
    f["anchor_edges"] = ae; f["anchor_ranges"] = np.linalg.norm(t[ae[:, 0]] - A[ae[:, 1]], axis=1)
    # Errors |(0.06, 0.08)| = 0.1, 0, 0.2 and sqrt(2) for s3.
    f.create_dataset("positions", data=t + np.array([[0.06, 0.08], [0, 0], [0, 0.2], [1, 1]]))
EOF
"$SNL" eval "$T/few.h5" "$T/few.h5" --json "$T/few.json" > /dev/null
"$PY" -c "
import json, math, sys
d = json.load(open(sys.argv[1]))
want = {'rmse_localizable': math.sqrt((0.01 + 0.04) / 3), 'mpe_localizable': (0.1 + 0.2) / 3,
        'rmse': math.sqrt((0.01 + 0.04 + 2) / 4), 'mpe': (0.1 + 0.2 + math.sqrt(2)) / 4}
bad = {k: (d.get(k), v) for k, v in want.items() if not abs(d.get(k, math.inf) - v) <= 1e-12}
print(bad or '', file=sys.stderr)
sys.exit(1 if bad else 0)" "$T/few.json" || fail "eval: metrics over the localizable sensors are wrong"
echo "surface_eval: ok"
