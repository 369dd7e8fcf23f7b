#!/usr/bin/env bash
# Bad consensus problems end to end (docs/consensus.md, "Problem file"): every
# rule of the format, a disconnected graph, non-positive parameters, a
# truth_path that is not a Hamilton path, and bad options of `consensus
# generate` and `consensus solve`. Each ends in exactly one clear error line
# naming the attribute or dataset, a non-zero exit (no crash, no hang) on 1 and 3
# ranks, and an existing output file keeps its bytes.
source "$(dirname "$0")/common.bash"
"$SNL" consensus generate -o "$T/exp.h5" --nodes 30 --hamiltonian --seed 3 -q
"$SNL" consensus generate -o "$T/quad.h5" --nodes 30 --family quadratic --dim 2 --seed 3 -q
"$SNL" consensus generate -o "$T/logi.h5" --nodes 30 --family logistic --dim 2 --samples-per-node 4 --seed 3 -q
mkdir "$T/bad"

# Each case: a copy of a good file changed with h5py; the list gives
# "file<TAB>word the error must contain".
"$PY" - "$T" > "$T/list" <<'PYEOF'
import shutil, sys
import h5py, numpy as np
T = sys.argv[1]
cases = []

def case(name, base, word, change):
    path = f"{T}/bad/{name}.h5"
    shutil.copy(f"{T}/{base}.h5", path)
    with h5py.File(path, "r+") as f:
        change(f)
    cases.append((path, word))

def setattr_(key, value):
    def c(f):
        if value is None:
            del f.attrs[key]
        else:
            f.attrs[key] = value
    return c

def replace(name, fn):
    def c(f):
        data = fn(f[name][()]) if name in f else fn(None)
        del f[name]
        if data is not None:
            f[name] = data
    return c

def setrow(name, index, value):
    def c(f):
        d = f[name][()]
        d[index] = value
        f[name][...] = d
    return c

# Root attributes: missing, wrong type, wrong value.
for key in ["format", "version", "num_nodes", "dim", "family"]:
    case(f"attr_missing_{key}", "exp", key, setattr_(key, None))
case("attr_format_value", "exp", "format", setattr_("format", "snl-network"))
case("attr_format_type", "exp", "format", setattr_("format", np.int64(1)))
case("attr_version_value", "exp", "version", setattr_("version", np.int64(2)))
case("attr_num_nodes_type", "exp", "num_nodes", setattr_("num_nodes", "30"))
case("attr_num_nodes_small", "exp", "num_nodes", setattr_("num_nodes", np.int64(1)))
case("attr_num_nodes_fraction", "exp", "num_nodes", setattr_("num_nodes", 29.5))
case("attr_dim_zero", "quad", "dim", setattr_("dim", np.int64(0)))
case("attr_dim_exp", "exp", "dim", setattr_("dim", np.int64(2)))
case("attr_family_value", "exp", "family", setattr_("family", "cubic"))
case("attr_family_type", "exp", "family", setattr_("family", np.float64(1.0)))
case("attr_lambda_missing", "logi", "lambda", setattr_("lambda", None))
case("attr_lambda_zero", "logi", "lambda", setattr_("lambda", 0.0))
case("attr_lambda_negative", "logi", "lambda", setattr_("lambda", -1.0))
case("attr_lambda_nan", "logi", "lambda", setattr_("lambda", np.nan))
case("attr_lambda_type", "logi", "lambda", setattr_("lambda", "one"))
# num_nodes larger than the data: truth_path is the first dataset checked against n.
case("attr_num_nodes_larger", "exp", "truth_path", setattr_("num_nodes", np.int64(31)))
# edges
case("edges_missing", "exp", "edges", replace("edges", lambda d: None))
case("edges_shape", "exp", "edges", replace("edges", lambda d: np.zeros((d.shape[0], 3), np.int64)))
case("edges_1d", "exp", "edges", replace("edges", lambda d: d[:, 0].copy()))
case("edges_float", "exp", "edges", replace("edges", lambda d: d.astype(np.float64)))
case("edges_out_of_range", "exp", "edges", setrow("edges", (4, 1), 30))
case("edges_negative", "exp", "edges", setrow("edges", (5, 0), -1))
case("edges_self_loop", "exp", "self-loop", replace("edges", lambda d: np.concatenate([d, [[7, 7]]]).astype(np.int64)))
case("edges_duplicate", "exp", "edges", replace("edges", lambda d: np.concatenate([d, d[3:4]]).astype(np.int64)))
case("edges_duplicate_reversed", "exp", "edges",
     replace("edges", lambda d: np.concatenate([d, d[3:4, ::-1]]).astype(np.int64)))
