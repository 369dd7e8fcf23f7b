#!/usr/bin/env bash
# With the default stopping rule (no --tol), snl solve stops at the same
# iteration and writes the same bytes on 1, 2 and 3 ranks and with either
# partition: /positions, every /history dataset but elapsed, and the summary's
# iteration count, costs, gap certificate and errors. The relative-improvement
# test and the metrics sum per-node terms exactly, independent of the partition.
# NET_ARGS overrides the network (a few hundred sensors whose stopping
# iteration is sensitive to the last bits of the test's sums).
source "$(dirname "$0")/common.bash"
read -r -a net <<< "${NET_ARGS:---sensors 300 --avg-degree 8 --sigma 0.05 --seed 1}"
"$SNL" generate -o "$T/net.h5" "${net[@]}" -q

same() {  # same REF OUT: /positions, /history but elapsed, the summary's decisions and metrics
  $PY - "$1" "$2" <<'PYEOF' || return 1
import json, sys, h5py
a, b = (h5py.File(f, "r") for f in sys.argv[1:3])
names = ["positions"] + ["history/" + k for k in a["history"] if k != "elapsed"]
assert set(a["history"]) == set(b["history"]), "history datasets differ"
bad = [n for n in names if a[n].shape != b[n].shape or a[n][()].tobytes() != b[n][()].tobytes()]
ja, jb = (json.load(open(f[:-3] + ".json")) for f in sys.argv[1:3])
keys = ["iterations", "termination", "message", "ml_cost", "relaxed_cost", "gap_certificate",
        "relaxed_optimum", "apriori_bound", "rmse", "mpe", "rmse_localizable", "mpe_localizable"]
bad += [k for k in keys if ja.get(k) != jb.get(k)]
if bad:
    print("differ:", ", ".join(bad), "| iterations", ja["iterations"], jb["iterations"])
    sys.exit(1)
PYEOF
}

for alg in pipeline relaxation bb; do
  runs=("1 metis" "2 metis" "3 metis" "2 block" "3 block")
  for r in "${runs[@]}"; do
    read -r np part <<< "$r"
    mpi "$np" "$SNL" solve "$T/net.h5" -o "$T/$alg.$np.$part.h5" --algorithm $alg --partition "$part" -q \
      --json "$T/$alg.$np.$part.json"
  done
  for r in "${runs[@]:1}"; do
    read -r np part <<< "$r"
    same "$T/$alg.1.metis.h5" "$T/$alg.$np.$part.h5" || fail "$alg: 1 rank and $np ranks ($part) differ"
  done
done
