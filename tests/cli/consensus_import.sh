#!/usr/bin/env bash
# `snl consensus import` (docs/consensus.md, "Your own data"): CSV tables of
# samples and links -> problem file -> `consensus solve` (default options) ->
# `snl export` CSV, on 1 and 2 ranks, against an optimum computed independently
# with numpy (least squares: the normal equations; logistic: Newton's method),
# to 1e-8 at every node; `snl info` on the problem and the result; and every
# bad input ends with exactly one error line naming the file and line, the
# right exit status (2 bad options, 1 bad data) on 1 and 3 ranks, and an
# existing output keeps its bytes.
source "$(dirname "$0")/common.bash"

# Good data: 13 nodes (node 5 owns no sample, node 12 appears in the links
# only), q = 3; the samples file's columns in a non-default order for the
# second case (label first, node id in the middle).
"$PY" - "$T" <<'PYEOF'
import sys
import numpy as np
T = sys.argv[1]
rng = np.random.default_rng(46)
n, q = 13, 3
owners = [p for p in range(12) if p != 5 for _ in range(int(rng.integers(1, 5)))]
S = len(owners)
A = rng.normal(size=(S, q))
b = A @ np.array([0.7, -1.3, 2.1]) + 0.2 * rng.normal(size=S)
y = np.where(rng.random(S) < 1 / (1 + np.exp(-A @ np.array([1.0, -0.5, 0.25]))), 1.0, -1.0)
def samples(path, target):
    with open(path, "w") as f:
        f.write("node,f0,f1,f2,target\n")
        for p, a, t in zip(owners, A, target):
            f.write(f"{p},{a[0]!r},{a[1]!r},{a[2]!r},{t!r}\n")
samples(f"{T}/ls.csv", b)
samples(f"{T}/logi.csv", y)
with open(f"{T}/ls_reordered.csv", "w") as f:  # label first, node id third
    f.write("b,f0,who,f1,f2\n")
    for p, a, t in zip(owners, A, b):
        f.write(f"{t!r},{a[0]!r},{p},{a[1]!r},{a[2]!r}\n")
edges = [(i, i + 1) for i in range(n - 1)] + [(0, 6), (3, 9), (12, 2)]
with open(f"{T}/edges.csv", "w") as f:
    f.write("i,j\n" + "".join(f"{i},{j}\n" for i, j in edges))
lam = 0.5
# least squares: (2 A^T A + lambda I) x = 2 A^T b
x_ls = np.linalg.solve(2 * A.T @ A + lam * np.eye(q), 2 * A.T @ b)
# logistic: Newton on sum log(1 + e^(-y a.x)) + lambda/2 x.x
x = np.zeros(q)
for _ in range(100):
    m = y * (A @ x)
    s = 1 / (1 + np.exp(m))          # sigmoid(-m)
    g = -(A.T @ (y * s)) + lam * x
    H = (A.T * (s * (1 - s))) @ A + lam * np.eye(q)
    dx = np.linalg.solve(H, g)
    x -= dx
    if np.max(np.abs(dx)) < 1e-15:
        break
np.savetxt(f"{T}/x_ls.txt", x_ls[None, :], fmt="%.17g")
np.savetxt(f"{T}/x_logi.txt", x[None, :], fmt="%.17g")
PYEOF

# check_x CSV WANT: the exported x (header node,x0,x1,x2; one row per node 0..12) against WANT.
check_x() {
  "$PY" - "$1" "$2" <<'PYEOF' || fail "exported x ($1) differs from the independent optimum ($2)"
import sys
import numpy as np
with open(sys.argv[1]) as f:
    header = f.readline().strip()
    assert header == "node,x0,x1,x2", header
rows = np.loadtxt(sys.argv[1], delimiter=",", skiprows=1, ndmin=2)
want = np.loadtxt(sys.argv[2], ndmin=1)
assert rows.shape == (13, 4), rows.shape
assert (rows[:, 0] == np.arange(13)).all(), rows[:, 0]
err = np.max(np.abs(rows[:, 1:] - want[None, :]))
print(f"  max |x_p - x*| = {err:.3g}")
assert err <= 1e-8, err
PYEOF
}

# Round trip on 1 and 2 ranks, for both families and the reordered columns.
for np_ in 1 2; do
  for c in "ls|ls.csv|least_squares|" "logi|logi.csv|logistic|" "reord|ls_reordered.csv|least_squares|--node-column who --label-column b"; do
    IFS='|' read -r name csv fam cols <<< "$c"
    # shellcheck disable=SC2086
    mpi $np_ "$SNL" consensus import --samples "$T/$csv" --edges "$T/edges.csv" --family $fam --lambda 0.5 $cols \
      -o "$T/$name.h5" > "$T/import.out"
    grep -q "n=13, 15 links, family $fam, dim 3" "$T/import.out" || { cat "$T/import.out"; fail "$name: import summary"; }
    grep -q "2 of 13 nodes own no sample" "$T/import.out" || { cat "$T/import.out"; fail "$name: nodes without samples"; }
    mpi $np_ "$SNL" consensus solve "$T/$name.h5" -o "$T/$name.r.h5" -q
    mpi $np_ "$SNL" export "$T/$name.r.h5" -o "$T/$name.x.csv" -q
    want=$T/x_ls.txt
    [ "$fam" = logistic ] && want=$T/x_logi.txt
    echo "$name np=$np_:"
    check_x "$T/$name.x.csv" "$want"
  done
