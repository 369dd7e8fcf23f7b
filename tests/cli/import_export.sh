#!/usr/bin/env bash
# snl import and snl export end to end: the bundled text network (inputs/text,
# written from inputs/net10_s0.01.h5) imports to the same measurements, solves
# to the same positions, and exports them exactly; sigma columns and 1-based
# ids; every bad table ends in one "FILE:LINE:" error, exit 1, the existing
# output untouched; bad options exit 2.
source "$(dirname "$0")/common.bash"
TXT=$SNL_SOURCE_DIR/inputs/text
REF=$SNL_SOURCE_DIR/inputs/net10_s0.01.h5
import_txt() { "$SNL" import --sensor-edges "$TXT/edges.csv" --anchor-edges "$TXT/anchor_edges.txt" \
  --anchors "$TXT/anchors.csv" "$@"; }

# 1. The text tables give the bundled network's measurements, bit for bit.
import_txt --truth "$TXT/truth.csv" --sigma 0.01 -o "$T/net.h5" > "$T/out"
grep -q "imported $T/net.h5: n=10 m=4 p=2, 22 sensor ranges (0 duplicate rows), 10 anchor ranges" "$T/out" ||
  { cat "$T/out"; fail "import summary"; }
"$PY" - "$T/net.h5" "$REF" <<'EOF' || fail "imported network differs from $REF"
import sys, h5py, numpy as np
a, b = h5py.File(sys.argv[1], "r"), h5py.File(sys.argv[2], "r")
for k in ["anchors", "sensor_edges", "sensor_ranges", "anchor_edges", "anchor_ranges", "truth", "sigma"]:
    assert np.array_equal(a[k][()], b[k][()]), k
assert a.attrs["num_sensors"] == 10 and a.attrs["dim"] == 2
assert "sensor_sigmas" not in a and "anchor_sigmas" not in a
EOF

# 2. Solving it gives the same positions as solving the bundled file; export writes them exactly.
for net in "$T/net.h5" "$REF"; do
  "$SNL" solve "$net" -o "$T/res_$(basename "$net")" --max-iter 300 --tol 0 -q
done
"$PY" - "$T/res_net.h5" "$T/res_$(basename "$REF")" <<'EOF' || fail "positions differ between imported and bundled network"
import sys, h5py, numpy as np
assert np.array_equal(h5py.File(sys.argv[1], "r")["positions"][:], h5py.File(sys.argv[2], "r")["positions"][:])
EOF
"$SNL" export "$T/res_net.h5" -o "$T/pos.csv" > "$T/out"
grep -q "exported $T/pos.csv: 10 sensors, p=2" "$T/out" || { cat "$T/out"; fail "export summary"; }
"$SNL" export "$T/res_net.h5" -o "$T/pos_flags.csv" --network "$T/net.h5" --index-base 1 > "$T/out"
grep -q "localizability flags computed; rigidity at the truth: 0 sensors not localizable" "$T/out" ||
  { cat "$T/out"; fail "export --network summary"; }
"$SNL" export "$T/res_net.h5" -o "$T/pos_stored.csv" --network "$REF" -q
"$PY" - "$T" <<'EOF' || fail "exported CSV"
import sys, csv, h5py, numpy as np
T = sys.argv[1]
x = h5py.File(T + "/res_net.h5", "r")["positions"][:]
truth = h5py.File(T + "/net.h5", "r")["truth"][:]
rows = list(csv.reader(open(T + "/pos.csv")))
assert rows[0] == ["sensor", "x", "y"], rows[0]
assert [int(r[0]) for r in rows[1:]] == list(range(10))
assert np.array_equal(np.array([[float(v) for v in r[1:]] for r in rows[1:]]), x)   # exact round trip
assert np.sqrt(np.mean(np.sum((x - truth) ** 2, 1))) < 0.05                          # it did localize
for name in ["pos_flags.csv", "pos_stored.csv"]:
    rows = list(csv.reader(open(T + "/" + name)))
    assert rows[0] == ["sensor", "x", "y", "flags", "localizable"], rows[0]
    assert all(r[3:] == ["0", "1"] for r in rows[1:]), name
    assert np.array_equal(np.array([[float(v) for v in r[1:3]] for r in rows[1:]]), x)
rows = list(csv.reader(open(T + "/pos_flags.csv")))
assert [int(r[0]) for r in rows[1:]] == list(range(1, 11))                            # --index-base 1
EOF