case("edges_none", "quad", "edges", replace("edges", lambda d: np.zeros((0, 2), np.int64)))

def cut_node(v):
    def fn(d):
        return d[(d[:, 0] != v) & (d[:, 1] != v)].copy()
    return fn
case("disconnected", "quad", "not connected", replace("edges", cut_node(11)))
# exp parameters: every one must be finite and > 0, with [n] shape.
for p in "abcd":
    for tag, v in [("zero", 0.0), ("negative", -0.5), ("nan", np.nan), ("inf", np.inf)]:
        case(f"exp_{p}_{tag}", "exp", f"exp_{p}", setrow(f"exp_{p}", 9, v))
    case(f"exp_{p}_missing", "exp", f"exp_{p}", replace(f"exp_{p}", lambda d: None))
case("exp_b_shape", "exp", "exp_b", replace("exp_b", lambda d: d[:-1].copy()))
case("exp_c_2d", "exp", "exp_c", replace("exp_c", lambda d: d.reshape(-1, 1).copy()))
case("exp_foreign_quad_h", "exp", "quad_h", lambda f: f.create_dataset("quad_h", data=np.ones((30, 1))))
# truth_path
case("truth_path_repeat", "exp", "truth_path",
     replace("truth_path", lambda d: np.concatenate([d[:6], d[5:6], d[7:]]).astype(np.int64)))
case("truth_path_out_of_range", "exp", "truth_path", setrow("truth_path", 3, 30))
case("truth_path_shape", "exp", "truth_path", replace("truth_path", lambda d: d[:-1].copy()))

def not_a_path(f):
    # A permutation that is not a path of the graph: swap two path positions
    # so that some consecutive pair is not a link.
    d = f["truth_path"][()]
    e = {tuple(sorted(r)) for r in f["edges"][()].tolist()}
    n = len(d)
    for i in range(1, n - 1):
        for j in range(i + 2, n - 1):
            t = d.copy()
            t[i], t[j] = t[j], t[i]
            if any(tuple(sorted((int(t[k - 1]), int(t[k])))) not in e for k in range(1, n)):
                f["truth_path"][...] = t
                return
    raise SystemExit("no swap breaks the path")
case("truth_path_not_a_path", "exp", "truth_path", not_a_path)
# quadratic
case("quad_h_zero", "quad", "quad_h", setrow("quad_h", (4, 1), 0.0))
case("quad_h_negative", "quad", "quad_h", setrow("quad_h", (4, 0), -2.0))
case("quad_h_nan", "quad", "quad_h", setrow("quad_h", (8, 1), np.nan))
case("quad_r_inf", "quad", "quad_r", setrow("quad_r", (2, 0), np.inf))
# Finite, but f_p or its derivatives at x = 0 overflow: a clear error about the data, not a solver failure.
case("quad_r_huge", "quad", "overflows", setrow("quad_r", (5, 1), 1e200))
case("quad_h_shape", "quad", "quad_h", replace("quad_h", lambda d: d[:, :1].copy()))
case("quad_r_missing", "quad", "quad_r", replace("quad_r", lambda d: None))
# logistic
case("labels_half", "logi", "labels", setrow("labels", 10, 0.5))
case("labels_zero", "logi", "labels", setrow("labels", 11, 0.0))
case("owner_out_of_range", "logi", "owner", setrow("owner", 12, 30))
case("owner_negative", "logi", "owner", setrow("owner", 13, -1))
case("owner_shape", "logi", "owner", replace("owner", lambda d: d[:-1].copy()))
case("features_nan", "logi", "features", setrow("features", (14, 1), np.nan))
case("features_huge", "logi", "overflows", setrow("features", (3, 0), 1e200))
case("features_shape", "logi", "features", replace("features", lambda d: d[:, :1].copy()))
# Not a problem file at all.
with open(f"{T}/bad/not_hdf5.h5", "w") as fh:
    fh.write("this is not HDF5\n")
