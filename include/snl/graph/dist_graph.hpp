#pragma once
// Problem-agnostic distributed graph: local numbering (owned interior, owned
// boundary, then ghosts), per-edge data and the halo plan, on a partition
// (partition.hpp).
// The localization problem is one client; the consensus problem another.
#include <mpi.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "snl/core/common.hpp"
#include "snl/core/memory.hpp"
#include "snl/core/mpi_util.hpp"
#include "snl/graph/halo.hpp"
#include "snl/graph/partition.hpp"

namespace snl {


/// For a send buffer packed in rank order: `start` holds each rank's record
/// count at start[r + 1] (start[0] = 0, size + 1 entries) and becomes the
/// ranks' first places (a running sum); scount gets the counts. Refuses a
/// count whose `width` items per record exceed MPI's int (`what` names the
/// exchange in the error).
void pack_offsets(std::vector<std::int64_t>& start, std::vector<int>& scount, int width, const char* what);

/// Collective: an MPI_Alltoallv of a send buffer already in rank order
/// (scount[r] items for rank r) of trivially copyable items, which it
/// consumes; returns what this rank received, in rank order. On one rank the
/// buffer itself is returned (no copy). With `recv_counts`, how many came
/// from each rank.
template <class T>
std::vector<T> exchange_packed(MPI_Comm comm, std::vector<T>&& sbuf, const std::vector<int>& scount,
                               std::vector<int>* recv_counts = nullptr);

/// Collective all-to-all of trivially copyable records: out[r] goes to rank r;
/// returns what this rank received, concatenated in rank order.
/// With `recv_counts`, how many came from each rank.
template <class T>
std::vector<T> exchange_records(MPI_Comm comm, const std::vector<std::vector<T>>& out,
                                std::vector<int>* recv_counts = nullptr);

/// Order of the owned nodes inside the interior and boundary groups.
/// kRcm: reverse Cuthill-McKee on the owned subgraph, so that neighbours are
/// close in memory (the generator numbers sensors in random spatial order, and
/// global-id order makes every neighbour access a cache miss). kGlobalId: the
/// old order, kept for measurement. Results do not depend on it: every node
/// still sums its neighbours in global-id order.
enum class LocalOrdering { kRcm, kGlobalId };
/// kRcm unless the environment sets SNL_TEST_LOCAL_ORDER=gid (for benchmarks).
LocalOrdering default_local_ordering();

/// Whether the setup's temporaries (the merge's rows, the graph build's
/// records and lists) carry 64-bit node ids for a graph of n nodes: from 2^31
/// nodes on, or where the environment sets SNL_TEST_SETUP_IDS=64 on any rank (for
/// tests: both widths give the same problem). Below, 32-bit ids. Collective,
/// so that every rank takes the same width.
bool setup_wide_ids(MPI_Comm comm, GlobalId n);

/// The graph by blocks of rows: this rank holds the row of every node of its
/// id block (block_range), neighbours ascending by global id (the fixed
/// summation order), with `width` values per entry. Built once from the edge
/// pairs: the partition reads it (partition_nodes) and the DistGraph consumes
/// it, so the edges are routed and sorted once for both.
struct BlockRows {
  GlobalId n = 0, begin = 0;  ///< nodes in all; this rank's first row
  int width = 0;
  bool wide = false;                  ///< neighbour ids in nbr64 (setup_wide_ids), else in nbr32
  std::vector<std::int64_t> offsets;  ///< row t: entries [offsets[t], offsets[t + 1])
  std::vector<std::int32_t> nbr32;
  std::vector<GlobalId> nbr64;
  std::vector<double> values;  ///< `width` per entry
  std::int64_t peak_bytes = 0;  ///< the build's temporaries at their largest on this rank
  std::int64_t merged = 0;      ///< entries merged away (from_pairs) in this rank's rows of smaller ends
  std::int64_t num_rows() const { return offsets.empty() ? 0 : static_cast<std::int64_t>(offsets.size()) - 1; }
  std::int64_t memory_bytes() const {
    return static_cast<std::int64_t>(offsets.capacity() * 8 + nbr32.capacity() * 4 + nbr64.capacity() * 8 +
                                     values.capacity() * 8);
  }
  /// Collective. `edges`: this rank's share of the undirected edges (any rank
  /// may hold any edge, each edge once overall), `values`: `width` per edge;
  /// both consumed. Each edge's two half-edges go to the block holders of
  /// their nodes, which bucket them into rows and sort each row.
  static BlockRows from_edges(MPI_Comm comm, GlobalId n, std::vector<GlobalId>&& edges, std::vector<double>&& values,
                              int width);
  /// How entries of one pair met more than once are merged (duplicate
  /// measurements): merge(values, count, width) gets `count` entries' values,
  /// ascending (lexicographically), and leaves the merged ones in the first
  /// `width`.
  using Merge = std::function<void(double* values, std::int64_t count, int width)>;
  /// Collective. From columns: pair e is (ends[2e], ends[2e + 1]), either
  /// orientation, with the value col0[e] and, where width is 2, col1[e] (col1
  /// null: 0). A pair met more than once (on any ranks) becomes one entry per
  /// row, merged by `merge`. `packed` is called once the columns are read
  /// (the caller may free them then).
  static BlockRows from_pairs(MPI_Comm comm, GlobalId n, const GlobalId* ends, std::size_t count, const double* col0,
                              const double* col1, int width, const Merge& merge,
                              const std::function<void()>& packed = {});
  /// This rank's edges with the smaller end in its block, as pairs (for the
  /// partitioners that take edge lists).
  std::vector<GlobalId> edges() const;
};

/// Collective. partition_nodes over block rows (BlockRows::from_edges): the
/// bfs partition walks them in place; the other methods take their edges.
OwnerDirectory partition_nodes(MPI_Comm comm, const BlockRows& rows, PartitionMethod method, PartitionStats* stats);

class DistGraph {
 public:
  DistGraph() = default;
  /// Collective. Duplicates `comm` once (freed by the destructor).
  /// `owners`: the owner directory (partition_nodes). `edges`: this
  /// rank's share of the undirected edges (global pairs, each edge once
  /// overall, any rank may hold any edge), with `width` doubles of data each
  /// in `edge_values`. `halo_width`: most doubles per node the halo carries.
  /// Both lists are taken by value: move them in (std::move) and their memory
  /// is freed as soon as the build has its own copy of them.
  DistGraph(MPI_Comm comm, const OwnerDirectory& owners, std::vector<GlobalId> edges,
            std::vector<double> edge_values, int width, int halo_width,
            LocalOrdering ordering = default_local_ordering());
  /// Collective. From block rows (consumed), with the same result as from
  /// their edges.
  DistGraph(MPI_Comm comm, const OwnerDirectory& owners, BlockRows&& rows, int halo_width,
            LocalOrdering ordering = default_local_ordering());
  /// The same from every node's owner rank (identical on every rank).
  DistGraph(MPI_Comm comm, GlobalId n, const std::vector<int>& owner, std::vector<GlobalId> edges,
            std::vector<double> edge_values, int width, int halo_width,
            LocalOrdering ordering = default_local_ordering());

