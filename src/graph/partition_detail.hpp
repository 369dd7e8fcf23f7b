#pragma once
// Internal to the graph layer (not installed): the partition's graph on rank
// 0, exposed for its test against the serial twin.
#include <mpi.h>

#include <cstdint>
#include <string>
#include <vector>

#include "snl/core/common.hpp"

namespace snl::detail {

/// The undirected graph of every rank's edge pairs as CSR on rank 0 (xadj of
/// n + 1 offsets, each row ascending, a pair's two half-edges in the rows of
/// both ends), built in parallel by the block holders of the rows. Collective;
/// returns "" on success, else why not (the same on every rank). Other ranks'
/// xadj and adjncy are left empty. peak: this rank's bytes at their largest.
std::string root_csr(MPI_Comm comm, GlobalId n, const std::vector<GlobalId>& edges, std::vector<std::int64_t>& xadj,
                     std::vector<std::int32_t>& adjncy, std::int64_t& peak);

}  // namespace snl::detail
