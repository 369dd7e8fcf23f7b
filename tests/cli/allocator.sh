#!/usr/bin/env bash
# snl tunes glibc's malloc (snl/core/memory.hpp): it re-executes itself with
# glibc.malloc.hugetlb=1 unless the environment chose already or SNL_MALLOC=system
# opts out, and says which in the solve JSON. The positions do not depend on it.
# Any other SNL_MALLOC is refused: one message, status 2, no output written.
source "$(dirname "$0")/common.bash"
"$SNL" generate -o "$T/net.h5" --sensors 300 --avg-degree 8 --sigma 0.01 --seed 5 -q
run() {  # run TAG [VAR=value ...]
  local tag=$1; shift
  env "$@" "$MPIEXEC" "$MPIEXEC_NUMPROC_FLAG" 2 "$SNL" solve "$T/net.h5" -o "$T/$tag.h5" --max-iter 40 --tol 0 -q \
    --json "$T/$tag.json" || fail "$tag: solve failed"
  h5diff "$T/$tag.h5" "$T/system.h5" /positions 2> /dev/null || [ "$tag" = system ] \
    || fail "$tag: positions differ from the untuned run's"
}
set +e
SNL_MALLOC=huge "$MPIEXEC" "$MPIEXEC_NUMPROC_FLAG" 2 "$SNL" solve "$T/net.h5" -o "$T/bad.h5" -q 2> "$T/bad.err"
rc=$?
set -e
[ "$rc" -eq 2 ] || fail "SNL_MALLOC=huge: exit status $rc, not 2"
[ "$(grep -c "SNL_MALLOC must be 'hugetlb' (the default) or 'system', not 'huge'" "$T/bad.err")" -eq 1 ] \
  || fail "SNL_MALLOC=huge: expected one message, got: $(cat "$T/bad.err")"
[ ! -e "$T/bad.h5" ] || fail "SNL_MALLOC=huge: an output was written"
field() { $PY -c "import json,sys; print(json.load(open(sys.argv[1]))['allocator'])" "$1"; }
run system SNL_MALLOC=system
mode=$(field "$T/system.json")
if [ "$mode" = other ]; then  # a sanitizer's allocator: nothing is tuned
  run default
  [ "$(field "$T/default.json")" = other ] || fail "sanitizer build: allocator must stay 'other'"
  echo "allocator: sanitizer build, nothing tuned"
  exit 0
fi
[ "$mode" = system ] || fail "SNL_MALLOC=system: allocator is '$mode', not 'system'"
run default
[ "$(field "$T/default.json")" = hugetlb ] || fail "default: allocator is '$(field "$T/default.json")', not 'hugetlb'"
# A choice already in GLIBC_TUNABLES is kept (no re-execution adds to it).
run chosen GLIBC_TUNABLES=glibc.malloc.hugetlb=0
[ "$(field "$T/chosen.json")" = system ] || fail "GLIBC_TUNABLES=glibc.malloc.hugetlb=0 must be kept as chosen"
run explicit SNL_MALLOC=hugetlb
[ "$(field "$T/explicit.json")" = hugetlb ] || fail "SNL_MALLOC=hugetlb: allocator is '$(field "$T/explicit.json")'"
echo "allocator: default hugetlb, SNL_MALLOC=system untuned, other values refused, positions identical"
