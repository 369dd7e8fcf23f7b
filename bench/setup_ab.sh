#!/usr/bin/env bash
# The setup of two snl builds, run by turns on the same networks (A, B, A, B,
# ...), so that a change of the setup code is measured against the code before
# it on one machine at one time. Each run: snl solve NET --partition metis
# --max-iter ITERS --tol 0 (ITERS: 1 unless set; the pipeline with --refine
# REFINE, mm unless set, so that each phase runs ITERS iterations) on NP
# ranks; records its wall time, load, the ms per iteration of each phase, the
# read, solve and write times, the setup
# phases of the solve JSON, its per-rank memory, and whether its positions
# equal the first A run's on that network, byte for byte.
#   A=old/bin/snl B=build/bin/snl NETS="n1m.h5 n10m.h5" NPS="1 2" REPS=2 \
#     WORK=/tmp/snl-ab bench/setup_ab.sh
# NPS_BIG / BIG_FROM: rank counts for networks of at least BIG_FROM sensors
# (default: NPS). ARGS replaces the solve options after the network (default
# "--max-iter ITERS --tol 0 --algorithm pipeline --refine REFINE"; e.g. ARGS=""
# runs snl solve's defaults end to end: wall and per-phase seconds compare
# then). One JSON line per run in $WORK/records.jsonl; one text line
# per run on stdout. More builds or settings: LABELS="A B C" with C=... and,
# for any label, L_ENV="VAR=value ..." set for its runs only (e.g.
# C=build/bin/snl C_ENV=SNL_MALLOC=system: the same binary on the system
# allocator's defaults). L_PART: the label's --partition (default: PARTITION,
# else metis), e.g. A_PART=metis B_PART=bfs with A=B.
set -euo pipefail
: "${A:?A: the first snl binary}" "${B:?B: the second snl binary}" "${NETS:?NETS: network files}"
NPS=${NPS:-"1 2"}
ARGS=${ARGS-"--max-iter ${ITERS:-1} --tol 0 --algorithm pipeline --refine ${REFINE:-mm}"}
NPS_BIG=${NPS_BIG:-$NPS}
BIG_FROM=${BIG_FROM:-5000000}
REPS=${REPS:-2}
LABELS=${LABELS:-"A B"}
WORK=${WORK:-/tmp/snl-ab}
PY=/usr/bin/python3
ROOT=$(cd "$(dirname "$0")/.." && pwd)  # binaries inside the repository are printed relative to it
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
mkdir -p "$WORK"
rec="$WORK/records.jsonl"
envs=""
for l in $LABELS; do
  : "${!l:?$l: an snl binary}"
  ev=${l}_ENV
  pv=${l}_PART
  bin=$(realpath -m "${!l}")
  envs+=" $l=${bin#"$ROOT"/}${!ev:+ (${!ev})} --partition ${!pv:-${PARTITION:-metis}}"
done
echo "# $(date -u +%FT%TZ)$envs, $(nproc) cores, load: $(cut -d' ' -f1-3 /proc/loadavg)"
for net in $NETS; do
  n=$("$A" info "$net" | sed -n 's/.*sensors n = \([0-9]*\).*/\1/p')
  nps=$NPS
  [ "$n" -ge "$BIG_FROM" ] && nps=$NPS_BIG
  ref=""
  for rep in $(seq "$REPS"); do
    for np in $nps; do
      for which in $LABELS; do
        bin=${!which}
        ev=${which}_ENV
        pv=${which}_PART
        out="$WORK/r_${n}_${np}_${which}${rep}"
        # shellcheck disable=SC2086  # L_ENV and ARGS are lists of words
        /usr/bin/time -f "%e" -o "$out.time" env ${!ev:-} mpirun -np "$np" --oversubscribe "$bin" solve "$net" -o "$out.h5" \
          --partition "${!pv:-${PARTITION:-metis}}" $ARGS -q --json "$out.json"
        [ -n "$ref" ] || ref="$out.h5"
        $PY - "$out" "$ref" "$n" "$np" "$which" "$rep" "$(cat "$out.time")" "$(cut -d' ' -f1 /proc/loadavg)" "$rec" <<'PYEOF'
import json, sys, h5py
out, ref, n, np_, which, rep, wall, load, rec = sys.argv[1:]
j = json.load(open(out + ".json"))
same = h5py.File(out + ".h5", "r")["positions"][()].tobytes() == h5py.File(ref, "r")["positions"][()].tobytes()
r = {"n": int(n), "ranks": int(np_), "build": which, "rep": int(rep), "wall": float(wall), "load1": float(load),
     "positions_equal_first_A": same, "allocator": j.get("allocator", "system")}
r.update({k: v for k, v in j.items() if k.startswith("setup_") or k in ("peak_rss_bytes_per_rank", "partition", "edge_cut", "ghosts",
                                                                    "read_seconds", "solve_seconds", "write_seconds",
                                                                    "start_seconds", "start_paths_seconds", "start_rounds",
                                                                    "iterations", "ml_cost")})
r.update({k: v for k, v in j.items() if k.endswith("_iterate_seconds")})
two_phases = j.get("algorithm") == "pipeline"  # the default ARGS: two phases, ITERS each
its = max(1, j["iterations"] // 2)
r.update({p + "_ms_per_iteration": 1e3 * j.get(p + "_iterate_seconds", 0) / its for p in ("relaxation", "mm", "mm-accel")
          if two_phases})
with open(rec, "a") as f:
    f.write(json.dumps(r) + "\n")
g = lambda k: r.get("setup_graph." + k + "_seconds", 0)
print(f"n={n} np={np_} {which}{rep} ({r['allocator']}, {r.get('partition')}, cut {r.get('edge_cut')}) load {load}: "
      f"wall {r['wall']:.2f} s, setup {r['setup_seconds']:.2f} (partition {r['setup_partition_seconds']:.2f}), "
      f"read {r.get('read_seconds', 0):.2f}, solve {r.get('solve_seconds', 0):.2f}, "
      + (f"ms/iteration relaxation {r['relaxation_ms_per_iteration']:.2f} MM {r['mm_ms_per_iteration']:.2f} "
         f"mm-accel {r['mm-accel_ms_per_iteration']:.2f}, " if two_phases else "")
      + f"graph {r['setup_graph_seconds']:.2f} (exchange {g('exchange'):.2f}, lists {g('lists'):.2f}, "
      f"order {g('order'):.2f}, csr {g('csr'):.2f}), build bytes/rank {max(r['setup_graph_build_bytes_per_rank'])}, "
      f"peak RSS/rank {max(r['peak_rss_bytes_per_rank'])}, same positions {same}; start {r.get('start_seconds', 0):.2f} s "
      f"(paths {r.get('start_paths_seconds', 0):.2f} s, {r.get('start_rounds', 0)} rounds), "
      f"iterations {r['iterations']}, ML cost {r['ml_cost']:.10g}, seconds iterating: "
      + ", ".join(f"{k[:-len('_iterate_seconds')]} {v:.2f}" for k, v in r.items() if k.endswith("_iterate_seconds")))
PYEOF
      done
    done
  done
done
