#pragma once
// The result file (format "snl-result", version 1) and --init position files.
#include <mpi.h>

#include <cstdint>
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

/// Per-sensor uncertainty stored in a result file (group "crlb", optional;
/// docs/formats.md).
struct ResultCovariance {
  int dim = 2;
  GlobalId num_sensors = 0;
  std::vector<double> covariance;      ///< [n * p * p] p x p blocks of J^-1; 0 outside the covered part
  std::vector<std::uint8_t> covered;   ///< [n] 1 where the bound covers the sensor
  std::string at;                      ///< where J was evaluated: "truth" or "estimate"
  std::string sigma_model;             ///< "uniform" or "per-measurement"
  double sigma = 0;                    ///< the uniform sigma (0 for per-measurement)
  double rmse = 0;                     ///< sqrt(tr(J^-1) / covered)
};

/// Serial (one process). Adds (or replaces) group "crlb" of the result file
/// `path`, keeping everything else: a copy next to it is edited and renamed
/// over `path` only when complete; on any error the original is untouched and
/// the copy removed. Throws snl::Error.
void add_covariance_to_result(const std::string& path, const ResultCovariance& c);

}  // namespace snl
