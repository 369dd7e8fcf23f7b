# Sourced by the CLI tests: paths, mpirun, scratch dir, assertions.
set -euo pipefail
: "${SNL:?SNL must point to the snl binary}"
MPIEXEC=${MPIEXEC:-mpirun}
MPIEXEC_NUMPROC_FLAG=${MPIEXEC_NUMPROC_FLAG:--np}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
PY=/usr/bin/python3
T=$(mktemp -d "${TMPDIR:-/tmp}/snl_cli.XXXXXX")
trap 'rm -rf "$T"' EXIT
mpi() { local np=$1; shift; "$MPIEXEC" "$MPIEXEC_NUMPROC_FLAG" "$np" --oversubscribe "$@"; }
fail() { echo "FAIL: $*" >&2; exit 1; }