  /// The graph's own duplicate of the constructor's communicator (congruent
  /// to it, never the same handle): the halo exchange and the clients'
  /// collectives run on it, apart from the caller's traffic.
  MPI_Comm comm() const { return comm_.get(); }
  GlobalId num_global() const { return n_global_; }
  LocalId num_owned() const { return n_owned_; }
  /// Owned nodes [0, num_interior()) have no ghost neighbour.
  LocalId num_interior() const { return n_interior_; }
  LocalId num_ghosts() const { return static_cast<LocalId>(local_to_global_.size()) - n_owned_; }
  LocalId num_local() const { return static_cast<LocalId>(local_to_global_.size()); }
  const std::vector<GlobalId>& local_to_global() const { return local_to_global_; }
  GlobalId global_id(LocalId v) const { return local_to_global_[v]; }

  /// Neighbours of owned node v: adjacency()[offsets()[v] .. offsets()[v+1]),
  /// sorted by global id (the fixed summation order that makes results
  /// independent of the number of ranks), with edge_value(e, c) alongside.
  const std::vector<std::int64_t>& offsets() const { return offsets_; }
  const std::vector<LocalId>& adjacency() const { return adjacency_; }
  double edge_value(std::int64_t e, int c = 0) const { return edge_values_[e * width_ + c]; }
  const std::vector<double>& edge_values() const { return edge_values_; }
  /// For clients that redraw edge data in place (Monte Carlo over noise).
  std::vector<double>& mutable_edge_values() { return edge_values_; }
  int edge_width() const { return width_; }
  /// Removes the last column of the edge data and returns it, one value per
  /// slot (data that travels with the edges but is not the range, e.g. sigmas).
  std::vector<double> take_last_edge_column();
  LocalId degree(LocalId v) const { return static_cast<LocalId>(offsets_[v + 1] - offsets_[v]); }
  LocalId max_degree() const;  ///< global (collective)

  HaloPlan& halo() { return halo_; }
  const HaloPlan& halo() const { return halo_; }

  /// Seconds spent in the constructor's phases on this rank (slots,
  /// exchange, lists, order, csr, halo), for the setup report.
  const std::vector<std::pair<std::string, double>>& build_phases() const { return build_phases_; }

  /// Undirected edges whose ends have different owners (same on every rank).
  GlobalId edge_cut() const { return edge_cut_; }
  /// Largest bytes of the constructor's temporaries on this rank (block
  /// rows, neighbour lists, send buffers), for the memory accounting.
  std::int64_t build_peak_bytes() const { return build_peak_bytes_; }

  /// Bytes held by the graph's arrays (capacities), halo buffers included.
  std::int64_t memory_bytes() const;

