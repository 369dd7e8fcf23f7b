#!/usr/bin/env bash
# Time to solution: end to end (read, setup, start, iterate, write) on the
# default networks (`snl generate --sensors N`), one row per method, with the
# communication rounds and the accuracy of the answer beside the wall time.
#
#   SIZES="100000 1000000" NP=2 WORK=/tmp/tts bench/time_to_solution.sh > out.txt
#
# Methods (rows):
#   default   `snl solve` with its defaults (dv-pipeline: distance-vector start,
#             200 relaxation iterations, 200 of mm-accel, ml-agd to convergence);
#   pipeline  the pipeline that was the default before: relaxation then mm-accel,
#             from the random start (--algorithm pipeline);
#   papers    003 + 000 as published: relaxation, then plain MM, papers' stopping
#             rule (--algorithm pipeline --refine mm --stop papers);
#   mm        plain MM (000) from the random start, the default stopping rule;
#   ceres     Ceres LM (bench/ceres/ceres_ml, central, one process) from the
#             default's own start after its relaxation phase (`--algorithm
#             relaxation --init dv --max-iter 200`), to its tolerances 1e-12 or
#             CERES_ITER LM iterations; only where the ceres_ml binary exists (a
#             build with -DSNL_BUILD_CERES=ON) and n <= CERES_MAX. Its wall time
#             adds the start's (a separate `snl solve` on NP ranks).
# Columns: wall, read, setup, start (the distance-vector start) and iterate
# (the Solver's) and write seconds (the solve's JSON), iterations, halo
# exchanges (the iterations' exchanges, the algorithm's MPI bytes over the bytes
# of one exchange, plus the start's rounds), gradient tests (one more exchange
# each), messages per sensor, final ML cost, its excess over the lowest cost of
# the rows (relative), RMSE, and RMSE over the CRLB on the localizable sensors
# (`snl eval --crlb`, once per network; CRLB=0 skips it).
# Before and after each size it prints the STREAM triad on the NP ranks
# (bench/stream_triad.cpp, built with -DSNL_BUILD_BENCH=ON; skipped without
# it): this VM's bandwidth moves by 2 x from hour to hour, and the rows of one
# run compare as ratios.
# Duration: about 2 minutes at 10^5 sensors, 15 minutes at 10^6 (the old
# pipelines take minutes there), hours at 10^7 on 2 cores.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
SNL=${SNL:-$ROOT/build/bin/snl}
CERES=${CERES:-$(dirname "$SNL")/ceres_ml}
CERES_MAX=${CERES_MAX:-100000}
CERES_ITER=${CERES_ITER:-100}
SIZES=${SIZES:-100000}
NP=${NP:-2}
WORK=${WORK:-$(mktemp -d /tmp/snl_tts.XXXXXX)}
METHODS=${METHODS:-"default pipeline papers mm ceres"}
CRLB=${CRLB:-1}
STREAM=${STREAM:-$(dirname "$SNL")/stream_triad}
PY=/usr/bin/python3
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
mkdir -p "$WORK"

stream() {  # the triad's GB/s on NP ranks (best of 10), or nothing without the binary
  [ -x "$STREAM" ] || return 0
  echo "# STREAM triad, $NP ranks, $1: $(mpirun -np "$NP" "$STREAM" 40000000 10 | sed -n 's/^triad_nt_gbs \([0-9.]*\).*/\1/p') GB/s"
}

method_args() {
  case $1 in
    default) echo "" ;;
    pipeline) echo "--algorithm pipeline" ;;
    papers) echo "--algorithm pipeline --refine mm --stop papers" ;;
    mm) echo "--algorithm mm" ;;
    *) echo "unknown method $1" >&2; exit 2 ;;
  esac
}

