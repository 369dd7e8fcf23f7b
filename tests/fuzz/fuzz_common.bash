# Shared by the fuzz drivers (sourced): finds clang++ with libFuzzer, makes the
# work folder and its corpus, and runs a target. Without a usable clang the
# driver prints 'skipped' and succeeds (ctest reports it skipped).
#   source fuzz_common.bash NAME [SOURCE_DIR] [WORK_DIR]
# sets SRC, WORK, CXX, FLAGS (libFuzzer + ASan + UBSan) and MPI_INC (mpi.h only:
# the headers name MPI_Comm, nothing is linked from MPI).
set -euo pipefail
FUZZ_NAME=$1
SRC=${2:-${SNL_SOURCE_DIR:-$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)}}
WORK=${3:-$(mktemp -d "${TMPDIR:-/tmp}/snl_$FUZZ_NAME.XXXXXX")}
CXX=""
for c in clang++-14 clang++; do command -v "$c" > /dev/null && { CXX=$c; break; }; done
if [ -z "$CXX" ]; then echo "skipped: no clang++ for libFuzzer"; exit 0; fi
mkdir -p "$WORK/corpus"
FLAGS=(-std=c++17 -O1 -g -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined)
echo 'extern "C" int LLVMFuzzerTestOneInput(const char*, unsigned long) { return 0; }' > "$WORK/probe.cpp"
"$CXX" "${FLAGS[@]}" "$WORK/probe.cpp" -o "$WORK/probe" 2> /dev/null ||
  { echo "skipped: $CXX cannot link libFuzzer targets here (libclang-rt missing?)"; exit 0; }
MPI_INC=()
for d in $(mpicxx --showme:incdirs 2> /dev/null) /usr/lib/x86_64-linux-gnu/openmpi/include; do MPI_INC+=(-I "$d"); done

# fuzz_run DEFAULT_SECONDS: runs $WORK/$FUZZ_NAME on the corpus for FUZZ_SECONDS.
fuzz_run() {
  "$WORK/$FUZZ_NAME" -max_total_time="${FUZZ_SECONDS:-$1}" -seed=1 -print_final_stats=1 "$WORK/corpus" 2>&1 |
    tail -n 25
  echo "$FUZZ_NAME: no crash"
}
