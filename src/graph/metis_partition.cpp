// METIS k-way on rank 0 over the partition graph's CSR.
#include <metis.h>

#include <algorithm>
#include <limits>

#include "graph/partition_detail.hpp"
#include "snl/core/mpi_util.hpp"
#include "snl/graph/dist_graph.hpp"
#include "snl/graph/partition.hpp"
#include "snl/io/network.hpp"

namespace snl::detail {

static_assert(sizeof(idx_t) == 4 || sizeof(idx_t) == 8, "unexpected METIS idx_t");

// METIS k-way on rank 0 over root_csr's graph. Collective; returns "" on
// success, else why it could not run (on rank 0; the caller broadcasts it).
std::string metis_on_root(MPI_Comm comm, GlobalId n, const std::vector<GlobalId>& edges, std::vector<int>& owner,
                          PhaseMarks& phase, std::int64_t& peak) {
  long long pairs = static_cast<long long>(edges.size() / 2), total = 0;
  MPI_Allreduce(&pairs, &total, 1, MPI_LONG_LONG, MPI_SUM, comm);
  const std::int64_t idx_max = std::numeric_limits<idx_t>::max();
  if (n > idx_max || 2 * total > idx_max)
    return "graph too large for this METIS build (" + std::to_string(sizeof(idx_t) * 8) + "-bit idx_t)";
  std::vector<idx_t> xadj, adjncy;
  std::string why = root_csr_impl(comm, n, edges, xadj, adjncy, peak);
  if (!why.empty()) return why;
  phase("metis_graph");
  if (comm_rank(comm) != 0) return "";
  idx_t nvtxs = static_cast<idx_t>(n), ncon = 1, np = comm_size(comm), objval = 0;
  idx_t options[METIS_NOPTIONS];
  METIS_SetDefaultOptions(options);
  options[METIS_OPTION_SEED] = 1;  // deterministic partitions
  options[METIS_OPTION_NUMBERING] = 0;
  int status = METIS_ERROR;
  try {
    std::vector<idx_t> part(static_cast<std::size_t>(n), 0);
    // METIS's CSR and part (METIS's own workspace not counted).
    peak = std::max(peak, static_cast<std::int64_t>((xadj.size() + adjncy.size() + part.size()) * sizeof(idx_t)));
    status = METIS_PartGraphKway(&nvtxs, &ncon, xadj.data(), adjncy.data(), nullptr, nullptr, nullptr, &np, nullptr,
                                 nullptr, options, &objval, part.data());
    if (status == METIS_OK) owner.assign(part.begin(), part.end());
  } catch (...) {
    status = METIS_ERROR_MEMORY;
  }
  if (status != METIS_OK) return status == METIS_ERROR_MEMORY ? "METIS ran out of memory" : "METIS failed";
  phase("metis");
  return "";
}

}  // namespace snl::detail
