#!/usr/bin/env bash
# The bfs partition of two snl builds on each network and rank count: B with
# SNL_BFS_TRACE=1 (rank 0 prints each pass: probe, pass from s, pass from r,
# with levels and nodes reached), then A; each run one iteration of snl solve
# --partition bfs; prints its edge cut, ghosts, setup and partition seconds, and
# whether B's positions equal A's, byte for byte.
#   A=OLD/bin/snl B=NEW/bin/snl NETS="n10m.h5 n1m.h5" NPS="2 4" WORK=W bench/bfs_probe_trace.sh
set -euo pipefail
: "${A:?A: the first snl binary}" "${B:?B: the second snl binary}" "${NETS:?NETS: network files}" "${WORK:?WORK: a folder}"
NPS=${NPS:-2}
mkdir -p "$WORK"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
W=$WORK
for net in $NETS; do
  for np in $NPS; do
    for which in B A; do
      bin=${!which}
      out=$W/$(basename "$net" .h5)_${np}_$which
      echo "## $(basename "$net") np=$np build=$which"
      SNL_BFS_TRACE=1 mpirun -x SNL_BFS_TRACE -np "$np" "$bin" solve "$net" -o "$out.h5" --partition bfs --max-iter 1 --tol 0 -q --json "$out.json" 2>&1 | grep "^bfs:" || true
      /usr/bin/python3 -c "
import json,sys
j=json.load(open('$out.json'))
print('partition', j.get('partition'), 'edge_cut', j.get('edge_cut'), 'ghosts', j.get('ghosts'), 'setup_partition_seconds', round(j.get('setup_partition_seconds',0),3), 'setup_seconds', round(j['setup_seconds'],3))"
    done
    /usr/bin/python3 -c "
import h5py
a=h5py.File('$W/$(basename "$net" .h5)_${np}_A.h5','r')['positions'][()].tobytes(); b=h5py.File('$W/$(basename "$net" .h5)_${np}_B.h5','r')['positions'][()].tobytes()
print('positions B == A:', a==b)"
  done
done