done

# snl info on the problem and on the result.
"$SNL" info "$T/ls.h5" > "$T/info" || fail "info on a consensus problem: non-zero exit"
for w in "family least_squares" "nodes n = 13" "dimension q = 3" "links = 15" "samples = $(($(wc -l < "$T/ls.csv") - 1)) (2 nodes without samples)" "lambda = 0.5" \
  "Hamilton path (truth_path): no"; do
  grep -qF "$w" "$T/info" || { cat "$T/info"; fail "info (problem) lacks '$w'"; }
done
"$SNL" info "$T/ls.r.h5" > "$T/info" || fail "info on a consensus result: non-zero exit"
for w in "snl-consensus-result" "method newton-tree" "converged yes" "nodes n = 13"; do
  grep -qF "$w" "$T/info" || { cat "$T/info"; fail "info (result) lacks '$w'"; }
done
"$SNL" info "$T/ls.r.h5" --json "$T/info.json" > /dev/null
"$PY" -c 'import json, sys; j = json.load(open(sys.argv[1])); assert j["num_nodes"] == 13 and j["dim"] == 3 and j["converged"], j' \
  "$T/info.json" || fail "info --json on a consensus result"
"$SNL" export "$T/ls.r.h5" -o "$T/x1.csv" --index-base 1 -q
[ "$(sed -n 2p "$T/x1.csv" | cut -d, -f1)" = 1 ] && [ "$(tail -n 1 "$T/x1.csv" | cut -d, -f1)" = 13 ] &&
  [ "$(cut -d, -f2- "$T/x1.csv")" = "$(cut -d, -f2- "$T/ls.x.csv")" ] || fail "export --index-base 1"
echo "info: ok"

# ---------------------------------------------------------------------------
# Bad inputs. Each file is a copy of a good one with one line changed.
mkdir "$T/bad"
bad_line() {  # bad_line NAME BASE LINE TEXT: BASE with line LINE replaced by TEXT
  awk -v l="$3" -v t="$4" 'NR == l { print t; next } { print }' "$T/$2" > "$T/bad/$1"
}
bad_line ragged.csv ls.csv 3 "1,0.5,0.25"
bad_line text.csv ls.csv 4 "2,0.5,abc,0.1,1.0"
bad_line nan.csv ls.csv 5 "3,0.5,nan,0.1,1.0"
bad_line inf_label.csv ls.csv 6 "3,0.5,0.2,0.1,inf"
bad_line empty_cell.csv ls.csv 7 "3,0.5,,0.1,1.0"
bad_line neg_node.csv ls.csv 8 "-1,0.5,0.2,0.1,1.0"
bad_line big_node.csv ls.csv 9 "40,0.5,0.2,0.1,1.0"
bad_line frac_node.csv ls.csv 2 "1.5,0.5,0.2,0.1,1.0"
bad_line label_half.csv logi.csv 3 "1,0.5,0.2,0.1,0.5"
bad_line overflow.csv ls.csv 10 "4,0.5,0.2,0.1,1e200"
bad_line dup_header.csv ls.csv 1 "node,f0,f0,f2,target"
bad_line short_header.csv ls.csv 1 "node,target"
bad_line self_loop.csv edges.csv 4 "3,3"
bad_line dup_edge.csv edges.csv 7 "1,0"
bad_line edge_cols.csv edges.csv 3 "1,2,3"
bad_line edge_text.csv edges.csv 5 "4,x"
bad_line edge_neg.csv edges.csv 6 "-2,5"
bad_line edge_big.csv edges.csv 6 "5,99"
head -n 1 "$T/ls.csv" > "$T/bad/header_only.csv"
: > "$T/bad/empty.csv"
# The graph cut in two: every link between {0..5} and {6..12} removed.
awk -F, 'NR == 1 || ($1 < 6) == ($2 < 6)' "$T/edges.csv" > "$T/bad/disconnected.csv"

