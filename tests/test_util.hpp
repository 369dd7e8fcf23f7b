#pragma once
// Small helpers shared by the tests.
#include <mpi.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <string>

namespace snl::test {

/// A scratch directory unique to this test process group (same on all ranks).
inline std::string scratch_dir(MPI_Comm comm = MPI_COMM_WORLD) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  long long id = rank == 0 ? static_cast<long long>(getpid()) : 0;
  MPI_Bcast(&id, 1, MPI_LONG_LONG, 0, comm);
  const char* base = std::getenv("TMPDIR");
  std::string dir = std::string(base ? base : "/tmp") + "/snl_test_" + std::to_string(id);
  if (rank == 0) {
    std::string cmd = "mkdir -p '" + dir + "'";
    if (std::system(cmd.c_str()) != 0) std::abort();
  }
  MPI_Barrier(comm);
  return dir;
}

inline std::string source_path(const std::string& rel) { return std::string(SNL_SOURCE_DIR) + "/" + rel; }

}  // namespace snl::test
