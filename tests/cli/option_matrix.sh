#!/usr/bin/env bash
# Options only some algorithms honour (--grad-tol, --temporal-block, --bb-rounds,
# --esdp-rho, --mode), against every distributed algorithm. The expected capabilities are
# written out here, from what the methods do (a gradient norm: relaxation and both
# BBs; several iterations per pass: relaxation and MM; consensus rounds: both BBs;
# an ADMM penalty: esdp-dist; unsynchronised activations: async and async-exact),
# independently of the registry
# (the centralized relaxations, which refuse all three, are tested in sdp_relaxations.sh):
#  - refused pair: exit 2 with one "snl: error:" line naming the option, on 1 and
#    2 ranks, an existing output left untouched and no JSON written; the
#    option at its default value is accepted;
#  - accepted pair: the option has an effect (--grad-tol large stops earlier,
#    --temporal-block 4 records at pass ends with the same positions,
#    --bb-rounds changes the communications, --esdp-rho changes the positions,
#    --mode free runs the free mode: its summary says so).
source "$(dirname "$0")/common.bash"
"$SNL" generate -o "$T/net.h5" --sensors 150 --avg-degree 7 --sigma 0.05 --seed 11 -q
"$SNL" solve "$T/net.h5" -o "$T/keep.h5" --max-iter 5 --tol 0 -q
sum0=$(md5sum < "$T/keep.h5")

ALGS="relaxation mm mm-accel pipeline bb bb-calafiore pm async async-exact esdp-dist"
declare -A HONOURED=(
  [grad-tol]="relaxation pipeline bb bb-calafiore"
  [temporal-block]="relaxation mm pipeline"
  [bb-rounds]="bb bb-calafiore"
  [esdp-rho]="esdp-dist"
  [mode]="async async-exact"
)
declare -A VALUE=([grad-tol]=1e6 [temporal-block]=4 [bb-rounds]=5 [esdp-rho]=3 [mode]=free)
declare -A DEFAULT=([grad-tol]=0 [temporal-block]=1 [bb-rounds]=20 [esdp-rho]=1 [mode]=replay)

json() { "$PY" -c "import json,sys; print(json.load(open(sys.argv[1]))[sys.argv[2]])" "$@"; }
history_len() { "$PY" -c "import h5py,sys; print(len(h5py.File(sys.argv[1])['history/iteration']))" "$1"; }
solve() {  # solve NAME ALG ARGS...: a short run, JSON summary in $T/NAME.json
  local name=$1 alg=$2; shift 2
  "$SNL" solve "$T/net.h5" -o "$T/$name.h5" --algorithm "$alg" --json "$T/$name.json" -q "$@" \
    || fail "$name: $alg $* was refused"
}

# The effect of an accepted option, against the same run without it.
check_effect() {  # check_effect OPTION ALG
  local opt=$1 alg=$2 base="base.$alg" with="$1.$2"
  case $opt in
    grad-tol)
      solve "$base" "$alg" --max-iter 200 --tol 0
      solve "$with" "$alg" --max-iter 200 --tol 0 --grad-tol "${VALUE[$opt]}"
      [ "$(json "$T/$with.json" iterations)" -lt "$(json "$T/$base.json" iterations)" ] \
        || fail "--grad-tol large did not stop $alg earlier" ;;
    temporal-block)
      solve "$base" "$alg" --max-iter 40 --tol 0
      solve "$with" "$alg" --max-iter 40 --tol 0 --temporal-block "${VALUE[$opt]}"
      h5diff -q "$T/$base.h5" "$T/$with.h5" /positions || fail "--temporal-block changed the positions of $alg"
      [ "$(history_len "$T/$with.h5")" -lt "$(history_len "$T/$base.h5")" ] \
        || fail "--temporal-block 4 did not record $alg at pass ends only" ;;
    bb-rounds)
      solve "$base" "$alg" --max-iter 20 --tol 0
      solve "$with" "$alg" --max-iter 20 --tol 0 --bb-rounds "${VALUE[$opt]}"
      [ "$(json "$T/$with.json" communications_per_sensor)" != "$(json "$T/$base.json" communications_per_sensor)" ] \
        || fail "--bb-rounds did not change the communications of $alg" ;;
    esdp-rho)
      solve "$base" "$alg" --max-iter 20 --tol 0
      solve "$with" "$alg" --max-iter 20 --tol 0 --esdp-rho "${VALUE[$opt]}"
      ! h5diff -q "$T/$base.h5" "$T/$with.h5" /positions > /dev/null || fail "--esdp-rho did not change the positions of $alg" ;;
    mode)
      solve "$with" "$alg" --max-iter 5 --tol 0 --mode "${VALUE[$opt]}"
      [ "$(json "$T/$with.json" async_mode)" = free ] || fail "--mode free did not run $alg in free mode" ;;
  esac
}

# A refused pair: usage error on every rank count, nothing written; the default is accepted.
check_refused() {  # check_refused OPTION ALG
  local opt=$1 alg=$2
  for np in 1 2; do
    rm -f "$T/refused.json"
    set +e
    if [ $np = 1 ]; then run=("$SNL"); else run=("$MPIEXEC" "$MPIEXEC_NUMPROC_FLAG" $np --oversubscribe "$SNL"); fi
    "${run[@]}" solve "$T/net.h5" -o "$T/keep.h5" --algorithm "$alg" --max-iter 5 --json "$T/refused.json" \
      -q "--$opt" "${VALUE[$opt]}" > "$T/out" 2> "$T/err"
    rc=$?
    set -e
    [ $rc -eq 2 ] || { cat "$T/err"; fail "--$opt with $alg on $np ranks: exit status $rc, expected 2"; }
    [ "$(grep -c '^snl: error: ' "$T/err")" -eq 1 ] || { cat "$T/err"; fail "--$opt with $alg: expected one error line"; }
    grep -q -- "--$opt is not honoured by --algorithm $alg" "$T/err" || { cat "$T/err"; fail "--$opt with $alg: unclear message"; }
    [ "$(md5sum < "$T/keep.h5")" = "$sum0" ] || fail "--$opt with $alg on $np ranks: existing output was modified"
    [ ! -e "$T/refused.json" ] || fail "--$opt with $alg on $np ranks: wrote a JSON summary"
  done
  solve "default.$opt.$alg" "$alg" --max-iter 5 "--$opt" "${DEFAULT[$opt]}"
}

refused=0 accepted=0
for opt in grad-tol temporal-block bb-rounds esdp-rho mode; do
  for alg in $ALGS; do
    if [[ " ${HONOURED[$opt]} " == *" $alg "* ]]; then
      check_effect "$opt" "$alg"
      accepted=$((accepted + 1))
    else
      check_refused "$opt" "$alg"
      refused=$((refused + 1))
    fi
  done
done
echo "option_matrix: $accepted option/algorithm pairs accepted with an effect, $refused refused"
