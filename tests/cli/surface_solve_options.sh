#!/usr/bin/env bash
# snl solve's --init FILE, --grad-tol and --strict do what they say, checked on
# the values (numpy / h5py, from the shared spec algorithms.md):
#  - --init FILE --max-iter 0 returns the file's positions exactly, for every
#    algorithm, on 1 and 2 ranks; a plain file with only `positions` works;
#  - --init FILE --max-iter 1 continues from those positions: the relaxation's
#    first step is x0 - grad f_hat(x0)/L and BB's is x0 - grad f(x0)/L
#    (L = 2 delta_max + max |A_i|), and the recorded gradient norm at
#    iteration 1 is ||grad f_hat(x0)|| resp. ||grad f(x0)||;
#  - --grad-tol G stops at the first iteration whose gradient norm is <= G
#    (the same run without it has all earlier norms > G), says so in the
#    JSON, and a G below every norm changes nothing;
#  - --strict refuses a network with unlocalizable sensors (non-zero exit, one
#    error naming --strict, an existing output untouched, on 1 and 2 ranks)
#    and accepts a localizable one with the same positions as without it.
source "$(dirname "$0")/common.bash"
"$SNL" generate -o "$T/net.h5" --sensors 50 --avg-degree 7 --sigma 0.05 --seed 13 -q
"$SNL" solve "$T/net.h5" -o "$T/start.h5" --algorithm relaxation --max-iter 15 --tol 0 -q

# --- --init FILE ---
"$PY" - "$T/plain.h5" <<'EOF'
import sys, h5py, numpy as np
with h5py.File(sys.argv[1], "w") as f:
    f["positions"] = np.random.default_rng(5).uniform(-0.2, 1.2, (50, 2))
EOF
for init in start plain; do
  for alg in relaxation mm pipeline bb pm async; do
    for np in 1 2; do
      mpi $np "$SNL" solve "$T/net.h5" -o "$T/i0.h5" --algorithm $alg --init "$T/$init.h5" --max-iter 0 -q \
        || fail "--init $init.h5 --max-iter 0 refused for $alg on $np ranks"
      h5diff -q "$T/i0.h5" "$T/$init.h5" /positions \
        || fail "--init $init.h5 --max-iter 0: $alg on $np ranks did not return the initial positions"
    done
  done
done

step_check() {  # step_check ALG RESULT: one step from plain.h5's positions, computed here
  "$PY" - "$T/net.h5" "$T/plain.h5" "$2" "$1" <<'EOF' || fail "--init --max-iter 1: $1's first step is not from the file's positions"
import sys, h5py, numpy as np
N, x0 = h5py.File(sys.argv[1], "r"), h5py.File(sys.argv[2], "r")["positions"][:]
R, alg = h5py.File(sys.argv[3], "r"), sys.argv[4]
A, se, sr, ae, ar = (N[k][:] for k in ("anchors", "sensor_edges", "sensor_ranges", "anchor_edges", "anchor_ranges"))
n = len(x0)
g = np.zeros_like(x0)
def add(i, z, r):  # e(z, r) for f_hat; the ML term (1 - r/|z|) z for f
    nz = np.linalg.norm(z, axis=1)
    c = np.maximum(0, 1 - r / nz) if alg == "relaxation" else 1 - r / nz
    np.add.at(g, i, c[:, None] * z)
add(se[:, 0], x0[se[:, 0]] - x0[se[:, 1]], sr)
add(se[:, 1], x0[se[:, 1]] - x0[se[:, 0]], sr)
add(ae[:, 0], x0[ae[:, 0]] - A[ae[:, 1]], ar)
L = 2 * np.bincount(se.ravel(), minlength=n).max() + np.bincount(ae[:, 0], minlength=n).max()
want = x0 - g / L
got = R["positions"][:]
gn = R["history/grad_norm"][:]
it = R["history/iteration"][:]
ok = np.abs(got - want).max() <= 1e-12 and abs(gn[it == 1][0] - np.linalg.norm(g)) <= 1e-10 * np.linalg.norm(g)
if not ok:
    print("  max |x - want| = %g; grad norm %r vs %r" % (np.abs(got - want).max(), gn[it == 1], np.linalg.norm(g)),
          file=sys.stderr)
sys.exit(0 if ok else 1)
EOF
}
for alg in relaxation bb; do
  for np in 1 2; do
    mpi $np "$SNL" solve "$T/net.h5" -o "$T/i1.h5" --algorithm $alg --init "$T/plain.h5" --max-iter 1 --tol 0 -q
    step_check $alg "$T/i1.h5"
  done
