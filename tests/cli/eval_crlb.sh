#!/usr/bin/env bash
# snl eval --crlb's per-sensor covariances (group crlb of the result file):
#  - crlb/covariance [n, p, p] and crlb/covered against numpy's dense inverse of
#    J restricted to the covered sensors, with the network's per-measurement
#    sigmas (w = 1/sigma_ij^2), on 1 and 2 ranks (identical files);
#  - the result file's own datasets are kept byte for byte; a second eval
#    replaces the group; --no-covariance leaves the file alone;
#  - --fim-at estimate on a network without truth: J at the result's positions;
#  - the edited copy cannot be made: one clear error, non-zero exit, the file untouched;
#  - no "nan" or "inf" in any text or JSON output;
#  - tools/plot_result.py draws the ellipses from the group.
source "$(dirname "$0")/common.bash"
"$SNL" generate -o "$T/net.h5" --sensors 60 --avg-degree 5 --anchors 8 --sigma 0.02 --seed 3 --localizable no -q
"$SNL" solve "$T/net.h5" -o "$T/res.h5" --algorithm relaxation --max-iter 30 --tol 0 -q
# Per-measurement sigmas: each range its own sigma in [0.01, 0.05].
"$PY" - "$T/net.h5" <<'PYEOF'
import sys, h5py, numpy as np
with h5py.File(sys.argv[1], "a") as f:
    r = np.random.default_rng(1)
    f["sensor_sigmas"] = r.uniform(0.01, 0.05, len(f["sensor_ranges"]))
    f["anchor_sigmas"] = r.uniform(0.01, 0.05, len(f["anchor_ranges"]))
PYEOF
cp "$T/res.h5" "$T/orig.h5"

check_cov() {  # check_cov NET RESULT JSON AT(truth|estimate)
  "$PY" - "$@" <<'PYEOF' || fail "crlb/covariance of $2 differs from the dense inverse"
import json, sys, h5py, numpy as np
net, res, js, at = sys.argv[1:5]
N, R, d = h5py.File(net, "r"), h5py.File(res, "r"), json.load(open(js))
A = N["anchors"][:]
x = N["truth"][:] if at == "truth" else R["positions"][:]
n, p = x.shape
cov, cv = R["crlb/covariance"][:], R["crlb/covered"][:]
assert cov.shape == (n, p, p) and cv.shape == (n,), (cov.shape, cv.shape)
part = np.flatnonzero(cv)
assert len(part) == d["crlb_sensors"] and sorted(d["crlb_outside"]) == list(np.flatnonzero(cv == 0))
assert 0 < len(part) < n, "the test wants a flexible part"
at_ = {int(i): k for k, i in enumerate(part)}
F = np.zeros((len(part) * p, len(part) * p))
ss = N["sensor_sigmas"][:] if "sensor_sigmas" in N else np.full(len(N["sensor_ranges"]), N["sigma"][()])
sa = N["anchor_sigmas"][:] if "anchor_sigmas" in N else np.full(len(N["anchor_ranges"]), N["sigma"][()])
for (i, j), s in zip(N["sensor_edges"][:], ss):
    if i in at_ and j in at_:
        u = (x[i] - x[j]) / np.linalg.norm(x[i] - x[j]); B = np.outer(u, u) / s ** 2
        a, b = at_[i] * p, at_[j] * p
        F[a:a+p, a:a+p] += B; F[b:b+p, b:b+p] += B; F[a:a+p, b:b+p] -= B; F[b:b+p, a:a+p] -= B
for (i, k), s in zip(N["anchor_edges"][:], sa):
    if i in at_:
        u = (x[i] - A[k]) / np.linalg.norm(x[i] - A[k]); a = at_[i] * p
        F[a:a+p, a:a+p] += np.outer(u, u) / s ** 2
inv = np.linalg.inv(F)
want = np.array([inv[k*p:k*p+p, k*p:k*p+p] for k in range(len(part))])
err = np.abs(cov[part] - want).max() / np.abs(want).max()
assert err < 1e-9, err
assert np.all(cov[cv == 0] == 0)
rm = np.sqrt(np.trace(inv) / len(part))
assert abs(d["crlb_rmse"] - rm) <= 1e-10 * rm, (d["crlb_rmse"], rm)
assert R["crlb"].attrs["at"] == at, R["crlb"].attrs["at"]
PYEOF
}
same_positions() {  # same_positions A B: positions and history byte for byte
  "$PY" - "$1" "$2" <<'PYEOF' || fail "eval --crlb changed the result file's own content"
import sys, h5py
a, b = h5py.File(sys.argv[1], "r"), h5py.File(sys.argv[2], "r")
assert a["positions"][()].tobytes() == b["positions"][()].tobytes()
for k in a["history"]:
    assert a["history"][k][()].tobytes() == b["history"][k][()].tobytes(), k
for k, v in a.attrs.items():
    assert str(b.attrs[k]) == str(v), k
PYEOF
}
nonan() { grep -Eiq '\bnan\b|\binf\b' "$@" && fail "nan/inf in $*: $(cat "$@")"; true; }

