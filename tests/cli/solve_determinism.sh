#!/usr/bin/env bash
# snl solve gives bit-identical positions on 1, 2 and 3 ranks (all synchronous algorithms).
source "$(dirname "$0")/common.bash"
"$SNL" generate -o "$T/net.h5" --sensors 400 --avg-degree 8 --sigma 0.05 --seed 11 -q
for alg in relaxation mm pipeline bb pm async async-exact; do
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
