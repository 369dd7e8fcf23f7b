#!/usr/bin/env bash
# A/B of two (or more) builds of libsnl on one network: the relaxation and MM
# on 2 and on 1 rank(s), the builds alternated run by run, with STREAM readings
# (2 ranks, then 1) at the start of each repetition. Each build is a directory
# holding its libsnl.so.0 (copy build/libsnl.so.0* there after building it);
# the snl binary of BIN loads it through LD_LIBRARY_PATH.
#
#   mkdir /tmp/a /tmp/b && cp build/libsnl.so.0* /tmp/a    # ... rebuild, then into /tmp/b
#   NET=/tmp/snl-10m/net.h5 LIBS="/tmp/a /tmp/b" bench/ab_libs.sh
# Environment: NET (required), LIBS (required), BIN (build/bin), IT (200), REPS (2), RANKS ("2 1").
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
BIN=${BIN:-$here/build/bin}
: "${NET:?set NET to a network file}" "${LIBS:?set LIBS to the build directories}"
IT=${IT:-200}
export OMPI_ALLOW_RUN_AS_ROOT=${OMPI_ALLOW_RUN_AS_ROOT:-1} OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=${OMPI_ALLOW_RUN_AS_ROOT_CONFIRM:-1}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for rep in $(seq "${REPS:-2}"); do
  echo "STREAM triad: $(mpirun -np 2 "$BIN/stream_triad" 40000000 10 | awk '{print $2}') GB/s (2 ranks)," \
    "$(mpirun -np 1 "$BIN/stream_triad" 40000000 10 | awk '{print $2}') GB/s (1 rank)"
  for R in ${RANKS:-2 1}; do
    for alg in relaxation mm; do
      for lib in $LIBS; do
        rm -f "$tmp/out.h5" "$tmp/s.json"
        LD_LIBRARY_PATH=$lib mpirun -x LD_LIBRARY_PATH -np "$R" "$BIN/snl" solve "$NET" -o "$tmp/out.h5" \
          --algorithm "$alg" --max-iter "$IT" --tol 0 --history-every "$IT" --json "$tmp/s.json" -q >/dev/null
        ms=$(/usr/bin/python3 -c 'import json, sys; print("%.2f" % (1e3 * json.load(open(sys.argv[1]))["seconds_per_iteration"]))' "$tmp/s.json")
        echo "$lib ranks=$R $alg: $ms ms/iteration"
      done
    done
  done
done