  /// Map of owned global id -> local id, by binary search over the owned
  /// nodes (kept sorted in owned_sorted_). Returns -1 if not owned.
  LocalId owned_local(GlobalId g) const;
  /// The owned nodes as (global id, local id), ascending in global id.
  const std::vector<std::pair<GlobalId, LocalId>>& owned_by_global_id() const { return owned_sorted_; }

 private:
  // The constructor's steps with node ids of type Id in its temporaries.
  template <class Id>
  void build(const OwnerDirectory& owners, BlockRows&& rows, std::vector<Id>& nbr, int halo_width,
             LocalOrdering ordering);

  // Declared first, so destroyed last: the halo's requests are freed before
  // the communicator they live on.
  DupComm comm_;
  GlobalId n_global_ = 0;
  LocalId n_owned_ = 0, n_interior_ = 0;
  GlobalId edge_cut_ = 0;
  std::int64_t build_peak_bytes_ = 0;
  int width_ = 0;
  std::vector<GlobalId> local_to_global_;
  std::vector<std::pair<std::string, double>> build_phases_;
  std::vector<std::int64_t> offsets_;
  std::vector<LocalId> adjacency_;
  std::vector<double> edge_values_;
  std::vector<std::pair<GlobalId, LocalId>> owned_sorted_;
  HaloPlan halo_;
};

// ---- template implementation ----
template <class T>
std::vector<T> exchange_packed(MPI_Comm comm, std::vector<T>&& sbuf, const std::vector<int>& scount,
                               std::vector<int>* recv_counts) {
  int size = 1;
  MPI_Comm_size(comm, &size);
  if (size == 1) {  // nothing to move between ranks
    if (recv_counts) *recv_counts = scount;
    return std::move(sbuf);
  }
  std::vector<int> rcount(size), sdisp(size), rdisp(size);
  MPI_Alltoall(scount.data(), 1, MPI_INT, rcount.data(), 1, MPI_INT, comm);
  std::int64_t rtot = 0, stot = 0;
  for (int r = 0; r < size; ++r) {
    sdisp[r] = static_cast<int>(stot);
    rdisp[r] = static_cast<int>(std::min<std::int64_t>(rtot, INT32_MAX));
    stot += scount[r];
    rtot += rcount[r];
  }
  int ok = rtot <= INT32_MAX && stot <= INT32_MAX, all_ok = 0;
  MPI_Allreduce(&ok, &all_ok, 1, MPI_INT, MPI_MIN, comm);
  if (!all_ok) throw Error("record exchange: more than 2^31 records sent or received by one rank; use more ranks");
  std::vector<T> rbuf(static_cast<std::size_t>(rtot));
  MPI_Datatype rec;
  MPI_Type_contiguous(static_cast<int>(sizeof(T)), MPI_BYTE, &rec);
  MPI_Type_commit(&rec);
  MPI_Alltoallv(sbuf.data(), scount.data(), sdisp.data(), rec, rbuf.data(), rcount.data(), rdisp.data(), rec, comm);
  MPI_Type_free(&rec);
  release(sbuf);
  if (recv_counts) *recv_counts = std::move(rcount);
  return rbuf;
}

template <class T>
std::vector<T> exchange_records(MPI_Comm comm, const std::vector<std::vector<T>>& out, std::vector<int>* recv_counts) {
  int size = 1;
  MPI_Comm_size(comm, &size);
  MPI_Datatype rec;
  MPI_Type_contiguous(static_cast<int>(sizeof(T)), MPI_BYTE, &rec);
  MPI_Type_commit(&rec);
  std::vector<int> scount(size), rcount(size), sdisp(size), rdisp(size);
  std::int64_t stot = 0;
  for (int r = 0; r < size; ++r) {
    if (out[r].size() > static_cast<std::size_t>(INT32_MAX)) throw Error("exchange_records: message too large");
    scount[r] = static_cast<int>(out[r].size());
    stot += scount[r];
  }
  if (stot > INT32_MAX) throw Error("exchange_records: send volume exceeds 2^31 records");
  MPI_Alltoall(scount.data(), 1, MPI_INT, rcount.data(), 1, MPI_INT, comm);
  std::int64_t rtot = 0;
  for (int r = 0; r < size; ++r) {
    sdisp[r] = static_cast<int>(r == 0 ? 0 : sdisp[r - 1] + scount[r - 1]);
    rdisp[r] = static_cast<int>(rtot);
    rtot += rcount[r];
  }
  if (rtot > INT32_MAX) throw Error("exchange_records: receive volume exceeds 2^31 records");
  std::vector<T> sbuf;
  sbuf.reserve(static_cast<std::size_t>(stot));
  for (int r = 0; r < size; ++r) sbuf.insert(sbuf.end(), out[r].begin(), out[r].end());
  std::vector<T> rbuf(static_cast<std::size_t>(rtot));
  MPI_Alltoallv(sbuf.data(), scount.data(), sdisp.data(), rec, rbuf.data(), rcount.data(), rdisp.data(), rec, comm);
  MPI_Type_free(&rec);
  if (recv_counts) *recv_counts = std::move(rcount);
  return rbuf;
}

}  // namespace snl
