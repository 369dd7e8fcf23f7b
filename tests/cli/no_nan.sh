#!/usr/bin/env bash
# No "nan" or "inf" (any case, as a whole word) in any text, JSON or CSV output
# meant for a person or a program: generate, info, solve with every algorithm,
# eval (with --crlb), experiment and consensus, on a small default network, on
# a degenerate one with truth (no sensor can be localized: no anchor
# measurement at all) and on the same without truth (and without sigma).
# Metrics over an empty set must be reported absent (n/a, null), not NaN.
# Also: solve's early warning and its iteration-cap message, generate's warning.
source "$(dirname "$0")/common.bash"
O="$T/out"; mkdir -p "$O"
run() {  # run NAME CMD...: stdout and stderr of CMD into $O/NAME.{out,err}; any exit status
  local name=$1; shift
  "$@" > "$O/$name.out" 2> "$O/$name.err" || echo "$name exited $?" >> "$O/exits.txt"
}
run gen_good "$SNL" generate -o "$T/good.h5" --sensors 60 --seed 3
run gen_bad "$SNL" generate -o "$T/bad.h5" --sensors 30 --avg-degree 2 --anchors corners --anchor-radius 0.001 \
  --localizable no --seed 4
"$PY" - "$T/bad.h5" "$T/notruth.h5" <<'PY'
import shutil, sys, h5py
shutil.copy(sys.argv[1], sys.argv[2])
with h5py.File(sys.argv[2], "r+") as f:
    for k in ("truth", "sigma", "localizability"):
        if k in f: del f[k]
PY
algs=$("$SNL" solve --help | sed -n 's/.*--algorithm TEXT=[a-z-]* *\([a-z|-]*\).*/\1/p' | tr '|' ' ')
[ -n "$algs" ] || algs="relaxation mm pipeline bb pm async async-exact"
for net in good bad notruth; do
  run "info_$net" "$SNL" info "$T/$net.h5" --json "$O/info_$net.json"
  for alg in $algs; do
    launch=("$SNL"); [ "$alg" = pipeline ] && launch=(mpi 2 "$SNL")  # one MPI run; singletons are quicker
    iters=(--max-iter 30)
    case $alg in sdp|esdp|edm) iters=() ;; esac  # solved once: --max-iter is refused
    case $alg in esdp-dist) iters+=(--stop papers) ;; esac  # ADMM: only the relative-improvement rule
    if [ ${#iters[@]} -eq 0 ] && [ $net != good ]; then
      # No anchor measurement: the SDP relaxations refuse it (exit 4); their message must still be clean.
      set +e; "${launch[@]}" solve "$T/$net.h5" -o "$T/r_${net}_$alg.h5" --algorithm "$alg" --progress-seconds 0 \
        --json "$O/solve_${net}_$alg.json" > "$O/solve_${net}_$alg.out" 2> "$O/solve_${net}_$alg.err"; set -e
      continue
    fi
    run "solve_${net}_$alg" "${launch[@]}" solve "$T/$net.h5" -o "$T/r_${net}_$alg.h5" --algorithm "$alg" \
      "${iters[@]}" --progress-seconds 0 --json "$O/solve_${net}_$alg.json"
    [ -e "$T/r_${net}_$alg.h5" ] || fail "solve --algorithm $alg on $net wrote no result: $(cat "$O/solve_${net}_$alg.err")"
    run "eval_${net}_$alg" "$SNL" eval "$T/$net.h5" "$T/r_${net}_$alg.h5" --crlb --json "$O/eval_${net}_$alg.json"
  done
done
for net in good bad; do
  run "exp_$net" "$SNL" experiment "$T/$net.h5" -o "$O/exp_$net.csv" --trajectory "$O/traj_$net.csv" \
    --sigmas 0.01 --trials 2 --budget 40 --relax-max-iter 30
done
run cgen "$SNL" consensus generate -o "$T/c.h5" --nodes 20 --hamiltonian --seed 2
for m in newton-tree newton-path subgradient incremental central; do
  launch=("$SNL"); [ "$m" = newton-tree ] && launch=(mpi 2 "$SNL")
  run "csolve_$m" "${launch[@]}" consensus solve "$T/c.h5" -o "$T/c_$m.h5" --method "$m" --max-iter 20 \
    --progress-seconds 0 --json "$O/csolve_$m.json"
done
ls "$O"/*.json > /dev/null || fail "no JSON output was written"
# The same runs say early when they cannot succeed, with the numbers and the remedy.
grep -q "warning: most sensors (30 of 30) cannot be localized.*--avg-degree" "$O/solve_bad_pipeline.err" \
  || fail "solve on a network with no localizable sensor did not warn before iterating"
grep -q "the mm-accel phase stopped at --max-iter 30 before its stopping rule (--stop gradient, --tol 1e-05) was met.*raise --max-iter" \
  "$O/solve_good_pipeline.err" || fail "solve stopped by --max-iter did not say how far from --tol"
! grep -q "most sensors" "$O/solve_good_pipeline.err" || fail "solve warned on a localizable network"
grep -q "warning: .*30 of 30 sensors (100%) cannot be localized" "$O/gen_bad.err" \
  || fail "generate wrote a non-localizable network without a warning"
# Every output file, as a person or a program reads it.
bad=$(grep -ilwE 'nan|inf|infinity' "$O"/* || true)
if [ -n "$bad" ]; then
  for f in $bad; do echo "--- $f"; grep -iwE 'nan|inf|infinity' "$f" | head -5; done >&2
  fail "nan/inf in: $(echo $bad | sed "s|$O/||g")"
fi
