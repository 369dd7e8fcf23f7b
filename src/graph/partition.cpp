// The partition interface (snl/graph/partition.hpp): the method's choice,
// the dispatch to one partitioner (bfs_partition.cpp, metis_partition.cpp,
// parmetis_partition.cpp; block as the fallback) and the owner directory
// (owner_directory.cpp) built from its owners.
#include <algorithm>
#include <limits>

#include "graph/partition_detail.hpp"
#include "snl/core/mpi_util.hpp"
#include "snl/graph/dist_graph.hpp"
#include "snl/graph/partition.hpp"
#include "snl/io/network.hpp"

namespace snl {

PartitionMethod parse_partition_method(const std::string& s) {
  if (s == "metis") return PartitionMethod::kMetis;
  if (s == "block") return PartitionMethod::kBlock;
  if (s == "parmetis") return PartitionMethod::kParMetis;
  if (s == "bfs") return PartitionMethod::kBfs;
  if (s == "auto") return PartitionMethod::kAuto;
  throw Error("unknown partition method '" + s + "' (expected auto, metis, bfs, parmetis or block)");
}

bool parmetis_available() {
#ifdef SNL_HAVE_PARMETIS
  return true;
#else
  return false;
#endif
}

namespace {
// Number of shared-memory nodes the ranks of comm run on.
int count_nodes(MPI_Comm comm) {
  MPI_Comm local;
  MPI_Comm_split_type(comm, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &local);
  const int leader = comm_rank(local) == 0 ? 1 : 0;
  MPI_Comm_free(&local);
  int nodes = 0;
  MPI_Allreduce(&leader, &nodes, 1, MPI_INT, MPI_SUM, comm);
  return nodes;
}
}  // namespace

PartitionMethod resolve_partition_method(MPI_Comm comm, GlobalId /*n*/, PartitionMethod method) {
  if (method != PartitionMethod::kAuto) return method;
  if (!parmetis_available()) return PartitionMethod::kBfs;
  return count_nodes(comm) > 1 ? PartitionMethod::kParMetis : PartitionMethod::kBfs;
}

namespace detail {

// METIS (or the bfs partition) on rank 0 over the graph of every rank's edge
// pairs; each rank gets the owners of its block (scatter). Collective;
// returns "" on success, else why not.
std::string partition_on_root(MPI_Comm comm, GlobalId n, const std::vector<GlobalId>& edges, PartitionMethod method,
                              std::vector<int>& block, PhaseMarks& phase, std::int64_t& peak) {
  std::vector<int> owner;
  std::string why = method == PartitionMethod::kBfs ? bfs_on_root(comm, n, edges, owner, phase, peak)
                                                    : metis_on_root(comm, n, edges, owner, phase, peak);
  why = bcast_string(comm, why);
  if (!why.empty()) return why;
  const int size = comm_size(comm);
  std::vector<int> counts(size), displs(size);
  for (int r = 0; r < size; ++r) {
    GlobalId b, e;
    block_range(n, size, r, b, e);
    counts[r] = static_cast<int>(e - b);
    displs[r] = static_cast<int>(b);
  }
  block.resize(static_cast<std::size_t>(counts[comm_rank(comm)]));
  MPI_Scatterv(owner.data(), counts.data(), displs.data(), MPI_INT, block.data(), static_cast<int>(block.size()),
               MPI_INT, 0, comm);
  phase("scatter");
  return "";
}

}  // namespace detail

namespace {

using detail::PhaseMarks;
using detail::partition_on_root;

// Imbalance of the partition into stats (collective).
void partition_imbalance(const OwnerDirectory& dir, PartitionStats& stats) {
  const std::vector<GlobalId> counts = dir.counts();
  const double mean = static_cast<double>(dir.num_global()) / static_cast<double>(counts.size());
  stats.imbalance = mean > 0 ? static_cast<double>(*std::max_element(counts.begin(), counts.end())) / mean : 1.0;
}

// Owners of this rank's block by `method` (one rank or a fallback: block),
// and with the distributed bfs partition the nodes' keys (level_bisection).
// Sets `used` and `note`.
std::vector<int> block_owners(MPI_Comm comm, GlobalId n, const std::vector<GlobalId>& edges, const BlockRows* rows,
                              PartitionMethod method, std::vector<std::int32_t>& keys, PhaseMarks& phase,
                              std::int64_t& peak, std::string& used, std::string& note) {
  const int size = comm_size(comm);
  std::vector<int> block;
  std::string why;
  if (method == PartitionMethod::kBfs && size > 1) {
    why = detail::bfs_partition_blocks(comm, n, edges, rows, block, keys, phase, peak, note);
    if (why.empty()) used = "bfs";
  } else if (method == PartitionMethod::kMetis && size > 1) {
    why = partition_on_root(comm, n, edges, method, block, phase, peak);
    if (why.empty()) used = "metis";
  } else if (method == PartitionMethod::kParMetis && size > 1) {
#ifdef SNL_HAVE_PARMETIS
    // PT-Scotch needs vertices on every rank: tiny graphs go to METIS.
    why = n >= 2 * static_cast<GlobalId>(size) ? detail::parmetis_partition(comm, n, edges, block, phase, peak)
                                               : partition_on_root(comm, n, edges, PartitionMethod::kMetis, block, phase, peak);
    if (why.empty()) used = n >= 2 * static_cast<GlobalId>(size) ? "parmetis" : "metis";
#else
    why = "this build has no ParMETIS (install libscotchparmetis-dev and libptscotch-dev, then reconfigure)";
#endif
  } else if (method != PartitionMethod::kBlock) {
    // One rank: the trivial partition.
    used = method == PartitionMethod::kParMetis ? "parmetis" : method == PartitionMethod::kBfs ? "bfs" : "metis";
  }
  if (!why.empty()) note = why + "; used the block partition instead";
  if (!why.empty() || block.empty()) {
    keys.clear();
    GlobalId b, e;
    block_range(n, size, comm_rank(comm), b, e);
    block.assign(static_cast<std::size_t>(e - b), comm_rank(comm));
  }
  return block;
}

}  // namespace

// partition_nodes over the edges or, where given, over the block rows (the
// methods that take edges get the rows' edges).
static OwnerDirectory partition_impl(MPI_Comm comm, GlobalId n, const std::vector<GlobalId>& edges,
                                     const BlockRows* rows, PartitionMethod method, PartitionStats* stats) {
  const double t0 = MPI_Wtime();
  PhaseMarks phase;
  method = resolve_partition_method(comm, n, method);
  std::string used = "block", note;
  std::int64_t peak = 0;
  std::vector<std::int32_t> keys;
  const bool rows_in_place = rows && method == PartitionMethod::kBfs;
  const std::vector<int> block =
      rows && !rows_in_place && comm_size(comm) > 1
          ? block_owners(comm, n, rows->edges(), nullptr, method, keys, phase, peak, used, note)
          : block_owners(comm, n, edges, rows_in_place ? rows : nullptr, method, keys, phase, peak, used, note);
  OwnerDirectory dir(comm, n, block, keys);
  if (stats) {
    stats->method = used;
    stats->note = note;
    stats->peak_bytes = peak;
    partition_imbalance(dir, *stats);
    phase("stats");
    stats->phases = std::move(phase.phases);
    stats->seconds = MPI_Wtime() - t0;
  }
  return dir;
}

OwnerDirectory partition_nodes(MPI_Comm comm, GlobalId n, const std::vector<GlobalId>& edges,
                               PartitionMethod method, PartitionStats* stats) {
  return partition_impl(comm, n, edges, nullptr, method, stats);
}

OwnerDirectory partition_nodes(MPI_Comm comm, const BlockRows& rows, PartitionMethod method, PartitionStats* stats) {
  return partition_impl(comm, rows.n, {}, &rows, method, stats);
}

std::vector<int> partition_graph(MPI_Comm comm, GlobalId n, const std::vector<GlobalId>& edges,
                                 PartitionMethod method, PartitionStats* stats) {
  const OwnerDirectory dir = partition_nodes(comm, n, edges, method, stats);
  std::vector<int> owner = dir.gather_dense();
  if (stats) {
    long long cut = 0, gcut = 0;
    for (std::size_t e = 0; e < edges.size(); e += 2) cut += owner[edges[e]] != owner[edges[e + 1]];
    MPI_Allreduce(&cut, &gcut, 1, MPI_LONG_LONG, MPI_SUM, comm);
    stats->edge_cut = gcut;
  }
  return owner;
}

}  // namespace snl
