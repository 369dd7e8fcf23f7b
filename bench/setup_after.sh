#!/usr/bin/env bash
# The setup of one snl build right after runs of each kind, on one network and
# 2 ranks: per rep, a one-iteration solve with --refine mm (the smaller
# footprint), then two with the default refinement (mm-accel, the larger).
# On a VM whose fresh pages are slow to fault in, a run's setup depends on the
# previous process: this prints each run's setup phases and peak memory.
#   NET=net_10000000.h5 SNL=build-bench/bin/snl REPS=2 WORK=/tmp/snl-after bench/setup_after.sh
set -euo pipefail
: "${NET:?NET: a network file}" "${SNL:?SNL: an snl binary}"
REPS=${REPS:-2}
WORK=${WORK:-/tmp/snl-after}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
mkdir -p "$WORK"
echo "# $(date -u +%FT%TZ) $(basename "$SNL"), $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
for rep in $(seq "$REPS"); do
  for kind in mm default default2; do
    extra=()
    [ "$kind" = mm ] && extra=(--refine mm)
    rm -f "$WORK/r.h5"
    mpirun -np 2 "$SNL" solve "$NET" -o "$WORK/r.h5" --max-iter 1 --tol 0 "${extra[@]}" -q \
      --json "$WORK/r_${rep}_$kind.json" >/dev/null
    /usr/bin/python3 - "$WORK/r_${rep}_$kind.json" "$rep" "$kind" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
p = {k: v for k, v in d.items() if k.startswith("setup") and isinstance(v, float)}
rss = [round(x / 2**20) for x in d.get("peak_rss_bytes_per_rank", [])]
print(f"rep {sys.argv[2]} {sys.argv[3]:8s} setup {d['setup_seconds']:.2f} s: merge {p['setup_merge_seconds']:.2f}, "
      f"partition {p['setup_partition_seconds']:.2f}, exchange {p['setup_graph.exchange_seconds']:.2f}, "
      f"lists {p['setup_graph.lists_seconds']:.2f}, order {p['setup_graph.order_seconds']:.2f}, "
      f"csr {p['setup_graph.csr_seconds']:.2f}; peak RSS per rank {rss} MiB")
PY
  done
done
