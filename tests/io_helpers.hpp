#pragma once
// Helpers of the file tests (tests/unit/test_{network_io,h5file,result_io}.cpp,
// tests/mpi/test_{network_io,result_io}_mpi.cpp): scratch paths, the error a
// network file gives, and a substring expectation for error messages.
#include <mpi.h>

#include <string>

#include "snl/core/common.hpp"
#include "snl/io/network.hpp"
#include "test_util.hpp"

namespace snl::test {

/// A path in this process's scratch directory (serial tests).
inline std::string scratch(const std::string& name) { return scratch_dir(MPI_COMM_SELF) + "/" + name; }

/// A path in the scratch directory shared by all ranks (collective).
inline std::string path_of(const std::string& name) { return scratch_dir(MPI_COMM_WORLD) + "/" + name; }

/// The message read_network_serial throws for `path`, or "(no error)".
inline std::string read_error(const std::string& path) {
  try {
    read_network_serial(path);
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace snl::test

#define EXPECT_CONTAINS(text, fragment)                                                        \
  do {                                                                                         \
    const std::string t_ = (text);                                                             \
    EXPECT_NE(t_.find(fragment), std::string::npos) << "message: '" << t_ << "'";              \
  } while (0)
