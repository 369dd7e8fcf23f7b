#!/usr/bin/env bash
# Setup time and per-rank memory of snl solve, METIS against ParMETIS, on 1, 2
# and 4 ranks (4 oversubscribed on the 2-core VM), and the positions of every
# run against the METIS run on the first rank count of NPS, byte for byte.
#   WORK=/tmp/snl-setup SIZES="1000000 10000000" NPS="1 2 4" ITERS=10 bench/setup_scaling.sh
# GEN: snl generate options of the networks (default: none, the generator's
# defaults; GEN="--avg-degree 6 --sigma 0.01 --side 1 --anchors corners
# --localizable no" gives the older records' networks). LOCK: a lock file the
# timed runs hold (default: none).
# Prints one line per run; the solve JSONs stay in $WORK (records.jsonl: one per run).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BIN=${BIN:-$ROOT/build/bin}
WORK=${WORK:-/tmp/snl-setup}
SIZES=${SIZES:-"1000000"}
NPS=${NPS:-"1 2 4"}
ITERS=${ITERS:-10}
GEN=${GEN:-}
LOCK=${LOCK:-}
locked() { if [ -n "$LOCK" ]; then flock "$LOCK" "$@"; else "$@"; fi; }
PY=/usr/bin/python3
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
mkdir -p "$WORK"
rec="$WORK/records.jsonl"
echo "# $(date -u +%FT%TZ) $(git -C "$ROOT" rev-parse --short HEAD) $(nproc) cores, load: $(cut -d' ' -f1-3 /proc/loadavg)"
for n in $SIZES; do
  f="$WORK/net_$n.h5"
  # shellcheck disable=SC2086
  [[ -f $f ]] || "$BIN/snl" generate -o "$f" --sensors "$n" $GEN -q
  echo "# network $f: snl generate --sensors $n $GEN"
  for np in $NPS; do
    for part in metis parmetis; do
      out="$WORK/r_${n}_${np}_${part}"
      locked /usr/bin/time -f "%e" -o "$out.time" mpirun -np "$np" --oversubscribe "$BIN/snl" solve "$f" -o "$out.h5" \
        --partition "$part" --max-iter "$ITERS" --tol 0 -q --json "$out.json"
      $PY - "$out" "$WORK/r_${n}_${NPS%% *}_metis.h5" "$n" "$np" "$part" "$(cat "$out.time")" "$(cut -d' ' -f1 /proc/loadavg)" >>"$rec" <<'PYEOF'
import json, sys, h5py
out, ref, n, np_, part, wall, load = sys.argv[1:]
j = json.load(open(out + ".json"))
same = h5py.File(out + ".h5", "r")["positions"][()].tobytes() == h5py.File(ref, "r")["positions"][()].tobytes()
r = {"n": int(n), "ranks": int(np_), "requested": part, "partition": j["partition"], "wall": float(wall),
     "load1": float(load), "positions_equal_metis_first": same, "edge_cut": j["edge_cut"], "ghosts": j["ghosts"],
     "read_seconds": j["read_seconds"], "setup_seconds": j["setup_seconds"]}
r.update({k: v for k, v in j.items() if k.startswith("setup_") or k.endswith("_per_rank")})
print(json.dumps(r))
PYEOF
      tail -1 "$rec" | $PY -c '
import json, sys
r = json.loads(sys.stdin.read())
rss = r["peak_rss_bytes_per_rank"]
mean = sum(rss) / len(rss)
print("n=%d ranks=%d %-8s setup %6.2f s (partition %5.2f, graph %5.2f) peak RSS MiB %s max/mean %.2f cut %d"
      " positions==metis(first): %s load %.1f" % (r["n"], r["ranks"], r["partition"], r["setup_seconds"],
      r["setup_partition_seconds"], r["setup_graph_seconds"], [round(x / 2**20) for x in rss], max(rss) / mean,
      r["edge_cut"], r["positions_equal_metis_first"], r["load1"]))'
    done
  done
done
