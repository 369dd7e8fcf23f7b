#!/usr/bin/env bash
# Weighted ML, the Huber loss and the generator's noise models end to end:
# --noise multiplicative writes per-range sigmas, NLOS outliers are flagged at
# about the asked fraction; --weights/--loss give the same positions on 1 and
# 2 ranks, and a checkpoint resumes; bad sigmas and bad --weights/--loss strings end in one clear error
# with the output untouched.
source "$(dirname "$0")/common.bash"
"$SNL" generate -o "$T/net.h5" --sensors 80 --avg-degree 8 --sigma 0.05 --seed 3 -q --noise multiplicative \
  --nlos-fraction 0.2 --nlos-bias 0.3
"$PY" - "$T/net.h5" <<'PY'
import sys, h5py, numpy as np
f = h5py.File(sys.argv[1], "r")
X, A = f["truth"][()], f["anchors"][()]
se, ae = f["sensor_edges"][()], f["anchor_edges"][()]
d = np.linalg.norm(X[se[:, 0]] - X[se[:, 1]], axis=1)
s = f["sensor_sigmas"][()]
floor = 0.01 * max(d.max(), np.linalg.norm(X[ae[:, 0]] - A[ae[:, 1]], axis=1).max())
assert np.allclose(s, 0.05 * np.maximum(d, floor)), "sensor sigmas are not sigma * distance"
assert f["anchor_sigmas"].shape == f["anchor_ranges"].shape
nl = f["sensor_nlos"][()]
assert 0.1 < nl.mean() < 0.3, nl.mean()
bias = f["sensor_ranges"][()] - d
assert bias[nl == 1].mean() > 0.1 and abs(bias[nl == 0].mean()) < 0.02, "NLOS bias not where flagged"
PY
for opts in "--weights file --loss huber:0.05" "--weights multiplicative:0.05 --algorithm mm"; do
  # shellcheck disable=SC2086
  mpi 1 "$SNL" solve "$T/net.h5" -o "$T/a.h5" --max-iter 30 --tol 0 $opts -q
  # shellcheck disable=SC2086
  mpi 2 "$SNL" solve "$T/net.h5" -o "$T/b.h5" --max-iter 30 --tol 0 $opts -q
  "$PY" -c "import h5py,sys,numpy as np; a,b=(h5py.File(f)['positions'][()] for f in sys.argv[1:]); sys.exit(0 if np.array_equal(a,b) else 1)" \
    "$T/a.h5" "$T/b.h5" || fail "$opts: 1 and 2 ranks differ"
done
# A checkpoint of a Huber, weighted pipeline resumes bit for bit on 2 ranks, and only with the same --loss.
"$SNL" solve "$T/net.h5" -o "$T/full.h5" --loss huber:0.05 --max-iter 60 --tol 0 -q
"$SNL" solve "$T/net.h5" -o "$T/part.h5" --loss huber:0.05 --max-iter 60 --tol 0 -q --checkpoint "$T/ck.h5" \
  --checkpoint-every 40
mpi 2 "$SNL" solve "$T/net.h5" -o "$T/res.h5" --loss huber:0.05 --max-iter 60 --tol 0 -q --restart "$T/ck.h5"
"$PY" -c "import h5py,sys,numpy as np; a,b=(h5py.File(f)['positions'][()] for f in sys.argv[1:]); sys.exit(0 if np.array_equal(a,b) else 1)" \
  "$T/full.h5" "$T/res.h5" || fail "Huber restart differs"
if "$SNL" solve "$T/net.h5" -o "$T/res.h5" --max-iter 60 --tol 0 -q --restart "$T/ck.h5" 2> "$T/err"; then
  fail "restart with another --loss accepted"
fi
grep -q "loss" "$T/err" || fail "restart refusal does not name --loss"
# Bad sigmas in the file (negative, zero, NaN, wrong length), --weights file
# without sigmas, bad option strings: one error, a non-zero exit, output untouched.
"$SNL" generate -o "$T/plain.h5" --sensors 40 --seed 2 -q
"$SNL" solve "$T/plain.h5" -o "$T/keep.h5" --max-iter 5 -q
sum0=$(md5sum < "$T/keep.h5")
"$PY" - "$T/net.h5" "$T" <<'PY'
import sys, shutil, h5py, numpy as np
src, out = sys.argv[1], sys.argv[2]
for name, fn in [("neg", lambda s: -s), ("zero", lambda s: 0 * s), ("nan", lambda s: s * np.nan),
                 ("short", lambda s: s[:-1])]:
    shutil.copy(src, f"{out}/bad_{name}.h5")
    with h5py.File(f"{out}/bad_{name}.h5", "r+") as f:
        s = fn(f["sensor_sigmas"][()])
        del f["sensor_sigmas"]
        f["sensor_sigmas"] = s
PY
check_refused() {  # NAME NP ARGS...
  local name=$1 np=$2; shift 2
  set +e
  mpi "$np" "$SNL" solve "$@" -o "$T/keep.h5" --max-iter 5 -q > /dev/null 2> "$T/err"; local rc=$?
  set -e
  [ $rc -ne 0 ] && [ $rc -lt 128 ] || fail "$name: exit status $rc"
  [ "$(grep -c '^snl: error: ' "$T/err")" -eq 1 ] || { cat "$T/err"; fail "$name: expected exactly one error message"; }
  [ "$(md5sum < "$T/keep.h5")" = "$sum0" ] || fail "$name: existing output was modified"
}
for b in neg zero nan short; do check_refused "sigmas $b" 2 "$T/bad_$b.h5"; done
check_refused "file weights without sigmas" 2 "$T/plain.h5" --weights file
grep -q "no sensor_sigmas" "$T/err" || fail "missing sigmas not named"
for bad in "--weights bogus" "--weights multiplicative:0" "--weights multiplicative:x" "--loss huber" \
           "--loss huber:-1" "--loss l1"; do
  # shellcheck disable=SC2086
  check_refused "$bad" 2 "$T/plain.h5" $bad
done
set +e
"$SNL" generate -o "$T/g.h5" --sensors 20 --noise laplace -q 2> "$T/err"; rc=$?
set -e
[ $rc -ne 0 ] && grep -q "bad --noise" "$T/err" && [ ! -e "$T/g.h5" ] || fail "bad --noise accepted"
echo "weights: ok"
