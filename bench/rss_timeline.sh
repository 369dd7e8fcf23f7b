#!/usr/bin/env bash
# The resident memory of each process of a run over time: starts the command,
# then every INTERVAL seconds (0.5 unless set) prints "seconds pid rss_kib"
# for every process whose command line starts with PATTERN, until none is
# left. Shows in which step a run's peak RSS falls (the JSON gives only the
# peak), e.g. the setup's against the solve's:
#   PATTERN="$PWD/build-bench/bin/snl solve" bench/rss_timeline.sh \
#     mpirun -np 2 "$PWD/build-bench/bin/snl" solve NET -o OUT.h5 --json OUT.json > rss.txt
set -euo pipefail
: "${PATTERN:?PATTERN: the start of the command lines to watch}"
INTERVAL=${INTERVAL:-0.5}
"$@" &
run=$!
t0=$(date +%s.%N)
echo "# $(date -u +%FT%TZ) $*"
while kill -0 "$run" 2>/dev/null; do
  now=$(date +%s.%N)
  for p in $(pgrep -f "^$PATTERN" || true); do
    kib=$(awk '/^VmRSS/ {print $2}' "/proc/$p/status" 2>/dev/null || true)
    [ -n "$kib" ] && awk -v a="$now" -v b="$t0" -v p="$p" -v k="$kib" 'BEGIN { printf "%.2f %s %s\n", a - b, p, k }'
  done
  sleep "$INTERVAL"
done
wait "$run"
