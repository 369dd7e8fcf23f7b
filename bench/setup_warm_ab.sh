#!/usr/bin/env bash
# Two builds' snl_setup_warm (bench/setup_warm.cpp) by turns on one network:
# each run reads and sets up the network REPS times in one process, the first
# time on fresh memory, then on pages the process has already touched. One
# JSON line per repetition in $OUT, tagged with the build's label and the pair.
#   A=OLD/build-bench B=NEW/build-bench NET=W/net_10000000.h5 PAIRS=3 REPS=3 NP=2 \
#     PARTITION=bfs OUT=W/warm.jsonl bench/setup_warm_ab.sh
# Rows: /usr/bin/python3 bench/setup_warm_rows.py W/warm.jsonl
set -euo pipefail
: "${A:?A: the first build directory}" "${B:?B: the second build directory}" "${NET:?NET: a network file}"
: "${OUT:?OUT: the JSON lines file}"
PAIRS=${PAIRS:-3}
REPS=${REPS:-3}
NP=${NP:-2}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
echo "# $(date -u +%FT%TZ) A=$A B=$B NET=$NET NP=$NP PARTITION=${PARTITION:-bfs}, $(nproc) cores, load: $(cut -d' ' -f1-3 /proc/loadavg)"
for pair in $(seq "$PAIRS"); do
  for label in A B; do
    dir=${!label}
    mpirun -np "$NP" "$dir/bin/snl_setup_warm" "$NET" "${PARTITION:-bfs}" "$REPS" |
      sed "s/^{/{\"build\": \"$label\", \"pair\": $pair, /" | tee -a "$OUT"
  done
done
