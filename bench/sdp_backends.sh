#!/usr/bin/env bash
# The SDP solver for --algorithm sdp, esdp and edm, chosen by measurement: the
# same SDPs (written by snl with SNL_SDP_DUMP) solved by DSDP inside snl and by
# the CSDP and DSDP executables (Debian coinor-csdp, dsdp), on the 003-like
# networks of 50 and 200 sensors (unit square, corner anchors, sigma 0.05), and
# snl's own DSDP time on larger networks for the size limits.
#   bench/sdp_backends.sh [SNL] > docs/data/sdp_backends.csv
# Times are CPU seconds (user + system, /usr/bin/time) of the whole process, so
# that the load of the shared 2-core machine matters less than wall time would;
# snl's include reading the network and writing the result (a few ms).
set -euo pipefail
SNL=${1:-build/bin/snl}
W=$(mktemp -d /tmp/snl_sdpb.XXXXXX)
trap 'rm -rf "$W"' EXIT
echo "sensors,relaxation,solver,seconds,objective_or_status"
tm() { /usr/bin/time -f "%U %S" -o "$W/t" "$@" > "$W/log" 2>&1 || true; tail -1 "$W/t" | awk '{print $1 + $2}'; }
for n in 50 200; do
  deg=$([ $n = 50 ] && echo 6.1 || echo 8)
  "$SNL" generate -o "$W/net$n.h5" --sensors $n --avg-degree $deg --sigma 0.05 --seed 2015 -q
  for alg in sdp esdp edm; do
    t=$(SNL_SDP_DUMP="$W/p.dat-s" tm "$SNL" solve "$W/net$n.h5" -o "$W/r.h5" --algorithm $alg --json "$W/r.json" -q)
    /usr/bin/python3 -c "import json;j=json.load(open('$W/r.json'));print('$n,$alg,dsdp-in-snl,$t,%s'%j['sdp_status'])"
    if command -v csdp > /dev/null; then
      t=$(tm timeout 600 csdp "$W/p.dat-s"); echo "$n,$alg,csdp-exe,$t,$(grep -m1 -o 'Success.*\|Failure.*\|Partial.*' "$W/log" | tr ',' ';')"
    fi
    if command -v dsdp5 > /dev/null; then
      t=$(tm timeout 600 dsdp5 "$W/p.dat-s"); echo "$n,$alg,dsdp5-exe,$t,$(grep -m1 -o 'DSDP Converged\|DSDP Terminated.*\|Infeasible.*' "$W/log" | tr ',' ';')"
    fi
  done
done
# Size limits: snl's DSDP time as the network grows (average degree 8).
for n in 400 1000; do
  "$SNL" generate -o "$W/big$n.h5" --sensors $n --avg-degree 8 --sigma 0.05 --seed 2015 -q
  for alg in sdp esdp edm; do
    [ $n = 1000 ] && [ $alg != esdp ] && continue
    rm -f "$W/r.json"
    t=$(tm timeout 900 "$SNL" solve "$W/big$n.h5" -o "$W/r.h5" --algorithm $alg --json "$W/r.json" -q)
    if [ -f "$W/r.json" ]; then
      /usr/bin/python3 -c "import json;j=json.load(open('$W/r.json'));print('$n,$alg,dsdp-in-snl,$t,%s'%j['sdp_status'])"
    else
      echo "$n,$alg,dsdp-in-snl,$t,$(head -c 120 "$W/log" | tr ',\n' '; ')"
    fi
  done
done