echo "# time_to_solution: $(date -u +%Y-%m-%dT%H:%MZ) $(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo '?') np=$NP host=$(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')"
for n in $SIZES; do
  net=$WORK/net_$n.h5
  [ -f "$net" ] || "$SNL" generate -o "$net" --sensors "$n" > "$WORK/gen_$n.txt"
  stream "before n = $n"
  crlb=nan
  ran=""
  for m in $METHODS; do
    if [ "$m" = ceres ]; then
      if [ ! -x "$CERES" ] || [ "$n" -gt "$CERES_MAX" ]; then continue; fi
      mpirun -np "$NP" "$SNL" solve "$net" -o "$WORK/r_${n}_ceres_start.h5" --json "$WORK/r_${n}_ceres_start.json" -q \
        --algorithm relaxation --init dv --max-iter 200 --tol 0 > "$WORK/r_${n}_ceres_start.txt" 2>&1
      "$CERES" "$net" "$WORK/r_${n}_ceres_start.h5" -o "$WORK/r_${n}_ceres.h5" --json "$WORK/r_${n}_ceres.json" \
        --max-iter "$CERES_ITER" --tol 1e-12 --gradient-tol 1e-12 --parameter-tol 1e-12 --threads 1 -q \
        > "$WORK/r_${n}_ceres.txt" 2>&1
      ran="$ran ceres"
      continue
    fi
    out=$WORK/r_${n}_$m.h5
    # shellcheck disable=SC2046
    mpirun -np "$NP" "$SNL" solve "$net" -o "$out" --json "$WORK/r_${n}_$m.json" -q $(method_args "$m") > "$WORK/r_${n}_$m.txt" 2>&1
    ran="$ran $m"
    if [ "$CRLB" = 1 ] && [ "$crlb" = nan ]; then
      "$SNL" eval "$net" "$out" --crlb --no-covariance --json "$WORK/eval_$n.json" > "$WORK/eval_$n.txt"
      crlb=$("$PY" -c "import json,sys; d=json.load(open(sys.argv[1])); print(d['crlb_rmse'] if d.get('crlb_defined') else float('nan'))" "$WORK/eval_$n.json")
    fi
  done
  "$PY" - "$WORK" "$n" "$crlb" "$ran" <<'EOF'
import json, sys, os
work, n, crlb, methods = sys.argv[1], sys.argv[2], float(sys.argv[3]), sys.argv[4].split()
rows = {m: json.load(open(os.path.join(work, f"r_{n}_{m}.json"))) for m in methods}
best = min(d["ml_cost"] for d in rows.values())
print(f"\nn = {n}: RMSE_CRLB over the localizable sensors = {crlb:.6g}; lowest ML cost of the rows {best:.10g}")
print(f"{'method':8} {'wall':>8} {'read':>6} {'setup':>6} {'start':>6} {'iterate':>8} {'write':>6} {'iters':>7} "
      f"{'exchanges':>9} {'tests':>5} {'msg/sensor':>10} {'ml_cost':>16} {'excess':>9} {'rmse':>9} {'rmse/crlb':>9}")
for m, d in rows.items():
    if m == "ceres":  # its start is a separate snl run; exchanges and messages: a central solver has none
        s = json.load(open(os.path.join(work, f"r_{n}_ceres_start.json")))
        wall = d["wall_seconds"] + s["wall_seconds"]
        print(f"{m:8} {wall:8.2f} {d['read_seconds']:6.2f} {d['setup_seconds']:6.2f} "
              f"{s['wall_seconds']:6.2f} {d['solve_seconds']:8.2f} {d['write_seconds']:6.2f} {d['iterations']:7d} "
              f"{'-':>9} {'-':>5} {'-':>10} {d['ml_cost']:16.10g} {(d['ml_cost'] - best) / best:9.2e} "
              f"{d['rmse']:9.6f} {d['rmse_localizable'] / crlb:9.3f}")
        continue
    ex = d["mpi_bytes"] / d["halo_bytes_per_iteration"] if d.get("halo_bytes_per_iteration") else float("nan")
    ex += d.get("start_rounds", 0)
    print(f"{m:8} {d['wall_seconds']:8.2f} {d['read_seconds']:6.2f} {d['setup_seconds']:6.2f} "
          f"{d.get('start_seconds', 0.0):6.2f} {d['solve_seconds']:8.2f} "
          f"{d['write_seconds']:6.2f} {d['iterations']:7d} {ex:9.0f} {d['gradient_tests']:5d} {d['communications_per_sensor']:10.0f} "
          f"{d['ml_cost']:16.10g} {(d['ml_cost'] - best) / best:9.2e} {d['rmse']:9.6f} {d['rmse_localizable'] / crlb:9.3f}")
EOF
  stream "after n = $n"
done
