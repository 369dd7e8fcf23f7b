#!/usr/bin/env bash
# `cmake --install` gives a usable package: an outside project finds it with
# find_package(snl), links snl::snl, and runs.
source "$(dirname "$0")/common.bash"
: "${SNL_BUILD_DIR:?}"
cmake --install "$SNL_BUILD_DIR" --prefix "$T/prefix" > /dev/null
[ -x "$T/prefix/bin/snl" ] || fail "snl not installed"
for h in core/common.hpp graph/dist_graph.hpp graph/halo.hpp io/network.hpp problem/problem.hpp solvers/solver.hpp; do
  [ -f "$T/prefix/include/snl/$h" ] || fail "public header snl/$h not installed"
done
# Internal headers (kernels, the JSON writer, solver helpers) and the test oracle stay private.
leaked=$(find "$T/prefix/include/snl" -name 'json.hpp' -o -name 'reference.hpp' -o -name 'kernels.hpp' -o -name 'algorithm_util.hpp')
[ -z "$leaked" ] || fail "internal headers installed: $leaked"
cmake -S "$SNL_SOURCE_DIR/tests/consumer" -B "$T/consumer" -DCMAKE_PREFIX_PATH="$T/prefix" > "$T/log" 2>&1 \
  || { cat "$T/log"; fail "find_package(snl) failed"; }
cmake --build "$T/consumer" > "$T/log" 2>&1 || { cat "$T/log"; fail "consumer did not build"; }
"$T/consumer/consumer" || fail "consumer run failed"
"$T/prefix/bin/snl" --version
# The Python package, where the build has it: importable from the prefix alone
# (no build tree on the path), finding the installed libsnl, and solving.
if [ -f "$SNL_BUILD_DIR/python/snl/__init__.py" ]; then
  init=$(find "$T/prefix" -path '*/site-packages/snl/__init__.py' | head -1)
  [ -n "$init" ] || fail "the snl Python package is not installed"
  site=$(dirname "$(dirname "$init")")
  (cd "$T" && env -u PYTHONPATH PYTHONPATH="$site" "$PY" -c "
import sys, snl
assert snl.__file__.startswith(sys.argv[1]), snl.__file__
r = snl.solve(snl.generate(60, seed=1))
assert r.positions.shape == (60, 2) and r.summary['rmse'] < 0.05, r.summary['rmse']
print('installed snl Python package:', snl.__file__)
" "$T/prefix") || fail "the installed snl Python package does not import or solve"
fi
