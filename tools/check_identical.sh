#!/usr/bin/env bash
# Checks that two snl builds give byte-identical results: positions, histories and
# the deterministic part of the JSON summaries (timings, memory and MPI byte counts
# removed) for every algorithm, on 1 and 2 ranks, plus generate, eval and experiment.
#
#   tools/check_identical.sh OLD_SNL NEW_SNL [WORKDIR]
#
# OLD_SNL may be a build of an earlier commit, e.g.
#   git worktree add /tmp/snl-old <commit> && bash /tmp/snl-old/scripts/setup.sh /tmp/snl-old/build
#   tools/check_identical.sh /tmp/snl-old/build/bin/snl build/bin/snl
# Exit status 0 when everything matches; every difference is printed.
set -euo pipefail
OLD=${1:?usage: check_identical.sh OLD_SNL NEW_SNL [WORKDIR]}
NEW=${2:?usage: check_identical.sh OLD_SNL NEW_SNL [WORKDIR]}
W=${3:-$(mktemp -d /tmp/snl_ident.XXXXXX)}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
PY=/usr/bin/python3
mkdir -p "$W/old" "$W/new"
bad=0

run_both() {  # run_both NAME NP ARGS... (ARGS use @D@ for the output directory)
  local name=$1 np=$2; shift 2
  for side in old new; do
    local bin=$OLD; [ $side = new ] && bin=$NEW
    local args=("${@//@D@/$W/$side}")
    if [ "$np" = 0 ]; then "$bin" "${args[@]}" > "$W/$side/$name.out" 2>&1 || echo "exit $?" >> "$W/$side/$name.out"
    else mpirun -np "$np" --oversubscribe "$bin" "${args[@]}" > "$W/$side/$name.out" 2>&1 || echo "exit $?" >> "$W/$side/$name.out"; fi
  done
}

cmp_h5() {  # cmp_h5 FILE: every dataset of the file, byte for byte (h5diff without tolerance)
  local f=$1
  if ! h5diff -q "$W/old/$f" "$W/new/$f" >/dev/null 2>&1; then
    # Attributes such as wall time differ by nature: compare datasets only.
    "$PY" - "$W/old/$f" "$W/new/$f" <<'EOF' || { echo "DIFF: $f"; bad=1; }
import sys, h5py, numpy as np
a, b = h5py.File(sys.argv[1], "r"), h5py.File(sys.argv[2], "r")
names = []
a.visititems(lambda n, o: names.append(n) if isinstance(o, h5py.Dataset) else None)
nb = []
b.visititems(lambda n, o: nb.append(n) if isinstance(o, h5py.Dataset) else None)
skip = ("wall", "seconds", "bytes", "elapsed")
ok = sorted(names) == sorted(nb)
for n in names:
    if any(s in n for s in skip) or n not in b: continue
    x, y = a[n][()], b[n][()]
    if x.tobytes() != y.tobytes():
        print("  dataset differs:", n); ok = False
sys.exit(0 if ok else 1)
EOF
  fi
}

cmp_json() {  # deterministic keys of a JSON summary
  "$PY" - "$W/old/$1" "$W/new/$1" <<'EOF' || { echo "DIFF: $1"; bad=1; }
import sys, json
def clean(d):
    if isinstance(d, dict):
        return {k: clean(v) for k, v in d.items()
                if not any(s in k for s in ("seconds", "wall", "bytes", "rss", "memory", "time", "eta", "stream", "ratio", "simd", "threads", "hostname", "elapsed", "wait_fraction"))}
    if isinstance(d, list): return [clean(x) for x in d]
    return d
a, b = clean(json.load(open(sys.argv[1]))), clean(json.load(open(sys.argv[2])))
if a != b:
    for k in sorted(set(a) | set(b)):
        if a.get(k) != b.get(k): print("  key differs:", k, a.get(k), b.get(k))
    sys.exit(1)
EOF
}

echo "== generate"
run_both gen2d 0 generate -o @D@/net2d.h5 --sensors 300 --avg-degree 8 --sigma 0.02 --anchors corners --seed 5 -q
run_both gen3d 0 generate -o @D@/net3d.h5 --sensors 200 --dim 3 --avg-degree 10 --sigma 0.02 --anchors 8 --seed 6 -q
cmp_h5 net2d.h5; cmp_h5 net3d.h5
cp "$W/old/net2d.h5" "$W/net2d.h5"; cp "$W/old/net3d.h5" "$W/net3d.h5"

echo "== solve (every algorithm, default stopping rule and --tol 0, 1 and 2 ranks)"
for alg in pipeline relaxation mm bb pm async async-exact; do
  for np in 1 2; do
    run_both "$alg.$np" $np solve "$W/net2d.h5" -o "@D@/$alg.$np.h5" --algorithm $alg --max-iter 400 -q --json "@D@/$alg.$np.json"
    cmp_h5 "$alg.$np.h5"; cmp_json "$alg.$np.json"
  done
  run_both "$alg.tol0" 2 solve "$W/net3d.h5" -o "@D@/$alg.tol0.h5" --algorithm $alg --max-iter 120 --tol 0 -q --json "@D@/$alg.tol0.json"
  cmp_h5 "$alg.tol0.h5"; cmp_json "$alg.tol0.json"
done
run_both tblock 2 solve "$W/net2d.h5" -o @D@/tblock.h5 --temporal-block 4 --max-iter 300 -q --json @D@/tblock.json
cmp_h5 tblock.h5; cmp_json tblock.json
for f in "$ROOT"/inputs/*.h5; do
  b=$(basename "$f" .h5)
  run_both "in.$b" 2 solve "$f" -o "@D@/in.$b.h5" -q --json "@D@/in.$b.json"
  cmp_h5 "in.$b.h5"; cmp_json "in.$b.json"
done

echo "== eval"
run_both eval 0 eval "$W/net2d.h5" "$W/old/pipeline.1.h5" --crlb --json @D@/eval.json
cmp_json eval.json

echo "== experiment"
run_both exp 2 experiment "$ROOT/inputs/net10_s0.05.h5" -o @D@/exp.csv --sigmas 0.01,0.05 --trials 3 --h5 @D@/exp.h5 --trajectory @D@/traj.csv
for f in exp.csv traj.csv; do cmp -s "$W/old/$f" "$W/new/$f" || { echo "DIFF: $f"; bad=1; }; done

echo "== checkpoint"
run_both ckpt 2 solve "$W/net2d.h5" -o @D@/ck.h5 --max-iter 100 --tol 0 --checkpoint @D@/ckpt.h5 --checkpoint-every 50 -q
cmp_h5 ckpt.h5

if [ $bad = 0 ]; then echo "check_identical: all outputs identical ($W)"; else echo "check_identical: DIFFERENCES ($W)"; fi
exit $bad
