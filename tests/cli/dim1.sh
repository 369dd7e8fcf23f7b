#!/usr/bin/env bash
# One-dimensional networks end to end:
#  - generate --dim 1 --topology star (003 Fig. 2), solve with the relaxation,
#    eval --global-opt: the true gap f* - f_hat is at most the eq. (22)
#    certificate, f* <= f(x_hat), and the eq. (23) bound is 1/2 sum r^2;
#  - a random 1-D network: eval --crlb gives a finite bound, 1 and 2 ranks agree;
#  - import of one-column anchors, export of one coordinate;
#  - bad input: --global-opt on a 2-D network, --topology star without --dim 1,
#    a dim-1 file with 2-column anchors: one clear error, non-zero exit, nothing written.
source "$(dirname "$0")/common.bash"
"$SNL" generate --dim 1 --topology star --sensors 1 --sigma 0.25 --seed 4 -o "$T/star.h5" -q
"$SNL" solve "$T/star.h5" --algorithm relaxation --tol 1e-12 --max-iter 100000 -o "$T/res.h5" -q
"$SNL" eval "$T/star.h5" "$T/res.h5" --global-opt --json "$T/e.json" > "$T/e.txt"
grep -q "exact global ML optimum f\* = " "$T/e.txt" || fail "eval --global-opt printed no optimum"
"$PY" - "$T/e.json" "$T/star.h5" <<'PYEOF' || fail "star: gap, certificate or bound inconsistent"
import json, sys, h5py, numpy as np
e, n = json.load(open(sys.argv[1])), h5py.File(sys.argv[2], "r")
assert n.attrs["dim"] == 1 and n["anchors"].shape == (3, 1), n["anchors"].shape
r = n["anchor_ranges"][:]
assert abs(e["apriori_bound"] - 0.5 * (r * r).sum()) < 1e-12, e
assert e["global_patterns"] == 8, e
assert e["global_ml_optimum"] <= e["ml_cost"] + 1e-12, e
assert 0 <= e["true_gap"] <= e["gap_certificate"] + 1e-12, e
# f* by a dense grid
x = np.linspace(-1, 8, 900001)
f = 0.5 * ((np.abs(x[:, None] - n["anchors"][:, 0][None, :]) - r) ** 2).sum(1)
assert abs(f.min() - e["global_ml_optimum"]) < 1e-8, (f.min(), e)
PYEOF

"$SNL" generate --dim 1 --sensors 40 --seed 2 --sigma 0.01 -o "$T/line.h5" -q
for np in 1 2; do
  mpi $np "$SNL" solve "$T/line.h5" --algorithm pipeline --max-iter 200 --tol 0 -o "$T/line$np.h5" -q
done
"$PY" -c 'import sys,h5py,numpy as np; a,b=(h5py.File(f)["positions"][:] for f in sys.argv[1:]); assert a.shape==(40,1) and np.array_equal(a,b)' \
  "$T/line1.h5" "$T/line2.h5" || fail "1-D pipeline differs between 1 and 2 ranks"
"$SNL" eval "$T/line.h5" "$T/line1.h5" --crlb --no-covariance --json "$T/c.json" > /dev/null
"$PY" -c 'import json,sys; d=json.load(open(sys.argv[1])); assert d["crlb_defined"] and 0 < d["crlb_rmse"] < 1, d' "$T/c.json" ||
  fail "1-D CRLB not defined"

# snl import of one-column anchors, and export of one coordinate.
printf "0\n10\n" > "$T/a.csv"; printf "0,1,2.1\n1,2,3.9\n" > "$T/se.csv"; printf "0,0,2.0\n2,1,4.1\n" > "$T/ae.csv"
"$SNL" import --sensor-edges "$T/se.csv" --anchor-edges "$T/ae.csv" --anchors "$T/a.csv" -o "$T/imp.h5" | grep -q "p=1" ||
  fail "import of one-column anchors"
"$SNL" solve "$T/imp.h5" --algorithm relaxation -o "$T/imp_res.h5" -q
"$SNL" export "$T/imp_res.h5" -o "$T/imp.csv" && [ "$(head -1 "$T/imp.csv")" = "sensor,x" ] || fail "1-D export header"

expect_error() {  # expect_error FRAGMENT FILE-THAT-MUST-NOT-EXIST CMD...
  local frag=$1 out=$2; shift 2
  if "$@" > "$T/err.txt" 2>&1; then fail "accepted: $*"; fi
  grep -qF -- "$frag" "$T/err.txt" || fail "no '$frag' in: $(cat "$T/err.txt")"
  [ ! -e "$out" ] || fail "$out written by a failing command: $*"
}
"$SNL" generate --sensors 20 --seed 1 -o "$T/plane.h5" -q
"$SNL" solve "$T/plane.h5" --algorithm relaxation --max-iter 20 -o "$T/plane_res.h5" -q
expect_error "one-dimensional networks (dim 1), got dim 2" "$T/g.json" \
  mpi 2 "$SNL" eval "$T/plane.h5" "$T/plane_res.h5" --global-opt --json "$T/g.json"
expect_error "more than the limit 30" "$T/g2.json" \
  "$SNL" eval "$T/line.h5" "$T/line1.h5" --global-opt --global-opt-max-terms 30 --json "$T/g2.json"
expect_error "give --dim 1" "$T/s2.h5" "$SNL" generate --topology star --sensors 1 -o "$T/s2.h5"
cp "$T/star.h5" "$T/bad.h5"
"$PY" -c 'import sys,h5py,numpy as np; f=h5py.File(sys.argv[1],"a"); del f["anchors"]; f["anchors"]=np.zeros((3,2))' "$T/bad.h5"
expect_error "dataset 'anchors' has shape [3, 2], expected [m, 1]" "$T/bad_res.h5" \
  "$SNL" solve "$T/bad.h5" --algorithm relaxation -o "$T/bad_res.h5"
echo "dim1: ok"
