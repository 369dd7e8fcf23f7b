#!/usr/bin/env bash
# Temporal blocking (--temporal-block S: S iterations per pass over memory) on
# one network: the pipeline with MM (IT relaxation + IT MM iterations, --refine
# mm: mm-accel takes one iteration per pass) for each S on
# each rank count, every solve bracketed by STREAM triad readings on its own
# ranks, then one table: ms per iteration of each phase, the 1 -> 2 rank
# parallel efficiency T1 / (2 T2) for each S, and whether the positions equal
# those of S = 1 on one rank bit for bit (h5diff). Recorded runs:
# docs/data/perf/results-*-tblock-*.txt (docs/data/perf/README.md).
#
#   NET=/tmp/snl-10m/net.h5 bench/temporal_block.sh
# Environment: NET (required), BLOCKS ("1 2 3 4"), RANKS ("1 2"), IT (200), BIN (build/bin).
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
BIN=${BIN:-$here/build/bin}
: "${NET:?set NET to a network file}"
IT=${IT:-200}
BLOCKS=${BLOCKS:-1 2 3 4}
RANKS=${RANKS:-1 2}
export OMPI_ALLOW_RUN_AS_ROOT=${OMPI_ALLOW_RUN_AS_ROOT:-1} OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=${OMPI_ALLOW_RUN_AS_ROOT_CONFIRM:-1}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
stream() { mpirun -np "$1" "$BIN/stream_triad" 40000000 10 | awk '{print $2}'; }
ref=""
for R in $RANKS; do
  for S in $BLOCKS; do
    before=$(stream "$R")
    mpirun -np "$R" "$BIN/snl" solve "$NET" -o "$tmp/out_${R}_$S.h5" --algorithm pipeline --max-iter "$IT" \
      --tol 0 --history-every "$IT" --temporal-block "$S" --refine mm --json "$tmp/s_${R}_$S.json" -q >/dev/null
    after=$(stream "$R")
    [ -n "$ref" ] || ref="$tmp/out_${R}_$S.h5"
    same=$(h5diff -q "$ref" "$tmp/out_${R}_$S.h5" /positions >/dev/null 2>&1 && echo yes || echo NO)
    echo "$R $S $before $after $same $tmp/s_${R}_$S.json" >>"$tmp/runs"
  done
done
/usr/bin/python3 - "$tmp/runs" "$IT" <<'EOF'
import json, sys
runs = [l.split() for l in open(sys.argv[1])]
it = int(sys.argv[2])
t = {}
print("ranks  S  STREAM GB/s (before/after)  relax ms/it  MM ms/it  wait  same bits")
for R, S, b, a, same, js in runs:
    d = json.load(open(js))
    rel, mm = (1e3 * d[f"{p}_iterate_seconds"] / it for p in ("relaxation", "mm"))
    t[(int(R), int(S))] = (rel, mm)
    print(f"{R:>5} {S:>2}  {b:>6} / {a:<6}              {rel:9.2f}  {mm:8.2f}  {d['iterate_wait_fraction']:.3f}  {same}")
print("S  efficiency 1 -> 2 ranks (relaxation, MM)")
for (R, S), (rel, mm) in sorted(t.items()):
    if R == 2 and (1, S) in t:
        r1, m1 = t[(1, S)]
        print(f"{S:>2}  {100 * r1 / (2 * rel):.0f}%  {100 * m1 / (2 * mm):.0f}%")
EOF
