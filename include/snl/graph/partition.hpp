#pragma once
// Partitioning of a distributed graph: the methods (bfs, METIS, ParMETIS,
// block), their choice, and the distributed owner directory they produce,
// from which DistGraph builds its local numbering (dist_graph.hpp).
#include <mpi.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "snl/core/common.hpp"
#include "snl/core/memory.hpp"
#include "snl/core/mpi_util.hpp"

namespace snl {

enum class PartitionMethod { kMetis, kBlock, kParMetis, kAuto, kBfs };
/// "metis" | "bfs" | "parmetis" | "block" | "auto" (see resolve_partition_method).
PartitionMethod parse_partition_method(const std::string& s);
/// Whether this build has the ParMETIS interface (PT-Scotch's) for kParMetis.
bool parmetis_available();
/// kAuto: parmetis when the ranks span more than one node (and the build has
/// it), else bfs. On one node bfs partitions several times faster than METIS
/// with iterations as fast, and it runs on every rank's block of rows
/// (nothing of size n on any rank), so no graph size sends it elsewhere;
/// across nodes each of its breadth-first levels would be a collective round.
/// Collective (it counts the nodes). Other methods are returned unchanged.
PartitionMethod resolve_partition_method(MPI_Comm comm, GlobalId n, PartitionMethod method);

/// The bfs partition on one rank (`--partition bfs` runs it on rank 0 only
/// where the distributed one, src/graph/level_bisection.cpp, would need over
/// default_max_levels breadth-first levels): recursive bisection of the graph
/// (CSR, rows ascending) by breadth-first order from a pseudo-peripheral node
/// (George and Liu's level structures); each range of parts [p0, p1) gets its
/// share of the nodes, sizes exact to one node; nodes of other components
/// follow the first in order. Deterministic. Returns each node's part.
std::vector<int> bfs_partition(const std::vector<std::int64_t>& xadj, const std::vector<std::int32_t>& adjncy,
                               int nparts);

struct PartitionStats {
  std::string method;          ///< what was actually used ("metis", "bfs", "parmetis" or "block")
  std::string note;            ///< why a fallback happened, if it did
  GlobalId edge_cut = 0;       ///< undirected edges whose ends live on different ranks
  double imbalance = 1.0;      ///< max owned / mean owned
  GlobalId total_ghosts = 0;   ///< sum over ranks
  GlobalId max_ghosts = 0;
  double seconds = 0.0;
  /// Seconds of its phases on this rank: gather (the edge lists to rank 0),
  /// metis_graph (METIS's CSR), metis (the call) or bfs (bfs_graph first
  /// where it builds its own rows from edges), scatter (the owners),
  /// or parmetis_graph and parmetis; stats.
  std::vector<std::pair<std::string, double>> phases;
  /// Bytes of the largest partitioner structures on this rank (METIS's or
  /// ParMETIS's graph, the gathered edges, the owner array on rank 0).
  std::int64_t peak_bytes = 0;
};

/// Distributed directory of node owners: rank r holds, for the global ids of
/// its block (block_range(n, P, r)), each node's owner and its index among
/// that owner's nodes: block by block, within a block in ascending (key,
/// global id) order (keys: all 0 when none are given), so that a block's
/// nodes of one owner take consecutive indices there. Nothing of size n on any rank; lookups are all-to-alls.
/// Holds its own duplicate communicator.
class OwnerDirectory {
 public:
  struct Slot {
    std::int32_t owner, index;
  };
  OwnerDirectory() = default;
  /// Collective. `owners`: the owner rank of each node of this rank's block;
  /// `keys` (empty, or one per node, >= 0): the order of the owner's indices.
  /// The bfs partition's keys are breadth-first distances, so that a part's
  /// indices run in bands and neighbours get nearby indices: the graph build
  /// then walks nearby memory where global ids scatter it.
  OwnerDirectory(MPI_Comm comm, GlobalId n, const std::vector<int>& owners,
                 const std::vector<std::int32_t>& keys = {});
  /// Collective. From every node's owner, the same vector on every rank.
  static OwnerDirectory from_dense(MPI_Comm comm, GlobalId n, const std::vector<int>& owner);
  MPI_Comm comm() const { return comm_.get(); }
  GlobalId num_global() const { return n_; }
  GlobalId block_begin() const { return begin_; }
  GlobalId block_end() const { return begin_ + static_cast<GlobalId>(slots_.size()); }
  /// The slot of a node of this rank's block.
  const Slot& local(GlobalId g) const { return slots_[static_cast<std::size_t>(g - begin_)]; }
  /// Starts loading local(g)'s cache line: loops over edges in random order
  /// issue it a few records ahead so that lookups overlap (at 10M the slots
  /// are 40 MB per rank, beyond the caches).
  void prefetch(GlobalId g) const { __builtin_prefetch(slots_.data() + (g - begin_)); }
  /// Collective: this rank's nodes in slot index order; with by_gid, their
  /// indices in ascending global id order.
  std::vector<GlobalId> owned_nodes(std::vector<std::int32_t>* by_gid = nullptr) const;
  /// Collective: nodes per rank (on every rank).
  std::vector<GlobalId> counts() const;
  /// Collective: every node's owner on every rank (O(n): for callers that
  /// need it whole, e.g. the consensus solvers).
  std::vector<int> gather_dense() const;
  std::int64_t memory_bytes() const { return static_cast<std::int64_t>(slots_.capacity() * sizeof(Slot)); }

 private:
  DupComm comm_;
  GlobalId n_ = 0, begin_ = 0;
  // Apart from malloc's heap: it lives through the graph build, whose larger
  // temporaries reuse the room the partition freed around it (MappedAllocator).
  std::vector<Slot, MappedAllocator<Slot>> slots_;
};

/// Collective. The owners of the nodes as a distributed directory. `edges`:
/// this rank's share of the undirected edges (pairs of global ids), each edge
/// given once overall. metis: METIS k-way on rank 0 over the gathered graph
/// (Debian's METIS has 32-bit idx_t: graphs too large for it fall back to
/// block with a note). parmetis: ParMETIS_V3_PartKway (PT-Scotch) over the
/// block-distributed graph, no rank holds more than its block. Stats get the
/// imbalance; the edge cut is counted by DistGraph (DistGraph::edge_cut).
OwnerDirectory partition_nodes(MPI_Comm comm, GlobalId n, const std::vector<GlobalId>& edges,
                               PartitionMethod method, PartitionStats* stats);

/// Collective. Owner rank of every global node, identical on every rank
/// (partition_nodes gathered; stats get the edge cut as well).
std::vector<int> partition_graph(MPI_Comm comm, GlobalId n, const std::vector<GlobalId>& edges,
                                 PartitionMethod method, PartitionStats* stats);

}  // namespace snl
