#!/usr/bin/env bash
# Scale check of `snl eval --crlb` (rigid-part identification, sparse LDL^T,
# selected inversion for the per-sensor covariances, group crlb written to the
# result file) on random 2D networks of N sensors, average degree 10, 1% random
# anchors, sigma 0.0003, the result being the true positions (a copy of the
# truth as a result file, so no solve is timed).
#
#   bench/crlb_scale.sh [BUILD_DIR] [OUT_FILE] [N...]
#   (default: build, docs/data/crlb/crlb-scale.txt, 10000 100000)
# Wall times and peak memory from /usr/bin/time; the machine is shared, so the
# times are noisy. The covered counts and RMSE_CRLB are deterministic.
set -euo pipefail
B=${1:-build}
OUT=${2:-docs/data/crlb/crlb-scale.txt}
shift $(( $# > 2 ? 2 : $# )) || true
SIZES=("$@")
[ ${#SIZES[@]} -eq 0 ] && SIZES=(10000 100000)
W=$(mktemp -d /tmp/snl_crlb_scale.XXXXXX)
trap 'rm -rf "$W"' EXIT
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
{
  echo "# snl eval --crlb scale check, $(date -u +%Y-%m-%d), $(nproc) cores shared with other jobs (timings noisy)"
  echo "# generate --avg-degree 10 --anchors N/100 --sigma 0.0003 --seed 1 --localizable no; result = truth"
  for n in "${SIZES[@]}"; do
    "$B/bin/snl" generate -o "$W/net.h5" --sensors "$n" --avg-degree 10 --anchors $((n / 100)) --sigma 0.0003 \
      --seed 1 --localizable no -q
    /usr/bin/python3 - "$W/net.h5" "$W/res.h5" <<'PYEOF'
import sys, h5py
with h5py.File(sys.argv[1], "r") as a, h5py.File(sys.argv[2], "w") as b:
    t = a["truth"][()]
    b.attrs["format"] = "snl-result"; b.attrs["version"] = 1; b.attrs["algorithm"] = "truth"
    b.attrs["iterations"] = 0; b.attrs["converged"] = 1; b.attrs["dim"] = t.shape[1]; b.attrs["num_sensors"] = t.shape[0]
    b["positions"] = t
PYEOF
    echo "## n = $n"
    /usr/bin/time -f "wall_seconds %e  user_seconds %U  sys_seconds %S  max_rss_kb %M" "$B/bin/snl" eval "$W/net.h5" "$W/res.h5" --crlb \
      --json "$W/ev.json" 2>&1 | grep -E "Cramer|outside|wall_seconds" | cut -c1-200
    /usr/bin/python3 -c "
import sys, json, h5py, numpy as np
d = json.load(open(sys.argv[1])); f = h5py.File(sys.argv[2], 'r')
c = f['crlb/covariance'][()][f['crlb/covered'][()] == 1]
sd = np.sqrt(np.trace(c, axis1=1, axis2=2))
print('crlb_sensors %d  outside %d  crlb_rmse %.6g  per-sensor sqrt(tr C_i): median %.4g, 99th pct %.4g, max %.4g'
      % (d['crlb_sensors'], len(d['crlb_outside']), d['crlb_rmse'], np.median(sd), np.percentile(sd, 99), sd.max()))" \
      "$W/ev.json" "$W/res.h5"
  done
} | tee "$OUT"
