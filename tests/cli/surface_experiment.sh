#!/usr/bin/env bash
# snl experiment's tables hold the values they promise (docs/formats.md,
# "Experiment outputs"), not just an exit code:
#  - per-trial CSV: exactly the documented columns; one row per sigma, trial
#    and method, plus the relaxation's starting row with --start relaxation;
#    every value finite; refinements within the communication budget and
#    counted as BB's 2T + p / MM's p reals per iteration; ml_cost_start the
#    relaxation row's ml_cost; the relaxation's RMSE (mean over trials) at a
#    small sigma below that at a large sigma;
#  - trajectory CSV: one run per refinement row, reals per sensor starting at
#    0 and strictly increasing, ML cost starting at ml_cost_start and ending at
#    the row's ml_cost and reals;
#  - --h5: the same table as columns; the same files on 1 and 2 ranks;
#  - --start random: every listed method from one start, no extra rows;
#    relaxation listed with --start relaxation is refused.
source "$(dirname "$0")/common.bash"
"$SNL" generate -o "$T/net.h5" --sensors 60 --avg-degree 10 --anchors 12 --anchor-radius 0.5 --sigma 0.01 --seed 4 -q
args=(--sigmas 0.002 0.3 --trials 3 --algorithms mm bb --budget 400 --bb-rounds 5 --seed 2 -q)
"$SNL" experiment "$T/net.h5" -o "$T/e1.csv" --trajectory "$T/t1.csv" --h5 "$T/e1.h5" "${args[@]}" > /dev/null
mpi 2 "$SNL" experiment "$T/net.h5" -o "$T/e2.csv" --trajectory "$T/t2.csv" "${args[@]}" > /dev/null
cmp -s "$T/e1.csv" "$T/e2.csv" || fail "experiment: per-trial CSV differs between 1 and 2 ranks"
cmp -s "$T/t1.csv" "$T/t2.csv" || fail "experiment: trajectory CSV differs between 1 and 2 ranks"

"$PY" - "$T/e1.csv" "$T/t1.csv" "$T/e1.h5" <<'EOF' || fail "experiment (--start relaxation): wrong tables"
import csv, math, sys
import h5py
rows = list(csv.DictReader(open(sys.argv[1])))
traj = list(csv.DictReader(open(sys.argv[2])))
cols = "sigma,trial,algorithm,iterations,messages_per_sensor,reals_per_sensor,ml_cost_start,ml_cost,rmse,mpe,fhat,objective".split(",")
errors = []
def check(cond, msg):
    if not cond: errors.append(msg)
check(list(rows[0].keys()) == cols, "columns %s" % list(rows[0].keys()))
sigmas, trials, methods, budget, p, T = ["0.002", "0.3"], 3, ["mm", "bb"], 400, 2, 5
check(len(rows) == len(sigmas) * trials * (len(methods) + 1), "%d rows" % len(rows))
keys = [(r["sigma"], int(r["trial"]), r["algorithm"]) for r in rows]
check(sorted(keys) == sorted((s, t, a) for s in sigmas for t in range(trials) for a in methods + ["relaxation"]),
      "rows are not one per sigma, trial and method: %s" % keys)
for r in rows:
    for c in cols[3:]:
        check(math.isfinite(float(r[c])), "%s %s not finite" % (r, c))
start = {(r["sigma"], r["trial"]): r for r in rows if r["algorithm"] == "relaxation"}
for r in rows:
    if r["algorithm"] == "relaxation":
        continue
    k, reals = int(r["iterations"]), float(r["reals_per_sensor"])
    per_iter = p + 2 * T if r["algorithm"] == "bb" else p
    check(0 < reals <= budget, "reals %s over the budget" % r)
    check(reals == k * per_iter, "reals %s != %d iterations x %d" % (r, k, per_iter))
    check(r["ml_cost_start"] == start[(r["sigma"], r["trial"])]["ml_cost"], "start cost %s" % r)
    run = [t for t in traj if (t["sigma"], t["trial"], t["algorithm"]) == (r["sigma"], r["trial"], r["algorithm"])]
    check(len(run) >= 2, "no trajectory for %s" % r)
    x = [float(t["reals_per_sensor"]) for t in run]
    check(x[0] == 0 and all(b > a for a, b in zip(x, x[1:])), "trajectory reals not increasing from 0: %s" % x)
    check(x[-1] == reals, "trajectory ends at %s, row says %s" % (x[-1], reals))
    check(run[0]["ml_cost"] == r["ml_cost_start"] and run[-1]["ml_cost"] == r["ml_cost"], "trajectory costs %s" % r)
    check(all(math.isfinite(float(t["ml_cost"])) for t in run), "non-finite trajectory cost")
for r in rows:  # f_hat underestimates f; the relaxation's own objective is f_hat
    check(float(r["fhat"]) <= float(r["ml_cost"]) * (1 + 1e-12), "fhat above the ML cost %s" % r)
    if r["algorithm"] == "relaxation":
        check(r["fhat"] == r["objective"], "relaxation objective is not fhat %s" % r)
check(len(traj) == sum(1 for t in traj if (t["sigma"], t["trial"], t["algorithm"]) in
      {(s, str(t_), a) for s, t_, a in keys if a != "relaxation"}), "trajectory of a run not in the table")
rmse = {s: sum(float(r["rmse"]) for r in rows if r["sigma"] == s and r["algorithm"] == "relaxation") / trials
        for s in sigmas}
check(rmse["0.002"] < 0.5 * rmse["0.3"], "relaxation RMSE %s" % rmse)
h = h5py.File(sys.argv[3], "r")
for c in ["sigma", "trial", "iterations", "reals_per_sensor", "ml_cost", "rmse", "mpe", "fhat", "objective"]:
    check(len(h[c]) == len(rows) and all(abs(a - float(r[c])) <= 1e-8 * max(1, abs(a)) for a, r in zip(h[c][:], rows)),
          "--h5 column " + c)  # the CSV has 10 significant digits
code = {"relaxation": 0, "mm": 1, "bb": 2}
check(list(h["algorithm"][:]) == [code[r["algorithm"]] for r in rows], "--h5 algorithm codes")
for e in errors[:10]: print("  " + e, file=sys.stderr)
sys.exit(1 if errors else 0)
EOF

# --start random: the listed methods only, each from the same start.
"$SNL" experiment "$T/net.h5" -o "$T/r.csv" --trajectory "$T/rt.csv" --start random --sigmas 0.01 --trials 2 \
  --algorithms relaxation mm bb --budget 200 -q > /dev/null
"$PY" - "$T/r.csv" <<'EOF' || fail "experiment --start random: wrong table"
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
ok = len(rows) == 1 * 2 * 3 and sorted(r["algorithm"] for r in rows) == sorted(["relaxation", "mm", "bb"] * 2)
for t in ("0", "1"):
    ok &= len({r["ml_cost_start"] for r in rows if r["trial"] == t}) == 1
ok &= rows[0]["ml_cost_start"] != rows[-1]["ml_cost_start"]  # a new start per trial
sys.exit(0 if ok else 1)
EOF
# With --start relaxation the relaxation rows are the starting points: listing
# relaxation as a method too would mix two runs into one row of the aggregate.
rc=0
"$SNL" experiment "$T/net.h5" -o "$T/dup.csv" --algorithms relaxation mm --trials 1 -q 2> "$T/err" || rc=$?
[ $rc -ne 0 ] && grep -q "snl: error: .*--start random" "$T/err" && [ ! -e "$T/dup.csv" ] \
  || fail "experiment --algorithms relaxation with --start relaxation: rc $rc, $(cat "$T/err")"
echo "surface_experiment: ok"