# 3. Sigma columns, 1-based ids; sensor 4 (1-based) has no measurement: flags 1+2+4 (unanchored, few
# measurements, not rigid at the result positions).
printf '# 1-based, whitespace, sigma column\n1 2 0.5 0.01\n2 3 0.5 0.02\n3 1 0.6 0.01\n1 2 0.52 0.01\n' > "$T/e.txt"
printf 'i,anchor,range\n1,1,0.3\n2,2,0.4\n3,3,0.5\n1,2,0.7\n2,3,0.6\n3,1,0.65\n' > "$T/a.csv"
printf '0 0\n1 0\n0 1\n' > "$T/anc.txt"
"$SNL" import --sensor-edges "$T/e.txt" --anchor-edges "$T/a.csv" --anchors "$T/anc.txt" --index-base 1 \
  --sensors 4 -o "$T/sig.h5" > "$T/out"
grep -q "n=4 m=3 p=2, 4 sensor ranges (1 duplicate rows), 6 anchor ranges (0 duplicate rows)" "$T/out" &&
  grep -q "per-measurement sigmas: yes (sensor ranges), no (anchor ranges)" "$T/out" &&
  grep -q "warning: 1 of 4 sensors have no measurement" "$T/out" || { cat "$T/out"; fail "sigma import summary"; }
"$PY" - "$T/sig.h5" <<'EOF' || fail "sigma network content"
import sys, h5py, numpy as np
f = h5py.File(sys.argv[1], "r")
assert f["sensor_edges"][:].tolist() == [[0, 1], [1, 2], [2, 0], [0, 1]]
assert f["sensor_sigmas"][:].tolist() == [0.01, 0.02, 0.01, 0.01]
assert "anchor_sigmas" not in f and "truth" not in f and "sigma" not in f
assert f["anchor_edges"][:].tolist() == [[0, 0], [1, 1], [2, 2], [0, 1], [1, 2], [2, 0]]
EOF
"$SNL" info "$T/sig.h5" | grep -q "(1 duplicate rows merged)" || fail "info on the imported network"
"$SNL" solve "$T/sig.h5" -o "$T/sig_res.h5" --max-iter 50 --tol 0 -q
"$SNL" export "$T/sig_res.h5" --network "$T/sig.h5" -o "$T/sig.csv" -q
[ "$(tail -n 1 "$T/sig.csv" | cut -d, -f4-)" = "7,0" ] || { cat "$T/sig.csv"; fail "flags of the unmeasured sensor"; }

