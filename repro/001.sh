#!/usr/bin/env bash
# Reproduces paper 001's Figs. 6-7 (distributed Newton against the subgradient
# and incremental baselines; docs/consensus.md).
#   repro/001.sh [BUILD_DIR]      (default build; a few minutes on 2 cores)
set -euo pipefail
cd "$(dirname "$0")/.."
bash repro/consensus_fig67.sh "${1:-build}"