cases.append((f"{T}/bad/not_hdf5.h5", "not_hdf5"))
for path, word in cases:
    print(f"{path}\t{word}")
PYEOF

"$SNL" consensus solve "$T/quad.h5" -o "$T/keep.h5" --max-iter 2 -q
sum0=$(md5sum < "$T/keep.h5")

# Jobs, one a line: label<TAB>word<TAB>expected status ("any" non-zero, or a number)<TAB>np<TAB>snl arguments.
# They run 4 at a time (a run mostly waits for MPI start-up); each must fail with exactly one
# error line containing the word, never crash or hang, and leave keep.h5 untouched.
: > "$T/jobs"
while IFS=$'\t' read -r f word; do
  name=$(basename "$f" .h5)
  nps="1 3"
  # exp_b..exp_d take exp_a's code path: 1 rank suffices.
  case $name in exp_[bcd]_*) nps=1 ;; esac
  for np in $nps; do
    printf '%s\t%s\tany\t%s\tconsensus solve %s -o %s --max-iter 2 -q\n' "$name np=$np" "$word" "$np" "$f" "$T/keep.h5" >> "$T/jobs"
  done
done < "$T/list"
# Bad options: exit 2 for generate, non-zero for solve.
gen_bad=(
  "--nodes 1|--nodes" "--nodes abc|--nodes" "--nodes 10 --family cubic|--family" "--nodes 10 --dim 2|--dim"
  "--nodes 10 --avg-degree -1|--avg-degree" "--nodes 10 --avg-degree 10|--avg-degree"
  "--nodes 10 --family logistic --lambda 0|--lambda" "--nodes 10 --family logistic --samples-per-node -1|--samples-per-node"
  "--nodes 10 --family quadratic --dim 0|--dim" "--nodes 10 --bogus|--bogus" "--avg-degree 4|--nodes"
)
for entry in "${gen_bad[@]}"; do
  for np in 1 3; do
    printf '%s\t%s\t2\t%s\tconsensus generate -o %s %s\n' "generate ${entry%|*} np=$np" "${entry#*|}" "$np" \
      "$T/keep.h5" "${entry%|*}" >> "$T/jobs"
  done
done
solve_bad=("--method foo|--method" "--dual foo|--dual" "--max-iter -1|--max-iter" "--tol -1|--tol" "--bogus|--bogus"
  "--step wolfe|--step" "--damping 0.5|--damping" "--step damped --damping 1|--damping"
  "--method subgradient --step armijo|--step" "--step 0.5|--step" "--oracle-tol 1e-3|--oracle-tol"
  "--method subgradient --oracle-tol -1|--oracle-tol")
for entry in "${solve_bad[@]}"; do
  for np in 1 3; do
    printf '%s\t%s\tany\t%s\tconsensus solve %s -o %s %s -q\n' "solve ${entry%|*} np=$np" "${entry#*|}" "$np" \
      "$T/quad.h5" "$T/keep.h5" "${entry%|*}" >> "$T/jobs"
  done
done

"$SNL" consensus solve "$T/quad.h5" -o "$T/keep.h5" --max-iter 2 -q
sum0=$(md5sum < "$T/keep.h5")
export T SNL MPIEXEC MPIEXEC_NUMPROC_FLAG sum0