for np in 1 2; do
  cp "$T/orig.h5" "$T/res$np.h5"
  mpi $np "$SNL" eval "$T/net.h5" "$T/res$np.h5" --crlb --json "$T/ev$np.json" > "$T/ev$np.out"
  grep -q "per-measurement sigma" "$T/ev$np.out" || fail "eval did not say it used per-measurement sigmas: $(cat "$T/ev$np.out")"
  check_cov "$T/net.h5" "$T/res$np.h5" "$T/ev$np.json" truth
  same_positions "$T/orig.h5" "$T/res$np.h5"
  nonan "$T/ev$np.out" "$T/ev$np.json"
done
"$PY" -c "
import sys, h5py
a, b = h5py.File(sys.argv[1], 'r'), h5py.File(sys.argv[2], 'r')
sys.exit(0 if a['crlb/covariance'][()].tobytes() == b['crlb/covariance'][()].tobytes() else 1)" "$T/res1.h5" "$T/res2.h5" \
  || fail "covariances differ between 1 and 2 ranks"
# Again: the group is replaced, not duplicated.
"$SNL" eval "$T/net.h5" "$T/res1.h5" --crlb --json "$T/again.json" > /dev/null
check_cov "$T/net.h5" "$T/res1.h5" "$T/again.json" truth
# --no-covariance: the file is left alone.
cp "$T/orig.h5" "$T/nc.h5"
"$SNL" eval "$T/net.h5" "$T/nc.h5" --crlb --no-covariance > /dev/null
cmp -s "$T/orig.h5" "$T/nc.h5" || fail "--no-covariance changed the result file"

# --fim-at estimate on a network without truth (and the default picks it).
"$PY" - "$T/net.h5" "$T/nt.h5" <<'PYEOF'
import sys, h5py
with h5py.File(sys.argv[1], "r") as a, h5py.File(sys.argv[2], "w") as b:
    for k, v in a.attrs.items(): b.attrs[k] = v
    for k in a:
        if k not in ("truth", "localizability"): a.copy(k, b)
PYEOF
cp "$T/orig.h5" "$T/est.h5"
"$SNL" eval "$T/nt.h5" "$T/est.h5" --crlb --json "$T/est.json" > "$T/est.out"
grep -q "Fisher information at the estimate" "$T/est.out" || fail "eval without truth: $(cat "$T/est.out")"
check_cov "$T/nt.h5" "$T/est.h5" "$T/est.json" estimate
nonan "$T/est.out" "$T/est.json"

# The edited copy cannot be made (a directory is in its way): a clear error,
# non-zero exit, the result file untouched.
cp "$T/orig.h5" "$T/bad.h5" && mkdir "$T/bad.h5.crlb-tmp"
if "$SNL" eval "$T/net.h5" "$T/bad.h5" --crlb > "$T/bad.out" 2>&1; then fail "eval --crlb with a blocked copy succeeded"; fi
grep -q "cannot add the CRLB covariances" "$T/bad.out" || fail "no clear error: $(cat "$T/bad.out")"
cmp -s "$T/orig.h5" "$T/bad.h5" || fail "a failed eval changed the result file"
# tools/plot_result.py draws the ellipses from the group (and the crosses).
"$PY" "$(dirname "$0")/../../tools/plot_result.py" "$T/net.h5" "$T/res1.h5" -o "$T/map.png" > "$T/plot.out" \
  || fail "plot_result.py failed on a result with group crlb: $(cat "$T/plot.out")"
[ -s "$T/map.png" ] || fail "plot_result.py wrote no figure"
echo "eval_crlb: ok"
