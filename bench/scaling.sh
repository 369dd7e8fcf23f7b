#!/usr/bin/env bash
# End-to-end benchmark: STREAM triad, then for each size generate
# the network, and solve it with the relaxation and with MM (ITERS iterations,
# --tol 0, history only at the end so that the iteration phase is pure) under
# mpirun -np 1 and -np 2 (strong scaling), plus weak scaling at 1M sensors per
# rank. Each solve is bracketed by two STREAM readings on its ranks (its
# bound). Prints ONE table (docs/performance.md explains the columns); keep
# a run as docs/data/perf/results-<date>-<name>.txt with $WORK/records.jsonl
# beside it, and add a row to docs/data/perf/README.md.
#
#   bench/scaling.sh                          # sizes 1M and 10M, 1000 iterations
#   SIZES="1000000" ITERS=200 bench/scaling.sh
# Environment: BIN (default build/bin), WORK (scratch dir, default
# /tmp/snl-scaling), SIZES, RANKS ("1 2"), ITERS, PARTITION (metis|block),
# ALGS ("relaxation mm"), WEAK (1: weak-scaling runs, default 1), KEEP (1: keep files),
# BLOCK (--temporal-block: iterations per pass over memory, default 1), GEN
# (snl generate options; default none: the generator's defaults, docs/generator.md;
# GEN="--avg-degree 6 --sigma 0.01 --side 1 --anchors corners" gives the networks
# of the records before 2026-12-01).
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
BIN=${BIN:-$here/build/bin}
WORK=${WORK:-/tmp/snl-scaling}
SIZES=${SIZES:-"1000000 10000000"}
RANKS=${RANKS:-"1 2"}
ITERS=${ITERS:-1000}
PARTITION=${PARTITION:-metis}
ALGS=${ALGS:-"relaxation mm"}
WEAK=${WEAK:-1}
BLOCK=${BLOCK:-1}
GEN=${GEN:-}
export OMPI_ALLOW_RUN_AS_ROOT=${OMPI_ALLOW_RUN_AS_ROOT:-1} OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=${OMPI_ALLOW_RUN_AS_ROOT_CONFIRM:-1}
mkdir -p "$WORK"
rec="$WORK/records.jsonl"
: >"$rec"
log() { echo "[scaling] $*" >&2; }

# Memory bandwidth of the whole machine, measured now (best of 20 triads).
stream1=$(mpirun -np 1 "$BIN/stream_triad" 40000000 20 | awk '{print $2}')
streamN=$(mpirun -np "$(nproc)" "$BIN/stream_triad" 40000000 20 | awk '{print $2}')
log "STREAM triad: 1 rank $stream1 GB/s, $(nproc) ranks $streamN GB/s"
# stream_def: the yardstick of these readings (bench/stream_triad.cpp: non-temporal
# stores, 24 bytes per element); records without it hold plain-store readings.
echo "{\"stream\": 1, \"stream_def\": \"nt_24B\", \"gbs_1\": $stream1, \"gbs_all\": $streamN, \"nproc\": $(nproc)}" >>"$rec"

gen() {  # n -> $WORK/net_n.h5, records generation time and peak RSS
  local n=$1 f="$WORK/net_$1.h5"
  if [[ ! -f $f ]]; then
    log "generate n=$n"
    local out
    # shellcheck disable=SC2086  # GEN: words on purpose
    out=$( { /usr/bin/time -f "RSS %M" "$BIN/snl" generate -o "$f" --sensors "$n" $GEN --localizable no; } 2>&1)
    local tg tw rss
    tg=$(sed -n 's/.*time: generate \([0-9.]*\) s.*/\1/p' <<<"$out")
    tw=$(sed -n 's/.*, write \([0-9.]*\) s.*/\1/p' <<<"$out")
    rss=$(sed -n 's/^RSS \([0-9]*\)/\1/p' <<<"$out")
    echo "{\"gen\": 1, \"n\": $n, \"generate_seconds\": $tg, \"gen_write_seconds\": $tw, \"gen_rss_kib\": $rss}" >>"$rec"
  fi
}

# STREAM triad on np ranks (best of 10), for the bound of one solve: the VM's
# shared bandwidth moves within minutes, so each solve is bracketed by two.
triad() { mpirun -np "$1" "$BIN/stream_triad" 40000000 10 | awk '{print $2}'; }

solve() {  # n ranks alg kind
  local n=$1 np=$2 alg=$3 kind=$4 js="$WORK/s_${1}_${2}_${3}.json" b0 b1
  log "solve n=$n ranks=$np $alg ($ITERS iterations)"
  b0=$(triad "$np")
  mpirun -np "$np" "$BIN/snl" solve "$WORK/net_$n.h5" -o "$WORK/r_${n}_${np}_${alg}.h5" --algorithm "$alg" \
    --max-iter "$ITERS" --tol 0 --history-every "$ITERS" --partition "$PARTITION" --temporal-block "$BLOCK" \
    --json "$js" -q
  b1=$(triad "$np")
  /usr/bin/python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); d["kind"]=sys.argv[2]
d["stream_before_gbs"], d["stream_after_gbs"] = float(sys.argv[3]), float(sys.argv[4]); d["stream_def"] = "nt_24B"
print(json.dumps(d))' \
    "$js" "$kind" "$b0" "$b1" >>"$rec"
  [[ ${KEEP:-0} == 1 ]] || rm -f "$WORK/r_${n}_${np}_${alg}.h5"
}

for n in $SIZES; do
  gen "$n"
  for np in $RANKS; do
    for alg in $ALGS; do solve "$n" "$np" "$alg" strong; done
  done
  [[ ${KEEP:-0} == 1 ]] || [[ $n == 1000000 && $WEAK == 1 ]] || rm -f "$WORK/net_$n.h5"
done
if [[ $WEAK == 1 ]]; then  # 1M sensors per rank (the table reuses strong runs of the same size)
  echo '{"weak": 1}' >>"$rec"
  for np in $RANKS; do
    n=$((1000000 * np))
    gen "$n"
    for alg in $ALGS; do
      [[ -f $WORK/s_${n}_${np}_${alg}.json ]] || solve "$n" "$np" "$alg" weak
    done
  done
fi

python3 "$here/bench/scaling_table.py" "$rec"
