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
