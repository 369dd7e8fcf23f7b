#!/usr/bin/env bash
# Installs snl's build and run dependencies (Debian 12 packages) and builds snl.
# Idempotent: quiet and fast when everything is already there.
#   scripts/setup.sh [BUILD_DIR] [extra cmake args...]
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${1:-build}
shift || true

# slurm-wlm and munge: tests/slurm runs the job scripts of jobs/ under a private
# one-node Slurm that it starts and stops itself (it never uses a system-wide one).
# gdb: a test run that hangs prints the stacks of its processes (tests/cli/common.bash).
PKGS=(build-essential cmake ninja-build pkg-config openmpi-bin libopenmpi-dev libhdf5-openmpi-dev hdf5-tools
      libeigen3-dev libmetis-dev libscotchparmetis-dev libptscotch-dev libdsdp-dev libgtest-dev libgmock-dev libcli11-dev libbenchmark-dev
      python3-numpy python3-h5py python3-matplotlib clang libclang-rt-14-dev
      python3-dev pybind11-dev python3-pybind11 python3-mpi4py python3-pytest python3-scipy
      slurm-wlm munge gdb)
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# Open MPI refuses to run as root unless told; oversubscription lets tests use 3 ranks on 2 cores.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1

if [ ! -f "$BUILD_DIR/build.ninja" ]; then
  cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
fi
cmake --build "$BUILD_DIR" -j "$(nproc)"
