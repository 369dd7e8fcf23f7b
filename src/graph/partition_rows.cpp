// The partition graph: every rank's edge pairs as rows of the block holders
// of their nodes (route_half_rows, fill_block_rows), gathered to rank 0 as one
// CSR for the partitioners that run there (root_csr_impl).
#include <algorithm>
#include <limits>

#include "graph/partition_detail.hpp"
#include "snl/core/mpi_util.hpp"
#include "snl/graph/dist_graph.hpp"
#include "snl/graph/partition.hpp"
#include "snl/io/network.hpp"

namespace snl {
namespace detail {

// root_csr, step 1: each pair's two half-edges to the block holders of their
// nodes; those of this rank's block stay (keep), the others are packed by
// destination and exchanged (got). Collective; "" or why not.
template <class Index>
std::string route_half_rows(MPI_Comm comm, const Blocks& blocks, const std::vector<GlobalId>& edges,
                         std::vector<HalfRow<Index>>& keep, std::vector<HalfRow<Index>>& got, std::int64_t& bytes) {
  const int size = blocks.size(), rank = comm_rank(comm);
  std::vector<HalfRow<Index>> sbuf;
  std::vector<int> scount(size, 0);
  bool ok = true;
  try {
    std::vector<std::int64_t> start(static_cast<std::size_t>(size) + 1, 0);
    std::int64_t local = 0;
    for (const GlobalId v : edges) {
      const int r = blocks.of(v);
      if (r == rank) ++local;
      else ++start[r + 1];
    }
    for (int r = 0; r < size; ++r) {
      ok = ok && start[r + 1] <= std::numeric_limits<int>::max();
      scount[r] = static_cast<int>(start[r + 1]);
      start[r + 1] += start[r];
    }
    ok = ok && start[size] <= std::numeric_limits<int>::max();
    keep.reserve(static_cast<std::size_t>(local));
    sbuf.resize(static_cast<std::size_t>(start[size]));
    auto put = [&](GlobalId v, GlobalId u) {
      const int r = blocks.of(v);
      const HalfRow<Index> h{static_cast<std::int32_t>(v - blocks.first[r]), static_cast<Index>(u)};
      if (r == rank) keep.push_back(h);
      else sbuf[start[r]++] = h;
    };
    for (std::size_t k = 0; k + 1 < edges.size(); k += 2) {
      put(edges[k], edges[k + 1]);
      put(edges[k + 1], edges[k]);
    }
  } catch (const std::bad_alloc&) {
    ok = false;
  }
  if (!all_ranks(comm, ok)) return "out of memory (or over 2^31 half-edges on a rank) building the partition's graph";
  bytes = static_cast<std::int64_t>((keep.capacity() + 2 * sbuf.size()) * sizeof(HalfRow<Index>));
  got = exchange_packed(comm, std::move(sbuf), scount);
  return "";
}

// root_csr, step 2: the rows of this rank's block of nb nodes: counted,
// filled, each sorted by neighbour id (the bfs probes follow a row's first
// entries). Two levels, as DistGraph's neighbour lists: the
// half-edges go into buckets of consecutive rows (few write streams), then
// each bucket's rows are counted and filled in cache (filling straight into
// the block's rows would wait on a cache miss per half-edge). Consumes keep and got. Returns false when out
// of memory.
template <class Offset, class Index>
bool fill_block_rows(std::int64_t nb, std::vector<HalfRow<Index>>&& keep, std::vector<HalfRow<Index>>&& got,
                std::vector<Offset>& lx, std::vector<Index>& ladj, std::int64_t& bytes) {
  constexpr std::int64_t kBuckets = 1024;
  bool ok = true;
  try {
    int shift = 0;
    while ((nb >> shift) >= kBuckets) ++shift;
    const std::int64_t nk = (nb >> shift) + 1;
    std::vector<std::int64_t> bstart(static_cast<std::size_t>(nk) + 1, 0);
    for (const auto& h : keep) ++bstart[(h.v >> shift) + 1];
    for (const auto& h : got) ++bstart[(h.v >> shift) + 1];
    for (std::int64_t k = 0; k < nk; ++k) bstart[k + 1] += bstart[k];
    std::vector<HalfRow<Index>> bucketed(static_cast<std::size_t>(bstart[nk]));
    {
      std::vector<std::int64_t> fill(bstart.begin(), bstart.end() - 1);
      for (const auto& h : keep) bucketed[fill[h.v >> shift]++] = h;
      for (const auto& h : got) bucketed[fill[h.v >> shift]++] = h;
    }
    bytes = static_cast<std::int64_t>((keep.capacity() + got.capacity() + bucketed.size()) * sizeof(HalfRow<Index>));
    release(keep);
    release(got);
    lx.assign(static_cast<std::size_t>(nb) + 1, 0);
    for (const auto& h : bucketed) ++lx[h.v + 1];
    for (std::int64_t v = 0; v < nb; ++v) lx[v + 1] += lx[v];
    ladj.resize(static_cast<std::size_t>(lx[nb]));
    std::vector<Offset> fill;
    for (std::int64_t k = 0; k < nk; ++k) {
      const std::int64_t v0 = k << shift;
      const std::int64_t v1 = std::min(nb, (k + 1) << shift);
      if (v0 >= v1) continue;
      fill.assign(lx.begin() + v0, lx.begin() + v1);
      for (auto p = bstart[k]; p < bstart[k + 1]; ++p) ladj[fill[bucketed[p].v - v0]++] = bucketed[p].u;
    }
    bytes = std::max(bytes, static_cast<std::int64_t>(bucketed.size() * sizeof(HalfRow<Index>) +
                                                      lx.size() * sizeof(Offset) + ladj.size() * sizeof(Index)));
  } catch (const std::bad_alloc&) {
    ok = false;
  }
  release(keep);
  release(got);
  for (std::int64_t v = 0; v < nb && ok; ++v) std::sort(ladj.begin() + lx[v], ladj.begin() + lx[v + 1]);
  return ok;
}

// root_csr, step 3: every block's rows to rank 0, which places them at their
// offsets (row ends from MPI_Gatherv, entries in messages of at most 2^27).
// Consumes lx and ladj. Collective; "" or why not.
template <class Offset, class Index>
std::string gather_rows(MPI_Comm comm, GlobalId n, const Blocks& blocks, std::vector<Offset>&& lx,
                        std::vector<Index>&& ladj, std::vector<Offset>& xadj, std::vector<Index>& adjncy,
                        std::int64_t& bytes) {
  const int size = blocks.size(), rank = comm_rank(comm);
  const auto nb = static_cast<int>(lx.size() - 1);
  const auto mine = static_cast<std::int64_t>(ladj.size());
  std::vector<std::int64_t> first(size, 0), entries(size, 0);
  MPI_Gather(&mine, 1, MPI_INT64_T, entries.data(), 1, MPI_INT64_T, 0, comm);
  bool ok = true;
  if (rank == 0) {
    try {
      xadj.assign(static_cast<std::size_t>(n) + 1, 0);
      for (int r = 1; r < size; ++r) first[r] = first[r - 1] + entries[r - 1];
      adjncy.resize(static_cast<std::size_t>(first[size - 1] + entries[size - 1]));
    } catch (const std::bad_alloc&) {
      ok = false;
    }
  }
  if (!all_ranks(comm, ok)) return "out of memory building the partition's graph on rank 0";
  MPI_Datatype off_type, idx_type;
  MPI_Type_contiguous(static_cast<int>(sizeof(Offset)), MPI_BYTE, &off_type);
  MPI_Type_contiguous(static_cast<int>(sizeof(Index)), MPI_BYTE, &idx_type);
  MPI_Type_commit(&off_type);
  MPI_Type_commit(&idx_type);
  // Each row's end within its block's entries; rank 0 adds the block's first offset.
  std::vector<int> counts(size), displs(size);
  for (int r = 0; r < size; ++r) {
    counts[r] = static_cast<int>(blocks.first[r + 1] - blocks.first[r]);
    displs[r] = static_cast<int>(blocks.first[r] + 1);
  }
  MPI_Gatherv(lx.data() + 1, nb, off_type, rank == 0 ? xadj.data() : nullptr, counts.data(), displs.data(), off_type, 0,
              comm);
  release(lx);
  constexpr std::int64_t kChunk = 1LL << 27;  // entries per message (int counts)
  if (rank == 0) {
    for (int r = 0; r < size; ++r)
      for (int v = 0; v < counts[r]; ++v) xadj[displs[r] + v] += static_cast<Offset>(first[r]);
    std::copy(ladj.begin(), ladj.end(), adjncy.begin());
    release(ladj);
    for (int r = 1; r < size; ++r)
      for (std::int64_t pos = first[r], left = entries[r]; left > 0;) {
        const int c = static_cast<int>(std::min(left, kChunk));
        MPI_Recv(adjncy.data() + pos, c, idx_type, r, 12, comm, MPI_STATUS_IGNORE);
        pos += c;
        left -= c;
      }
    bytes = static_cast<std::int64_t>(xadj.size() * sizeof(Offset) + adjncy.size() * sizeof(Index)) +
            mine * static_cast<std::int64_t>(sizeof(Index));
  } else {
    for (std::int64_t pos = 0, left = mine; left > 0;) {
      const int c = static_cast<int>(std::min(left, kChunk));
      MPI_Send(ladj.data() + pos, c, idx_type, 0, 12, comm);
      pos += c;
      left -= c;
    }
    release(ladj);
  }
  MPI_Type_free(&off_type);
  MPI_Type_free(&idx_type);
  return "";
}

// The undirected graph of the edge pairs (each rank's share) as CSR on rank
// 0, each row ascending: partitions depend on the neighbour order, and this
// one does not depend on which rank held which edge. Built in parallel: each
// half-edge goes to the block holder of its node (none moves where an edge
// has both ends in the sender's block), which counts, fills and sorts the rows
// of its block; the rows are gathered to rank 0 in block order. Rank 0 holds
// the CSR alone, not the gathered pairs beside it (at 10M sensors on 2 ranks
// 1.0 GB instead of 2.0), and the rows are sorted by all ranks. Collective;
// returns "" on success, else why not (the same on every rank). peak: this
// rank's bytes at their largest.
template <class Offset, class Index>
std::string root_csr_impl(MPI_Comm comm, GlobalId n, const std::vector<GlobalId>& edges, std::vector<Offset>& xadj,
                          std::vector<Index>& adjncy, std::int64_t& peak) {
  if (n >= std::numeric_limits<int>::max()) return "graph too large for a partition on one rank (2^31 nodes)";
  const Blocks blocks(n, comm_size(comm));
  const int rank = comm_rank(comm);
  std::vector<HalfRow<Index>> keep, got;
  std::int64_t routed = 0, rows = 0, gathered = 0;
  std::string why = route_half_rows(comm, blocks, edges, keep, got, routed);
  if (!why.empty()) return why;
  std::vector<Offset> lx;
  std::vector<Index> ladj;
  const bool ok = fill_block_rows(blocks.first[rank + 1] - blocks.first[rank], std::move(keep), std::move(got), lx, ladj, rows);
  if (!all_ranks(comm, ok)) return "out of memory building the partition's graph";
  why = gather_rows(comm, n, blocks, std::move(lx), std::move(ladj), xadj, adjncy, gathered);
  peak = std::max({routed, rows, gathered});
  return why;
}

template std::string route_half_rows<std::int32_t>(MPI_Comm, const Blocks&, const std::vector<GlobalId>&,
                                                   std::vector<HalfRow<std::int32_t>>&,
                                                   std::vector<HalfRow<std::int32_t>>&, std::int64_t&);
template std::string route_half_rows<std::int64_t>(MPI_Comm, const Blocks&, const std::vector<GlobalId>&,
                                                   std::vector<HalfRow<std::int64_t>>&,
                                                   std::vector<HalfRow<std::int64_t>>&, std::int64_t&);
template bool fill_block_rows<std::int64_t, std::int32_t>(std::int64_t, std::vector<HalfRow<std::int32_t>>&&,
                                                          std::vector<HalfRow<std::int32_t>>&&,
                                                          std::vector<std::int64_t>&, std::vector<std::int32_t>&,
                                                          std::int64_t&);
template bool fill_block_rows<std::int64_t, std::int64_t>(std::int64_t, std::vector<HalfRow<std::int64_t>>&&,
                                                          std::vector<HalfRow<std::int64_t>>&&,
                                                          std::vector<std::int64_t>&, std::vector<std::int64_t>&,
                                                          std::int64_t&);
// The bfs partition's CSR, and METIS's of either idx_t width.
template std::string root_csr_impl<std::int64_t, std::int32_t>(MPI_Comm, GlobalId, const std::vector<GlobalId>&,
                                                               std::vector<std::int64_t>&,
                                                               std::vector<std::int32_t>&, std::int64_t&);
template std::string root_csr_impl<std::int32_t, std::int32_t>(MPI_Comm, GlobalId, const std::vector<GlobalId>&,
                                                               std::vector<std::int32_t>&,
                                                               std::vector<std::int32_t>&, std::int64_t&);
template std::string root_csr_impl<std::int64_t, std::int64_t>(MPI_Comm, GlobalId, const std::vector<GlobalId>&,
                                                               std::vector<std::int64_t>&,
                                                               std::vector<std::int64_t>&, std::int64_t&);

}  // namespace detail

std::string detail::root_csr(MPI_Comm comm, GlobalId n, const std::vector<GlobalId>& edges,
                             std::vector<std::int64_t>& xadj, std::vector<std::int32_t>& adjncy, std::int64_t& peak) {
  return root_csr_impl(comm, n, edges, xadj, adjncy, peak);
}

}  // namespace snl
