#!/usr/bin/env bash
# The cost of calling snl from Python on a 10-sensor network (docs/python.md):
# the `snl solve` process (MPI start-up, reading, solving, writing), a
# `python3 -c "import snl; snl.solve(...)"` process, and snl.solve alone in a
# running interpreter; the median of REPS runs of each, and the
# solve's own time as the library reports it (solve_seconds).
#   bench/python_overhead.sh > docs/data/python/overhead.txt
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${BUILD:-$ROOT/build-py}
SNL=${SNL:-$BUILD/bin/snl}
PY=${PY:-/usr/bin/python3}
REPS=${REPS:-21}
WORK=${WORK:-$(mktemp -d /tmp/snl_pyo.XXXXXX)}
export PYTHONPATH=$BUILD/python${PYTHONPATH:+:$PYTHONPATH}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
net=$WORK/net10.h5
"$SNL" generate --sensors 10 --seed 1 -o "$net" -q
echo "# python_overhead: $(date -u +%Y-%m-%dT%H:%MZ) $(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo '?') $(nproc) cores; 10 sensors, median of $REPS runs"
"$PY" - "$SNL" "$PY" "$net" "$WORK" "$REPS" <<'PYEOF'
import json, statistics, subprocess, sys, time
snl_exe, py, net, work, reps = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4], int(sys.argv[5])

def wall(cmd):
    t = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True)
    return time.perf_counter() - t

cli = [wall([snl_exe, "solve", net, "-o", f"{work}/r.h5", "-q", "--json", f"{work}/r.json"]) for _ in range(reps)]
cli_solve = json.load(open(f"{work}/r.json"))["solve_seconds"]
script = f"import snl; snl.solve(snl.Network.from_file({net!r}))"
proc = [wall([py, "-c", script]) for _ in range(reps)]
imp = [wall([py, "-c", "import snl"]) for _ in range(reps)]
import snl  # in this interpreter: the call alone
n = snl.Network.from_file(net)
calls, inner = [], []
for _ in range(reps):
    t = time.perf_counter()
    r = snl.solve(n)
    calls.append(time.perf_counter() - t)
    inner.append(r.summary["solve_seconds"])
med = statistics.median
print("| what | median seconds |")
print("|---|---|")
print(f"| `snl solve` process (start, read, solve, write) | {med(cli):.4f} |")
print(f"| its solve alone (--json solve_seconds, last run) | {cli_solve:.6f} |")
print(f"| `python3 -c 'import snl'` process | {med(imp):.4f} |")
print(f"| `python3 -c` process: import, read, snl.solve | {med(proc):.4f} |")
print(f"| snl.solve call in a running interpreter | {med(calls):.6f} |")
print(f"| its solve alone (summary solve_seconds) | {med(inner):.6f} |")
print(f"| the call minus its solve (setup, start, array conversions) | {med(c - i for c, i in zip(calls, inner)):.6f} |")
PYEOF
