#!/usr/bin/env bash
# Time to solution: end to end (read, setup, iterate, write) on the default
# networks (`snl generate --sensors N`), one row per method, with the
# communication rounds and the accuracy of the answer beside the wall time.
#
#   SIZES="100000 1000000" NP=2 WORK=/tmp/tts bench/time_to_solution.sh > out.txt
#
# Methods (rows):
#   papers    003 + 000 as published: relaxation, then plain MM, papers' stopping
#             rule (--refine mm --stop papers);
#   default   `snl solve` with its defaults;
#   mm        plain MM (000) from the random start, the default stopping rule.
# (Ceres LM from the same relaxation output: bench/ceres/compare.sh, docs/ceres.md.)
# Columns: wall, read, setup, iterate and write seconds (the solve's JSON),
# iterations, the iterations' halo exchanges (the algorithm's MPI bytes over the
# bytes of one exchange), gradient tests (one more exchange each), messages per sensor,
# final ML cost, RMSE, and RMSE over the CRLB on the localizable sensors
# (`snl eval --crlb`, once per network; CRLB=0 skips it).
# Duration: about 1 minute at 10^5 sensors, 10-15 minutes at 10^6 (the
# default pipeline alone takes minutes there), an hour at 10^7 on 2 cores.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
SNL=${SNL:-$ROOT/build/bin/snl}
SIZES=${SIZES:-100000}
NP=${NP:-2}
WORK=${WORK:-$(mktemp -d /tmp/snl_tts.XXXXXX)}
METHODS=${METHODS:-"papers default mm"}
CRLB=${CRLB:-1}
PY=/usr/bin/python3
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
mkdir -p "$WORK"

method_args() {
  case $1 in
    papers) echo "--refine mm --stop papers" ;;
    default) echo "" ;;
    mm) echo "--algorithm mm" ;;
    *) echo "unknown method $1" >&2; exit 2 ;;
  esac
}

echo "# time_to_solution: $(date -u +%Y-%m-%dT%H:%MZ) $(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo '?') np=$NP host=$(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')"
for n in $SIZES; do
  net=$WORK/net_$n.h5
  [ -f "$net" ] || "$SNL" generate -o "$net" --sensors "$n" > "$WORK/gen_$n.txt"
  crlb=nan
  for m in $METHODS; do
    out=$WORK/r_${n}_$m.h5
    # shellcheck disable=SC2046
    mpirun -np "$NP" "$SNL" solve "$net" -o "$out" --json "$WORK/r_${n}_$m.json" -q $(method_args "$m") > "$WORK/r_${n}_$m.txt" 2>&1
    if [ "$CRLB" = 1 ] && [ "$crlb" = nan ]; then
      "$SNL" eval "$net" "$out" --crlb --no-covariance --json "$WORK/eval_$n.json" > "$WORK/eval_$n.txt"
      crlb=$("$PY" -c "import json,sys; d=json.load(open(sys.argv[1])); print(d['crlb_rmse'] if d.get('crlb_defined') else float('nan'))" "$WORK/eval_$n.json")
    fi
  done
  "$PY" - "$WORK" "$n" "$crlb" "$METHODS" <<'EOF'
import json, sys, os
work, n, crlb, methods = sys.argv[1], sys.argv[2], float(sys.argv[3]), sys.argv[4].split()
print(f"\nn = {n}: RMSE_CRLB over the localizable sensors = {crlb:.6g}")
print(f"{'method':8} {'wall':>8} {'read':>6} {'setup':>6} {'iterate':>8} {'write':>6} {'iters':>7} {'exchanges':>9} {'tests':>5} "
      f"{'msg/sensor':>10} {'ml_cost':>16} {'rmse':>9} {'rmse/crlb':>9}")
for m in methods:
    d = json.load(open(os.path.join(work, f"r_{n}_{m}.json")))
    ex = d["mpi_bytes"] / d["halo_bytes_per_iteration"] if d.get("halo_bytes_per_iteration") else float("nan")
    solve = d["solve_seconds"]
    print(f"{m:8} {d['wall_seconds']:8.2f} {d['read_seconds']:6.2f} {d['setup_seconds']:6.2f} {solve:8.2f} "
          f"{d['write_seconds']:6.2f} {d['iterations']:7d} {ex:9.0f} {d['gradient_tests']:5d} {d['communications_per_sensor']:10.0f} "
          f"{d['ml_cost']:16.10g} {d['rmse']:9.6f} {d['rmse_localizable'] / crlb:9.3f}")
EOF
done
