#!/usr/bin/env bash
# 000 Table I and Figs. 1-3: MM against both Barzilai-Borwein methods (bb, the
# variant on the ML cost; bb-calafiore, Calafiore-Carlone-Wei as published) from
# the relaxation's point, 20000 reals per sensor each, on network A of
# docs/experiments.md; 10 noise draws per sigma (the paper: 100), trajectories kept.
#   repro/repro_000.sh [SNL]
set -euo pipefail
SNL=${1:-build/bin/snl}
cd "$(dirname "$0")/.."
"$SNL" experiment inputs/net50_s0.01.h5 -o docs/data/repro_000_table1.csv --sigmas 0.01,0.05,0.1 \
  --trials 10 --budget 20000 --algorithms mm,bb,bb-calafiore --trajectory docs/data/repro_000_trajectory.csv \
  > docs/data/repro_000_table1.txt
/usr/bin/python3 tools/plot_experiment.py docs/data/repro_000_trajectory.csv -o docs/repro_000_cost_vs_comm.png
/usr/bin/python3 repro/plot_mpe_vs_comm.py docs/data/repro_000_trajectory.csv docs/repro_000_mpe_vs_comm.png
# Network B (every sensor ranged to all four anchors), the same runs.
"$SNL" experiment inputs/net50_allanchors_s0.01.h5 -o docs/data/repro_000_table1_B.csv --sigmas 0.01,0.05,0.1 \
  --trials 10 --budget 20000 --algorithms mm,bb,bb-calafiore --trajectory docs/data/repro_000_trajectory_B.csv \
  > docs/data/repro_000_table1_B.txt
/usr/bin/python3 tools/plot_experiment.py docs/data/repro_000_trajectory_B.csv -o docs/repro_000_cost_vs_comm_B.png
/usr/bin/python3 repro/plot_mpe_vs_comm.py docs/data/repro_000_trajectory_B.csv docs/repro_000_mpe_vs_comm_B.png
