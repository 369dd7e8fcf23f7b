#pragma once
// The result file (format "snl-result", version 1) and --init position files.
#include <mpi.h>

#include <string>
#include <utility>
#include <vector>

#include "snl/core/common.hpp"

namespace snl {

struct ResultFile {
  std::string algorithm;
  std::int64_t iterations = 0;
  bool converged = false;
  int dim = 2;
  GlobalId num_sensors = 0;
  /// This rank's rows [row_offset, row_offset + positions.size()/dim) of the
  /// [n, p] positions; the ranks' slabs tile [0, n).
  GlobalId row_offset = 0;
  std::vector<double> positions;
  /// history/<name>, identical on every rank; all series of equal length.
  std::vector<std::pair<std::string, std::vector<double>>> history;
  /// Further root attributes (identical on every rank).
  std::vector<std::pair<std::string, double>> double_attrs;
  std::vector<std::pair<std::string, std::string>> string_attrs;
};

/// Collective; atomic (temporary file renamed over `path` on success only).
void write_result(const std::string& path, MPI_Comm comm, const ResultFile& r);

/// Serial read of a whole result file (tests, `snl eval`).
ResultFile read_result_serial(const std::string& path);

/// Collective: rows [row_offset, row_offset+rows) of dataset `positions` of any
/// file (a result file works). Checks shape [expected_n, expected_dim] and that
/// every value is finite; throws snl::Error (same on all ranks) otherwise.
std::vector<double> read_positions(const std::string& path, MPI_Comm comm, GlobalId expected_n,
                                   int expected_dim, GlobalId row_offset, GlobalId rows);

}  // namespace snl