done

# --- --grad-tol ---
for alg in relaxation bb; do
  "$SNL" solve "$T/net.h5" -o "$T/g_base.h5" --algorithm $alg --max-iter 300 --tol 0 -q --json "$T/g_base.json"
  # A tolerance between two recorded norms, about a third of the way in.
  G=$("$PY" -c "
import sys, h5py, numpy as np
g = h5py.File(sys.argv[1])['history/grad_norm'][1:]
k = len(g) // 3
print(repr(float(np.min(g[:k + 1])) * (1 - 1e-9)))" "$T/g_base.h5")
  "$SNL" solve "$T/net.h5" -o "$T/g.h5" --algorithm $alg --max-iter 300 --tol 0 --grad-tol "$G" -q --json "$T/g.json"
  "$PY" - "$T/g_base.h5" "$T/g.h5" "$T/g.json" "$G" <<'EOF' || fail "--grad-tol $G did not stop $alg where its gradient norm first fell below it"
import json, sys, h5py, numpy as np
base, run, J, G = h5py.File(sys.argv[1]), h5py.File(sys.argv[2]), json.load(open(sys.argv[3])), float(sys.argv[4])
gb = base["history/grad_norm"][:]
first = int(np.argmax(gb[1:] <= G)) + 1  # record 0 is the start (no gradient)
assert gb[first] <= G and np.all(gb[1:first] > G)
gr = run["history/grad_norm"][:]
ok = (J["iterations"] == first and J["termination"] == "CONVERGENCE" and "gradient" in J["message"]
      and gr[-1] <= G and np.all(gr[1:-1] > G) and first < 300)
if not ok: print("  stopped at %r (%s: %s), expected %d; last norm %r" % (J["iterations"], J["termination"],
                 J["message"], first, gr[-1]), file=sys.stderr)
sys.exit(0 if ok else 1)
EOF
  "$SNL" solve "$T/net.h5" -o "$T/g_tiny.h5" --algorithm $alg --max-iter 300 --tol 0 --grad-tol 1e-300 -q
  h5diff -q "$T/g_tiny.h5" "$T/g_base.h5" /positions || fail "--grad-tol below every norm changed $alg's positions"
done

# --- --strict ---
"$SNL" generate -o "$T/bad.h5" --sensors 40 --avg-degree 3 --sigma 0.05 --seed 5 --localizable no -q
cp "$T/start.h5" "$T/keep.h5"
sum0=$(md5sum < "$T/keep.h5")
for np in 1 2; do
  rc=0
  mpi $np "$SNL" solve "$T/bad.h5" -o "$T/keep.h5" --strict --json "$T/strict.json" -q 2> "$T/err" || rc=$?
  [ $rc -ne 0 ] || fail "--strict accepted a network with unlocalizable sensors on $np ranks"
  [ "$(grep -c 'snl: error:' "$T/err")" -eq 1 ] && grep -q -- '--strict' "$T/err" \
    || fail "--strict refusal on $np ranks: expected one error naming --strict, got: $(cat "$T/err")"
  [ "$(md5sum < "$T/keep.h5")" = "$sum0" ] || fail "--strict refusal clobbered the output on $np ranks"
  [ ! -e "$T/strict.json" ] || fail "--strict refusal wrote a JSON summary"
done
"$SNL" solve "$T/bad.h5" -o "$T/lax.h5" --max-iter 5 -q || fail "without --strict the same network must be solved"
for np in 1 2; do
  mpi $np "$SNL" solve "$T/net.h5" -o "$T/s.h5" --strict --max-iter 20 -q || fail "--strict refused a localizable network"
  "$SNL" solve "$T/net.h5" -o "$T/ns.h5" --max-iter 20 -q
  h5diff -q "$T/s.h5" "$T/ns.h5" /positions || fail "--strict changed the result of a localizable network"
done
echo "surface_solve_options: ok"
