#pragma once
// Small helpers shared by the subcommands (internal header).
#include <mpi.h>

#include <string>

#include "snl/core/mpi_util.hpp"

namespace snl::detail {

inline bool is_root(MPI_Comm comm) { return comm_rank(comm) == 0; }

/// %g with `prec` significant digits.
std::string fmt(double v, int prec = 6);

/// Collective: rank 0 writes `text` to `path` atomically; every rank throws
/// the same snl::Error if that failed.
void write_text_on_root(const std::string& path, const std::string& text, MPI_Comm comm);

}  // namespace snl::detail
