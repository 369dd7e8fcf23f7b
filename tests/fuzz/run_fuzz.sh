#!/usr/bin/env bash
# Builds tests/fuzz/fuzz_network.cpp with clang (libFuzzer + ASan + UBSan; only
# src/io/validate.cpp, no MPI) and runs it for FUZZ_SECONDS (default 20) from a
# small seed corpus. Fails on any crash or invariant violation. Without clang
# it prints 'skipped' and succeeds. Usage: run_fuzz.sh [SOURCE_DIR] [WORK_DIR]
set -euo pipefail
SRC=${1:-${SNL_SOURCE_DIR:-$(cd "$(dirname "$0")/../.." && pwd)}}
WORK=${2:-$(mktemp -d "${TMPDIR:-/tmp}/snl_fuzz.XXXXXX")}
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
"$CXX" "${FLAGS[@]}" -Wall -Wextra -Werror -I "$SRC/include" "${MPI_INC[@]}" \
  "$SRC/tests/fuzz/fuzz_network.cpp" "$SRC/src/io/validate.cpp" -o "$WORK/fuzz_network"
# Seeds: empty, a tiny valid network with duplicates, special values.
printf '\x00\x05\x02\x04\x02\x01\x02\x10\x02\x01\x11\x03\x02\x20\x01\x02\x30\x01\x00\x20\x01\x01\x20' > "$WORK/corpus/dup"
printf '\x01\x08\x03\x06\x03\x00\x01\x02\x03\x04\x05\x06\x07\x08\x09\x0a\x0b' > "$WORK/corpus/special"
: > "$WORK/corpus/empty"
"$WORK/fuzz_network" -max_total_time="${FUZZ_SECONDS:-20}" -seed=1 -print_final_stats=1 "$WORK/corpus" 2>&1 | tail -n 25
echo "fuzz_network: no crash"
