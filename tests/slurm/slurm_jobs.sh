#!/usr/bin/env bash
# The batch scripts of jobs/ under a real (private, one-node) Slurm:
#  a) jobs/solve.sbatch on 2 tasks (mpirun inside the allocation, and srun
#     --mpi=pmix) gives the positions of a direct mpirun -np 2 snl solve;
#  b) a job with --time=2 --signal=B:USR1@40 on a solve slowed to 90 s
#     by a test hook is signalled before its time limit, checkpoints,
#     requeues itself and resumes (maybe several times) until it finishes with
#     the positions of an uninterrupted run; every resumed run starts at the
#     checkpoint's phase and iteration (snl's own progress lines say so);
#  c) jobs/experiment_array.sbatch as a 3-task array, merged by
#     jobs/merge_experiment.py: each task equals a direct snl experiment run
#     with its seed, the merged table holds every row once with its task.
# Exits 77 (reported as skipped) when no private Slurm can be started here.
set -euo pipefail
: "${SNL:?SNL must point to the snl binary}"
HERE=$(cd "$(dirname "$0")" && pwd)
SRC=${SNL_SOURCE_DIR:-$(cd "$HERE/../.." && pwd)}
SNL=$(readlink -f "$SNL")
PY=/usr/bin/python3
SKIP=77
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
# shellcheck source=tests/slurm/private_slurm.bash
source "$HERE/private_slurm.bash"

T=$(mktemp -d "${TMPDIR:-/tmp}/snl_slurm.XXXXXX")
cleanup() {
  local rc=$?
  slurm_down
  if [ $rc -ne 0 ] && [ $rc -ne $SKIP ]; then slurm_logs; echo "scratch kept in $T"; else rm -rf "$T"; fi
}
trap cleanup EXIT
trap 'exit 1' INT TERM
fail() { echo "FAIL: $*" >&2; exit 1; }
t0=$SECONDS
step() { echo "[$((SECONDS - t0)) s] $*"; }

if ! slurm_up "$T/slurm"; then
  echo "skipped: no private Slurm: $SLURM_WHY"
  exit $SKIP
fi
step "private Slurm up: $(sinfo -h -o '%P %D %c %t') (SLURM_CONF=$SLURM_CONF)"
cd "$T"

# Submit a job and wait for it (at most LIMIT seconds); prints its id. Runs in
# $(...): callers add "|| exit 1" so that a failure here ends the test.
submit_wait() {
  local limit=$1 out
  shift
  out=$(timeout "$limit" sbatch --wait --parsable "$@") || {
    squeue -h 2> /dev/null || true
    fail "sbatch --wait $* did not finish within $limit s or the job failed (${out:-no id})"
  }
  echo "${out%%;*}"
}
job_field() { scontrol -o show job "$1" | tr ' ' '\n' | sed -n "s/^$2=//p" | head -1; }
# A job's state once it has left COMPLETING (sbatch --wait returns when the
# batch script ends; Slurm may still be completing the job's steps then).
final_state() {
  local s i
  for i in $(seq 60); do
    s=$(job_field "$1" JobState)
    [ "$s" = COMPLETING ] || break
    sleep 1
  done
  echo "$s"
}
same_positions() { h5diff "$1" "$2" /positions /positions > /dev/null || fail "$3: positions differ ($1 vs $2)"; }

# ---- a) solve.sbatch on 2 tasks equals a direct 2-rank run.
NET=$SRC/inputs/net50_s0.05.h5
mpirun -np 2 "$SNL" solve "$NET" -o direct.h5 --max-iter 3000 --tol 1e-6 -q  # the default, dv-pipeline, as the job
for launcher in mpirun srun; do
  id=$(submit_wait 120 --ntasks=2 --time=5 -o "a_$launcher.log" \
    --export="ALL,SNL=$SNL,NET=$NET,OUT=$T/a_$launcher.h5,MAXITER=3000,TOL=1e-6,LAUNCHER=$launcher" \
    "$SRC/jobs/solve.sbatch") || exit 1
  [ "$(final_state "$id")" = COMPLETED ] || fail "solve job ($launcher) state $(final_state "$id")"
  [ -f "a_$launcher.ckpt.h5" ] || true  # --checkpoint-seconds 600: none for a short run
  same_positions direct.h5 "a_$launcher.h5" "solve.sbatch with $launcher"
  step "a) solve.sbatch ($launcher inside the allocation) == direct mpirun -np 2"
done

# ---- c) the Monte Carlo array and its merge.
id=$(submit_wait 120 --array=0-2 -o 'mc_%a.log' \
  --export="ALL,SNL=$SNL,NET=$SRC/inputs/net10_s0.05.h5,DIR=$T/mc,SIGMAS=0.01 0.05,TRIALS=2,SEED0=40,EXTRA=--budget 2000" \
  "$SRC/jobs/experiment_array.sbatch") || exit 1
for task in 0 1 2; do
  f=mc/task-$task.seed-$((40 + task)).csv
  [ -f "$f" ] || fail "array task $task wrote no $f"
  "$SNL" experiment "$SRC/inputs/net10_s0.05.h5" -o "direct_$task.csv" --seed $((40 + task)) \
    --sigmas 0.01 0.05 --trials 2 --algorithms mm bb --budget 2000 -q > /dev/null
  cmp -s "$f" "direct_$task.csv" || fail "array task $task differs from snl experiment --seed $((40 + task))"
