#pragma once
// Helpers that make every rank agree on errors, so a failure on one rank never
// leaves the others hanging in a collective.
#include <mpi.h>

#include <cstdint>
#include <string>
#include <vector>

#include "snl/common.hpp"

namespace snl {

int comm_rank(MPI_Comm comm);
int comm_size(MPI_Comm comm);

/// Collective. If any rank passes a non-empty message, every rank throws
/// snl::Error carrying the message of the lowest such rank.
void agree(MPI_Comm comm, const std::string& local_error);

/// Collective. Like agree(), but the message chosen is the one with the smallest
/// key (e.g. the first offending row of a dataset across all ranks' slabs).
void agree_first(MPI_Comm comm, std::int64_t key, const std::string& local_error);

/// Collective. Runs f(); an exception on any rank becomes an snl::Error on all.
template <class F>
void collective_try(MPI_Comm comm, F&& f) {
  std::string err;
  try {
    f();
  } catch (const std::bad_alloc&) {
    err = "out of memory";
  } catch (const std::exception& e) {
    err = e.what();
    if (err.empty()) err = "unknown error";
  }
  agree(comm, err);
}

/// Broadcast a string from root.
std::string bcast_string(MPI_Comm comm, const std::string& s, int root = 0);

/// Concatenation of every rank's vector on `root` (empty elsewhere), in rank
/// order; counts may exceed INT_MAX in total.
std::vector<std::int64_t> gather_to_root(MPI_Comm comm, const std::vector<std::int64_t>& mine, int root = 0);

/// Large-count helpers (counts above INT_MAX are split into chunks).
void bcast_bytes(MPI_Comm comm, void* data, std::size_t bytes, int root = 0);

}  // namespace snl