# 4. Bad tables: one "FILE:LINE: what" error, exit 1, the existing output untouched.
cp "$T/net.h5" "$T/keep.h5"
sum0=$(md5sum < "$T/keep.h5")
expect_error() {  # expect_error NP 'message part' import-args...
  local np=$1 want=$2
  shift 2
  set +e
  if [ "$np" -eq 1 ]; then "$SNL" import -o "$T/keep.h5" -q "$@"; else mpi "$np" "$SNL" import -o "$T/keep.h5" -q "$@"; fi \
    > /dev/null 2> "$T/err"
  local rc=$?
  set -e
  [ $rc -eq 1 ] || { cat "$T/err"; fail "'$want': exit status $rc"; }
  [ "$(grep -c '^snl: error: ' "$T/err")" -eq 1 ] || { cat "$T/err"; fail "'$want': expected exactly one error message"; }
  [ "$np" -gt 1 ] || [ "$(wc -l < "$T/err")" -eq 1 ] || { cat "$T/err"; fail "'$want': more than the error on stderr"; }
  grep -qF "snl: error: $want" "$T/err" || { cat "$T/err"; fail "expected '$want'"; }
  [ "$(md5sum < "$T/keep.h5")" = "$sum0" ] || fail "'$want': existing output modified"
  ! ls "$T"/keep.h5.tmp* > /dev/null 2>&1 || fail "'$want': temporary file left behind"
}
bad() { printf "$2" > "$T/$1"; }  # bad NAME CONTENT: a table in the scratch dir
G=(--anchor-edges "$TXT/anchor_edges.txt" --anchors "$TXT/anchors.csv")
bad b1.csv 'i,j,range\n0,1,0.5\n1,2,0.5x\n';   expect_error 1 "$T/b1.csv:3: column 3 (range): '0.5x' is not a number" --sensor-edges "$T/b1.csv" "${G[@]}"
bad b2.csv '0,1,0.5\n# c\n1,2\n';               expect_error 1 "$T/b2.csv:3: 2 columns, expected 3 or 4" --sensor-edges "$T/b2.csv" "${G[@]}"
bad b3.csv '0,1,0.5\n1,2,0.5,0.1\n';            expect_error 1 "$T/b3.csv:2: 4 columns, but line 1 has 3" --sensor-edges "$T/b3.csv" "${G[@]}"
bad b4.csv '0,1,0.5\n1,2,-0.5\n';               expect_error 2 "$T/b4.csv:2: range -0.5 is negative" --sensor-edges "$T/b4.csv" "${G[@]}"
bad b5.csv '0,1,0.5\n1,2,inf\n';                expect_error 1 "$T/b5.csv:2: range is Inf" --sensor-edges "$T/b5.csv" "${G[@]}"
bad b6.csv '0,1,0.5\n4,4,0.5\n';                expect_error 1 "$T/b6.csv:2: self-loop (4, 4)" --sensor-edges "$T/b6.csv" "${G[@]}"
bad b7.csv '0,1,0.5\n1,12,0.5\n';               expect_error 2 "$T/b7.csv:2: sensor index 12 out of range [0, 10) (n = 10 from --sensors)" --sensor-edges "$T/b7.csv" --sensors 10 "${G[@]}"
bad b8.txt '0 0 0.5\n1 4 0.5\n';                expect_error 1 "$T/b8.txt:2: anchor index 4 out of range [0, 4) (4 rows in $TXT/anchors.csv)" --sensor-edges "$TXT/edges.csv" --anchor-edges "$T/b8.txt" --anchors "$TXT/anchors.csv"
bad b9.csv '0,0,0\n1,1,1\n';                    expect_error 1 "$T/b9.csv:1: 3 coordinates, but $TXT/anchors.csv has 2 (the dimension p)" --sensor-edges "$TXT/edges.csv" "${G[@]}" --truth "$T/b9.csv"
bad b10.csv '0,0\n1,0\n0,1,2\n';                expect_error 1 "$T/b10.csv:3: 3 columns, but line 1 has 2" --sensor-edges "$TXT/edges.csv" --anchor-edges "$TXT/anchor_edges.txt" --anchors "$T/b10.csv"
bad b11.csv '0,0\nnan,1\n';                     expect_error 1 "$T/b11.csv:2: coordinate x is NaN" --sensor-edges "$TXT/edges.csv" --anchor-edges "$TXT/anchor_edges.txt" --anchors "$T/b11.csv"
bad b12.csv '0,1,0.5,0\n';                      expect_error 1 "$T/b12.csv:1: sigma 0 is outside [1e-150, 1e150]" --sensor-edges "$T/b12.csv" "${G[@]}"
bad b13.csv '1,0,0.5\n';                        expect_error 1 "$T/b13.csv:1: sensor index 0 is below the index base 1" --sensor-edges "$T/b13.csv" "${G[@]}" --index-base 1
expect_error 2 "$T/missing.csv: cannot open (No such file or directory)" --sensor-edges "$T/missing.csv" "${G[@]}"
expect_error 1 "$T: cannot read (Is a directory)" --sensor-edges "$T" "${G[@]}"
echo "import: 15 bad tables rejected"

# 5. Usage errors exit 2; export refuses a mismatched network; --help works.
set +e
import_txt -o "$T/keep.h5" --index-base 2 > /dev/null 2>&1; rc1=$?
"$SNL" export "$T/res_net.h5" -o "$T/x.csv" --network "$SNL_SOURCE_DIR/inputs/net50_s0.01.h5" 2> "$T/err"; rc2=$?
"$SNL" export "$T/nope.h5" -o "$T/pos.csv" 2> /dev/null; rc3=$?
set -e
[ $rc1 -eq 2 ] || fail "--index-base 2: exit status $rc1, expected 2"
[ $rc2 -eq 1 ] && grep -q "10 positions in dimension 2, but .*net50_s0.01.h5 has n = 50, p = 2" "$T/err" &&
  [ ! -e "$T/x.csv" ] || { cat "$T/err"; fail "export with a mismatched network"; }
[ $rc3 -eq 1 ] && [ "$(tail -n 1 "$T/pos.csv" | cut -d, -f1)" = 9 ] || fail "failed export modified its output"
"$SNL" import --help | grep -q -- "--sensor-edges" || fail "import --help"
"$SNL" export --help | grep -q -- "--network" || fail "export --help"
echo "import_export: ok"