done
cmp -s mc/task-0.seed-40.csv mc/task-1.seed-41.csv && fail "array tasks 0 and 1 drew the same noise"
$PY "$SRC/jobs/merge_experiment.py" mc/merged.csv mc/task-*.csv
$PY - mc/merged.csv mc/task-*.csv <<'PY' || fail "merged table is not the tasks' rows with task and seed"
import csv, re, sys
merged = list(csv.reader(open(sys.argv[1])))
expect = []
for path in sorted(sys.argv[2:], key=lambda p: int(re.search(r"task-(\d+)", p).group(1))):
    task, seed = re.search(r"task-(\d+)\.seed-(\d+)", path).groups()
    rows = list(csv.reader(open(path)))
    header = ["task", "seed"] + rows[0]
    expect += [[task, seed] + r for r in rows[1:]]
assert merged[0] == header, merged[0]
assert merged[1:] == expect, "rows differ"
assert len(expect) == 3 * 2 * 2 * 3, len(expect)  # tasks x sigmas x trials x (relaxation, mm, bb)
PY
# A task with another header, or a task id twice, is refused and writes nothing.
mkdir bad
sed '1s/^sigma,/noise,/' mc/task-1.seed-41.csv > bad/task-1.seed-41.csv
cp mc/task-2.seed-42.csv bad/task-2.seed-99.csv
for set in "mc/task-0.seed-40.csv bad/task-1.seed-41.csv" "mc/task-2.seed-42.csv bad/task-2.seed-99.csv"; do
  # shellcheck disable=SC2086
  $PY "$SRC/jobs/merge_experiment.py" bad/merged.csv $set 2> /dev/null && fail "merge accepted $set"
  [ ! -e bad/merged.csv ] || fail "a refused merge wrote its output"
done
step "c) experiment_array.sbatch: 3 tasks == direct runs with their seeds; merge checked"

# ---- b) time limit: signal, checkpoint, requeue, resume.
# --time=2 --signal=B:USR1@40: the signal is due 80 s into every run, and
# Slurm may send it up to 60 s early (sbatch(1); at its periodic check of time
# limits), so it comes 20-80 s in: after the solve has started (with @110 it
# came at once and killed the batch shell before its trap, or was lost while
# the job started). The job's 2 x MAXITER iterations sleep DELAY s each (snl's
# test hook SNL_TEST_ITERATION_DELAY), so a run would take 90 s whatever the
# machine's load, under the 120 s limit: the first run is always stopped, and
# how far each run gets before its signal varies.
MAXITER=1000
DELAY=0.045
mpirun -np 2 "$SNL" solve "$NET" -o ref.h5 --algorithm pipeline --max-iter "$MAXITER" --tol 0 -q ||
  fail "reference run failed"
step "b) uninterrupted reference run (--max-iter $MAXITER) done"
id=$(submit_wait 900 --ntasks=2 --time=2 --signal=B:USR1@40 -o b.log \
  --export="ALL,SNL=$SNL,NET=$NET,OUT=$T/b.h5,ALG=pipeline,MAXITER=$MAXITER,TOL=0,SNL_TEST_ITERATION_DELAY=$DELAY" \
  "$SRC/jobs/solve.sbatch") || exit 1
restarts=$(job_field "$id" Restarts)
step "b) time-limited job $id finished after $restarts requeues"
grep '^snl-solve:' b.log
[ "$(final_state "$id")" = COMPLETED ] || fail "time-limited job state $(final_state "$id")"
if [ "${restarts:-0}" -eq 0 ]; then
  grep -q 'stopped by a signal' b.log && fail "the job was stopped by Slurm's signal but not requeued"
  fail "the time-limited job was never signalled"
fi
[ "$(grep -c 'requeueing job' b.log)" -eq "$restarts" ] || fail "requeue count in the log differs from Slurm's"
# Every resumed run must start where its checkpoint stopped: the first progress
# line after "resuming from ... (PHASE iteration K)" is PHASE at >= K, or a later phase.
awk -v want_resumes="$restarts" '
  function rank(ph) { return ph == "relaxation" ? 0 : (ph == "mm" || ph == "mm-accel") ? 1 : -1 }
  /^snl-solve: resuming from/ {
    if (pending) { print "no progress line after a resume"; bad = 1 }
    ph = $(NF - 2); sub(/^\(/, "", ph); k = $NF; sub(/\)$/, "", k)
    if (k !~ /^[0-9]+$/ || rank(ph) < 0 || (rank(ph) == 0 && k == 0)) { print "bad resume line: " $0; bad = 1 }
    pending = 1; n++; next
  }
  pending && /^(relaxation|mm|mm-accel) +[0-9]+ / {
    if (rank($1) < rank(ph) || (rank($1) == rank(ph) && $2 + 0 < k + 0)) {
      print "resumed run restarted from scratch: checkpoint " ph " " k ", first progress " $1 " " $2; bad = 1
    }
    pending = 0
  }
  END {
    if (pending) { print "no progress line after the last resume"; bad = 1 }
    if (n != want_resumes) { print n " resumes in the log, " want_resumes " requeues"; bad = 1 }
    exit bad
  }' b.log || fail "the requeued runs did not resume from their checkpoints (see above)"
same_positions ref.h5 b.h5 "signalled, requeued and resumed job"
step "b) positions equal the uninterrupted run's"
echo "slurm_jobs: all checks passed in $((SECONDS - t0)) s"
