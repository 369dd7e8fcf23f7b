#pragma once
// Small helpers shared by the subcommands (internal header).
#include <mpi.h>

#include <cstdint>
#include <string>

#include "snl/core/mpi_util.hpp"

namespace snl::detail {

inline bool is_root(MPI_Comm comm) { return comm_rank(comm) == 0; }

/// %g with `prec` significant digits.
std::string fmt(double v, int prec = 6);

/// Collective: rank 0 writes `text` to `path` atomically; every rank throws
/// the same snl::Error if that failed.
void write_text_on_root(const std::string& path, const std::string& text, MPI_Comm comm);

/// The whole of a text file; snl::Error "PATH: cannot open/read (reason)".
std::string read_text_file(const std::string& path);

/// The root attribute `format` of an HDF5 file, "" when it is no HDF5 file or has none.
std::string hdf5_format(const std::string& path);

/// `snl info` on a consensus problem (format "snl-consensus", validated) or
/// result ("snl-consensus-result"): the summary text, and a JSON object in *json.
std::string consensus_info(const std::string& path, const std::string& format, std::string* json);

/// `snl export` on a consensus result: the CSV "node,x0,...,x{q-1}", one row per node (%.17g).
std::string consensus_x_csv(const std::string& path, int index_base, std::int64_t* nodes, std::int64_t* dim);

}  // namespace snl::detail
