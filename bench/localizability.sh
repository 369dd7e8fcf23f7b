#!/bin/bash
# Localizable fraction against average degree for the generator's default
# networks (docs/generator.md). Raw JSON lines (one per draw) into
# docs/data/localizability.jsonl; needs the benchmark build (-DSNL_BUILD_BENCH=ON).
#   bash bench/localizability.sh [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
B=${1:-build}/bin/snl_localizability
OUT=docs/data/localizability.jsonl
[ "${STAGE:-1}" = 1 ] && : > "$OUT.tmp"
DEGS2="6 8 10 12 14 16 18 20"
# STAGE=2 appends the stages after n = 10^5 to an existing $OUT (a run interrupted there).
if [ "${STAGE:-1}" = 2 ]; then cp "$OUT" "$OUT.tmp"; fi
{ if [ "${STAGE:-1}" = 1 ]; then
  "$B" 1000 2 20 $DEGS2
  "$B" 10000 2 5 $DEGS2
  # the windowed rigidity test against the exact one on the same draws
  "$B" 20000 2 2 8 10 12
  SNL_WINDOWS=1 "$B" 20000 2 2 8 10 12
  "$B" 100000 2 2 $DEGS2
  fi
  "$B" 1000000 2 1 10 14 16 20
  "$B" 1000 3 10 12 16 20 24 28
  "$B" 10000 3 2 16 20 24 28
} >> "$OUT.tmp"
mv "$OUT.tmp" "$OUT"
