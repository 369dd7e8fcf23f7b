#!/usr/bin/env bash
# CPU seconds of snl's DSDP relaxations at the size limit (300 sensors for all
# three) and ESDP at 500, where DSDP fails; average degree 8, sigma 0.05.
#   bench/sdp_limits.sh [SNL] > docs/data/sdp_limits.csv
set -euo pipefail
SNL=${1:-build/bin/snl}
W=$(mktemp -d /tmp/snl_sdpl.XXXXXX)
trap 'rm -rf "$W"' EXIT
for run in "500 esdp" "300 sdp" "300 esdp" "300 edm"; do
  set -- $run
  [ -f "$W/net$1.h5" ] || "$SNL" generate -o "$W/net$1.h5" --sensors $1 --avg-degree 8 --sigma 0.05 --seed 2015 -q
  rm -f "$W/r.json"
  /usr/bin/time -f "%U %S" -o "$W/t" "$SNL" solve "$W/net$1.h5" -o "$W/r.h5" --algorithm $2 --json "$W/r.json" -q \
    > "$W/log" 2>&1 || true
  t=$(tail -1 "$W/t" | awk '{print $1 + $2}')
  if [ -f "$W/r.json" ]; then
    /usr/bin/python3 -c "import json;j=json.load(open('$W/r.json'));print('$1,$2,dsdp-in-snl,$t,%s'%j['sdp_status'])"
  else
    echo "$1,$2,dsdp-in-snl,$t,$(head -c 120 "$W/log" | tr ',\n' '; ')"
  fi
done
