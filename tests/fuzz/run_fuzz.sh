#!/usr/bin/env bash
# Builds tests/fuzz/fuzz_network.cpp with clang (libFuzzer + ASan + UBSan; only
# src/io/validate.cpp, no MPI) and runs it for FUZZ_SECONDS (default 20) from a
# small seed corpus. Fails on any crash or invariant violation. Without clang
# it prints 'skipped' and succeeds. Usage: run_fuzz.sh [SOURCE_DIR] [WORK_DIR]
source "$(dirname "$0")/fuzz_common.bash" fuzz_network "$@"
"$CXX" "${FLAGS[@]}" -Wall -Wextra -Werror -I "$SRC/include" "${MPI_INC[@]}" \
  "$SRC/tests/fuzz/fuzz_network.cpp" "$SRC/src/io/validate.cpp" -o "$WORK/fuzz_network"
# Seeds: empty, a tiny valid network with duplicates, special values.
printf '\x00\x05\x02\x04\x02\x01\x02\x10\x02\x01\x11\x03\x02\x20\x01\x02\x30\x01\x00\x20\x01\x01\x20' > "$WORK/corpus/dup"
printf '\x01\x08\x03\x06\x03\x00\x01\x02\x03\x04\x05\x06\x07\x08\x09\x0a\x0b' > "$WORK/corpus/special"
: > "$WORK/corpus/empty"
fuzz_run 20
