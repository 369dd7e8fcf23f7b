#!/usr/bin/env bash
# Builds tests/fuzz/fuzz_text_table.cpp with clang (libFuzzer + ASan + UBSan;
# src/io/text_table.cpp and src/io/validate.cpp, no MPI) and runs it for
# FUZZ_SECONDS (default 10) from a small seed corpus. Fails on any crash or
# invariant violation. Without clang it prints 'skipped' and succeeds.
# Usage: run_fuzz_text.sh [SOURCE_DIR] [WORK_DIR]
set -euo pipefail
SRC=${1:-${SNL_SOURCE_DIR:-$(cd "$(dirname "$0")/../.." && pwd)}}
WORK=${2:-$(mktemp -d "${TMPDIR:-/tmp}/snl_fuzz_text.XXXXXX")}
CXX=""
for c in clang++-14 clang++; do command -v "$c" > /dev/null && { CXX=$c; break; }; done
if [ -z "$CXX" ]; then echo "skipped: no clang++ for libFuzzer"; exit 0; fi
mkdir -p "$WORK/corpus"
FLAGS=(-std=c++17 -O1 -g -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined)
echo 'extern "C" int LLVMFuzzerTestOneInput(const char*, unsigned long) { return 0; }' > "$WORK/probe.cpp"
"$CXX" "${FLAGS[@]}" "$WORK/probe.cpp" -o "$WORK/probe" 2> /dev/null ||
  { echo "skipped: $CXX cannot link libFuzzer targets here (libclang-rt missing?)"; exit 0; }
# network.hpp names MPI_Comm: only mpi.h is needed, nothing is linked from MPI.
MPI_INC=()
for d in $(mpicxx --showme:incdirs 2> /dev/null) /usr/lib/x86_64-linux-gnu/openmpi/include; do MPI_INC+=(-I "$d"); done
"$CXX" "${FLAGS[@]}" -Wall -Wextra -Werror -I "$SRC/include" -I "$SRC/src" "${MPI_INC[@]}" \
  "$SRC/tests/fuzz/fuzz_text_table.cpp" "$SRC/src/io/text_table.cpp" "$SRC/src/io/validate.cpp" \
  -o "$WORK/fuzz_text_table"
# Seeds: the bundled example (truth on), a 1-based table with sigmas, empty.
{ printf '\x20'; cat "$SRC/inputs/text/edges.csv"; printf '\x01'; cat "$SRC/inputs/text/anchor_edges.txt"
  printf '\x01'; cat "$SRC/inputs/text/anchors.csv"; printf '\x01'; cat "$SRC/inputs/text/truth.csv"; } > "$WORK/corpus/example"
printf '\x01# c\n1 2 0.5 0.1\n2,3,1e-3,2\x01i,anchor,range\n1,1,0.3\n3 2 nan\x011 2\n3,4\n\x01' > "$WORK/corpus/base1"
: > "$WORK/corpus/empty"
"$WORK/fuzz_text_table" -max_total_time="${FUZZ_SECONDS:-10}" -seed=1 -print_final_stats=1 "$WORK/corpus" 2>&1 |
  tail -n 25
echo "fuzz_text_table: no crash"