S=$T/ls.csv E=$T/edges.csv
# "label<TAB>word the error must contain<TAB>exit status<TAB>arguments of consensus import"
cases=(
  "missing samples	nope.csv:	1	--samples $T/nope.csv --edges $E --family least_squares"
  "missing edges	nope.csv:	1	--samples $S --edges $T/nope.csv --family least_squares"
  "ragged row	ragged.csv:3:	1	--samples $T/bad/ragged.csv --edges $E --family least_squares"
  "non-numeric cell	text.csv:4:	1	--samples $T/bad/text.csv --edges $E --family least_squares"
  "NaN	nan.csv:5:	1	--samples $T/bad/nan.csv --edges $E --family least_squares"
  "infinite label	inf_label.csv:6:	1	--samples $T/bad/inf_label.csv --edges $E --family least_squares"
  "empty cell	empty_cell.csv:7:	1	--samples $T/bad/empty_cell.csv --edges $E --family least_squares"
  "negative node	neg_node.csv:8:	1	--samples $T/bad/neg_node.csv --edges $E --family least_squares"
  "node out of range	big_node.csv:9:	1	--samples $T/bad/big_node.csv --edges $E --family least_squares --nodes 13"
  "fractional node id	frac_node.csv:2:	1	--samples $T/bad/frac_node.csv --edges $E --family least_squares"
  "label not +-1	label_half.csv:3:	1	--samples $T/bad/label_half.csv --edges $E --family logistic"
  "targets are not labels	ls.csv:2:	1	--samples $S --edges $E --family logistic"
  "overflow at x = 0	overflow.csv	1	--samples $T/bad/overflow.csv --edges $E --family least_squares"
  "duplicate column name	dup_header.csv:1:	1	--samples $T/bad/dup_header.csv --edges $E --family least_squares"
  "too few columns	short_header.csv:1:	1	--samples $T/bad/short_header.csv --edges $E --family least_squares"
  "header only	header_only.csv:1:	1	--samples $T/bad/header_only.csv --edges $E --family least_squares"
  "empty samples	empty.csv	1	--samples $T/bad/empty.csv --edges $E --family least_squares"
  "self-loop	self_loop.csv:4:	1	--samples $S --edges $T/bad/self_loop.csv --family least_squares"
  "duplicate link	dup_edge.csv:7:	1	--samples $S --edges $T/bad/dup_edge.csv --family least_squares"
  "three columns	edge_cols.csv:3:	1	--samples $S --edges $T/bad/edge_cols.csv --family least_squares"
  "non-integer link	edge_text.csv:5:	1	--samples $S --edges $T/bad/edge_text.csv --family least_squares"
  "negative link	edge_neg.csv:6:	1	--samples $S --edges $T/bad/edge_neg.csv --family least_squares"
  "link out of range	edge_big.csv:6:	1	--samples $S --edges $T/bad/edge_big.csv --family least_squares --nodes 13"
  "disconnected	not connected	1	--samples $S --edges $T/bad/disconnected.csv --family least_squares"
  "output is the samples	names the same file	1	--samples $S --edges $E --family least_squares -o $S"
  "output is the links	names the same file	1	--samples $S --edges $E --family least_squares -o $E"
  "family exp	--family	2	--samples $S --edges $E --family exp"
  "no family	--family	2	--samples $S --edges $E"
  "lambda 0	--lambda	2	--samples $S --edges $E --family least_squares --lambda 0"
  "nodes 1	--nodes	2	--samples $S --edges $E --family least_squares --nodes 1"
  "unknown column	--node-column	2	--samples $S --edges $E --family least_squares --node-column nd"
  "node = label	--label-column	2	--samples $S --edges $E --family least_squares --node-column node --label-column node"
  "unknown option	--bogus	2	--samples $S --edges $E --family least_squares --bogus"
)
cp "$T/ls.h5" "$T/keep.h5"
sum0=$(md5sum < "$T/keep.h5")
sums=$(md5sum "$S" "$E")
count=0
for c in "${cases[@]}"; do
  IFS=$'\t' read -r label word expect args <<< "$c"
  out=$T/keep.h5
  case $args in *" -o "*) out= ;; esac
  for np_ in 1 3; do
    set +e
    # shellcheck disable=SC2086
    mpi $np_ "$SNL" consensus import $args ${out:+-o "$out"} > /dev/null 2> "$T/err"
    rc=$?
    set -e
    what="$label (np=$np_)"
    [ "$rc" -eq "$expect" ] || { cat "$T/err"; fail "$what: exit status $rc, expected $expect"; }
    [ "$(grep -c '^snl: error: ' "$T/err")" -eq 1 ] || { cat "$T/err"; fail "$what: expected exactly one error line"; }
    grep '^snl: error: ' "$T/err" | grep -qF -- "$word" || { cat "$T/err"; fail "$what: error does not name '$word'"; }
    [ "$(md5sum < "$T/keep.h5")" = "$sum0" ] || fail "$what: the existing output was modified"
    [ "$(md5sum "$S" "$E")" = "$sums" ] || fail "$what: an input was modified"
    if ls "$T"/keep.h5.* > /dev/null 2>&1; then fail "$what: temporary file left behind"; fi
    count=$((count + 1))
  done
done
echo "consensus import: $count failing runs checked"

# `snl consensus --help` lists import.
"$SNL" consensus --help | grep -q "^  import " || fail "consensus --help does not list import"
# export refuses --network with a consensus result (one error line, non-zero).
set +e
"$SNL" export "$T/ls.r.h5" -o "$T/x.csv" --network "$T/ls.h5" > /dev/null 2> "$T/err"; rc=$?
set -e
[ "$rc" -ne 0 ] && [ "$(grep -c '^snl: error: ' "$T/err")" -eq 1 ] && grep -q -- "--network" "$T/err" ||
  { cat "$T/err"; fail "export --network on a consensus result"; }
echo "consensus_import: ok"
