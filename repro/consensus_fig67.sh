#!/usr/bin/env bash
# 001 Figs. 6-7 (reconstruction): 100 nodes, family exp with a planted Hamilton
# path; Newton on a spanning tree and on the path, distributed subgradient and
# incremental (and newton-tree with the exact tree dual); absolute error and F
# (running averages for the first-order methods) against primal iterations and
# against messages per node.
# Writes docs/data/consensus/fig67_*.csv (+ fig67_problem.txt, the commands) and
# docs/consensus_fig6_7.png, docs/consensus_fig6_7_messages.png.
# Usage: repro/consensus_fig67.sh [BUILD_DIR]   (default build)
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
SNL=${SNL:-$ROOT/${1:-build}/bin/snl}
NP=${NP:-1}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
OUT=$ROOT/docs/data/consensus
W=$(mktemp -d "${TMPDIR:-/tmp}/consensus_fig67.XXXXXX")
trap 'rm -rf "$W"' EXIT
mkdir -p "$OUT"
# The commands as run (scratch dir shown as $W, the checkout as .).
run() { echo "+ $*" | sed -e "s|$W|\$W|g" -e "s|$ROOT/|./|g" >> "$OUT/fig67_commands.txt"; "$@"; }
: > "$OUT/fig67_commands.txt"
run "$SNL" consensus generate -o "$W/p.h5" --nodes 100 --family exp --hamiltonian --seed 1 | sed "s|$W|\$W|" | tee "$OUT/fig67_problem.txt"
args=()
# name|solve options; the paper's four curves (Newton with the paper's damped step), and the exact tree dual for comparison.
for entry in "newton-tree|--method newton-tree --step damped" "newton-path|--method newton-path --step damped" \
             "subgradient|--method subgradient --max-iter 1000" "incremental|--method incremental --max-iter 1000" \
             "newton-tree-exact|--method newton-tree --dual exact --step damped"; do
  m=${entry%%|*}
  read -r -a opts <<< "${entry#*|}"
  run mpirun -np "$NP" "$SNL" consensus solve "$W/p.h5" -o "$W/$m.h5" "${opts[@]}" -q --json "$OUT/fig67_$m.json"
  args+=("$m=$W/$m.h5")
done
run /usr/bin/python3 "$ROOT/tools/plot_consensus.py" --results "${args[@]}" --csv-dir "$OUT" --prefix fig67 \
  --png "$ROOT/docs/consensus_fig6_7.png" --png-messages "$ROOT/docs/consensus_fig6_7_messages.png"
