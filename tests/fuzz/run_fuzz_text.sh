#!/usr/bin/env bash
# Builds tests/fuzz/fuzz_text_table.cpp with clang (libFuzzer + ASan + UBSan;
# src/io/text_table.cpp and src/io/validate.cpp, no MPI) and runs it for
# FUZZ_SECONDS (default 10) from a small seed corpus. Fails on any crash or
# invariant violation. Without clang it prints 'skipped' and succeeds.
# Usage: run_fuzz_text.sh [SOURCE_DIR] [WORK_DIR]
source "$(dirname "$0")/fuzz_common.bash" fuzz_text_table "$@"
"$CXX" "${FLAGS[@]}" -Wall -Wextra -Werror -I "$SRC/include" -I "$SRC/src" "${MPI_INC[@]}" \
  "$SRC/tests/fuzz/fuzz_text_table.cpp" "$SRC/src/io/text_table.cpp" "$SRC/src/io/validate.cpp" \
  -o "$WORK/fuzz_text_table"
# Seeds: the bundled example (truth on), a 1-based table with sigmas, empty.
{ printf '\x20'; cat "$SRC/inputs/text/edges.csv"; printf '\x01'; cat "$SRC/inputs/text/anchor_edges.txt"
  printf '\x01'; cat "$SRC/inputs/text/anchors.csv"; printf '\x01'; cat "$SRC/inputs/text/truth.csv"; } > "$WORK/corpus/example"
printf '\x01# c\n1 2 0.5 0.1\n2,3,1e-3,2\x01i,anchor,range\n1,1,0.3\n3 2 nan\x011 2\n3,4\n\x01' > "$WORK/corpus/base1"
: > "$WORK/corpus/empty"
fuzz_run 10