# One failing run: non-zero (not a crash), one error line containing $word, keep.h5 untouched.
check_failure() {
  local label=$1 word=$2 rc=$3 err=$4
  [ "$rc" -ne 124 ] || fail "$label: hang (killed by timeout)"
  [ "$rc" -ne 0 ] || fail "$label: accepted"
  [ "$rc" -lt 128 ] || fail "$label: crashed (status $rc)"
  local nerr
  nerr=$(grep -c '^snl: error: ' "$err" || true)
  [ "$nerr" -eq 1 ] || { cat "$err"; fail "$label: expected exactly one error line, got $nerr"; }
  grep -q "internal error" "$err" && fail "$label: internal error instead of a clear message"
  grep '^snl: error: ' "$err" | grep -q -- "$word" || { cat "$err"; fail "$label: error does not mention '$word'"; }
  [ "$(md5sum < "$T/keep.h5")" = "$sum0" ] || fail "$label: existing output was modified"
  if ls "$T"/keep.h5.* > /dev/null 2>&1; then fail "$label: temporary file left behind"; fi
  return 0
}
run_job() {
  local label word expect np args rc err
  IFS=$'\t' read -r label word expect np args <<< "$1"
  err=$(mktemp "$T/err.XXXXXX")
  set +e
  # shellcheck disable=SC2086
  timeout 60 "$MPIEXEC" "$MPIEXEC_NUMPROC_FLAG" "$np" --oversubscribe "$SNL" $args < /dev/null > /dev/null 2> "$err"
  rc=$?
  set -e
  check_failure "$label" "$word" "$rc" "$err"
  [ "$expect" = any ] || [ "$rc" -eq "$expect" ] || fail "$label: exit status $rc, expected $expect"
}
export -f check_failure run_job fail
xargs -d '\n' -n 1 -P "${JOBS:-4}" bash -c 'set -euo pipefail; run_job "$1"' _ < "$T/jobs" \
  || fail "some failing run misbehaved (messages above)"
n=$(wc -l < "$T/jobs")
[ "$(md5sum < "$T/keep.h5")" = "$sum0" ] || fail "existing output was modified"
echo "consensus_bad_input: $n failing runs checked"

# A missing problem file, and an output directory that does not exist.
set +e
mpi 3 "$SNL" consensus solve "$T/nope.h5" -o "$T/keep.h5" -q > "$T/out" 2> "$T/err"; rc=$?
set -e
check_failure "missing problem" "nope.h5" $rc "$T/err"
set +e
mpi 3 "$SNL" consensus generate -o "$T/nodir/p.h5" --nodes 10 > "$T/out" 2> "$T/err"; rc=$?
set -e
[ "$rc" -ne 0 ] && [ "$rc" -lt 128 ] && grep -q "does not exist" "$T/err" || fail "generate: missing output directory not reported"
# A good generate replaces the output (atomic rename) and is readable.
"$SNL" consensus generate -o "$T/keep.h5" --nodes 12 -q
"$SNL" consensus solve "$T/keep.h5" -o "$T/r.h5" -q
echo "consensus_bad_input: $((n + 2)) failing runs checked in all"

# `snl consensus --help` lists its commands (exit 0); an unknown command is one error line, exit 2.
"$SNL" consensus --help > "$T/help" || fail "consensus --help: non-zero exit"
grep -q "^  generate " "$T/help" && grep -q "^  solve " "$T/help" || { cat "$T/help"; fail "consensus --help: commands not listed"; }
set +e
"$SNL" consensus frob > /dev/null 2> "$T/err"; rc=$?
set -e
[ "$rc" -eq 2 ] && [ "$(grep -c '^snl: error: ' "$T/err")" -eq 1 ] && grep -q frob "$T/err" ||
  { cat "$T/err"; fail "consensus frob: expected one error line and exit 2 (got $rc)"; }
echo "consensus --help: ok"
