#!/usr/bin/env bash
# snl solve gives bit-identical positions on 1, 2 and 3 ranks (all synchronous algorithms).
source "$(dirname "$0")/common.bash"
"$SNL" generate -o "$T/net.h5" --sensors 400 --avg-degree 8 --sigma 0.05 --seed 11 -q
for alg in relaxation mm mm-accel ml-agd pipeline bb pm async async-exact; do
  for np in 1 2 3; do
    mpi $np "$SNL" solve "$T/net.h5" -o "$T/$alg.$np.h5" --algorithm $alg --max-iter 150 --tol 0 -q \
      --json "$T/$alg.$np.json"
  done
  for np in 2 3; do
    h5diff "$T/$alg.1.h5" "$T/$alg.$np.h5" /positions || fail "$alg: positions differ between 1 and $np ranks"
  done
  grep -q '"iterations": 150' "$T/$alg.1.json" || [ $alg = pipeline ] || fail "$alg: --tol 0 must run exactly --max-iter"
done
grep -q '"iterations": 300' "$T/pipeline.1.json" || fail "pipeline: two phases of 150"
# The pipeline with the accelerated refinement, and the gradient stopping rule
# (tested every 10 iterations, summed exactly): the same positions and the
# same stopping iteration on 1, 2 and 3 ranks.
# dv-pipeline (the default) with its distance-vector start and all three phases, to its stopping rule.
for case in "refine --algorithm pipeline --refine mm-accel --max-iter 150 --tol 0" \
            "gstop --algorithm pipeline --refine mm-accel --stop gradient --tol 1e-3" \
            "gstopacc --algorithm mm-accel --stop gradient --tol 1e-4" "dv --smooth-iter 40 --settle-iter 60" \
            "dvstart --algorithm mm --init dv --max-iter 50 --tol 0"; do
  set -- $case; name=$1; shift
  for np in 1 2 3; do
    mpi $np "$SNL" solve "$T/net.h5" -o "$T/$name.$np.h5" "$@" -q --json "$T/$name.$np.json"
  done
  for np in 2 3; do
    h5diff "$T/$name.1.h5" "$T/$name.$np.h5" /positions || fail "$name: positions differ between 1 and $np ranks"
    [ "$(grep '"iterations"' "$T/$name.1.json")" = "$(grep '"iterations"' "$T/$name.$np.json")" ] \
      || fail "$name: stopping iteration differs between 1 and $np ranks"
  done
done
grep -q '"converged": true' "$T/gstop.1.json" || fail "--stop gradient --tol 1e-3: the pipeline did not converge"
grep -q '"converged": true' "$T/dv.1.json" || fail "dv-pipeline did not converge"
grep -q '"start": "dv"' "$T/dv.1.json" || fail "dv-pipeline did not take the distance-vector start"
grep -q '"start": "dv"' "$T/dvstart.1.json" || fail "--init dv was not taken"
grep -q 'relative gradient' "$T/gstop.1.json" || fail "--stop gradient: the message does not name the rule"
