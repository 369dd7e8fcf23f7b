#!/usr/bin/env bash
# Reproduces paper 000's Table I and Figs. 1-3 with both Barzilai-Borwein
# methods (docs/reproduction.md), then the tables of docs/reproduction.md.
#   repro/000.sh [BUILD_DIR]      (default build; a few minutes on 2 cores)
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
bash repro/repro_000.sh "$BUILD/bin/snl"
/usr/bin/python3 repro/repro_tables.py
