// Partitioning (METIS or breadth-first level structures on rank 0, ParMETIS
// through PT-Scotch, block) and the distributed owner directory that DistGraph
// builds from. Over 600 lines because the partitioners share the rows of the
// partition graph built here (root_csr); one file per partitioner behind this
// interface is open work.
#include <metis.h>

#include <algorithm>
#include <functional>
#include <limits>
#include <numeric>

#include "graph/partition_detail.hpp"
#include "snl/core/mpi_util.hpp"
#include "snl/graph/dist_graph.hpp"
#include "snl/graph/partition.hpp"
#include "snl/io/network.hpp"

#ifdef SNL_HAVE_PARMETIS
#define SCOTCH_METIS_RETURN  // METIS_OK etc. come from metis.h (the same values)
#include <parmetis.h>  // PT-Scotch's compatibility header: idx_t is SCOTCH_Num, real_t is float
#endif

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

// ---- Breadth-first level-structure partition ----

namespace {
// bfs_partition with range labels of type Key: one byte where the labels
// fit (1 + 4 (nparts - 1) of them), so that the label array, read at random
// once per edge, is a quarter of the size (10 MB at 10M nodes) and stays in cache.
constexpr int kByteLabelParts = 64;
template <class Key>
std::vector<int> bfs_partition_keyed(const std::vector<std::int64_t>& xadj, const std::vector<std::int32_t>& adjncy,
                                     int nparts) {
  const std::int32_t n = static_cast<std::int32_t>(xadj.size() - 1);
  // ord: a permutation of the nodes in which every range still to be split is
  // contiguous. key[v]: a label of v's range, renewed by every pass that
  // visits v, so that one array (one cache miss per neighbour: the graph's
  // numbering is random, these loops wait on memory) tells both "in this
  // range" and "not yet visited".
  std::vector<std::int32_t> ord(n), queue(n);
  std::vector<Key> key(n, 0);
  std::iota(ord.begin(), ord.end(), 0);
  std::vector<int> owner(n, 0);
  struct Range {
    std::int32_t lo, hi;
    int p0, p1;
  };
  std::vector<Range> todo{{0, n, 0, nparts}};
  std::int32_t labels = 1;
  // Breadth-first order of the nodes labelled `from` reachable from root, into
  // queue[q0, ...), relabelled `to`; returns the end. Rows and labels are
  // prefetched a few queue places ahead.
  auto bfs = [&](std::int32_t root, std::int32_t from, std::int32_t to, std::int32_t q0) {
    std::int32_t head = q0, tail = q0;
    queue[tail++] = root;
    key[root] = static_cast<Key>(to);
    while (head < tail) {
      if (head + 12 < tail) __builtin_prefetch(&xadj[queue[head + 12]]);
      if (head + 6 < tail) __builtin_prefetch(&adjncy[xadj[queue[head + 6]]]);
      if (head + 3 < tail) {
        const std::int32_t w = queue[head + 3];
        for (std::int64_t k = xadj[w]; k < xadj[w + 1]; ++k) __builtin_prefetch(&key[adjncy[k]]);
      }
      const std::int32_t v = queue[head++];
      for (std::int64_t k = xadj[v]; k < xadj[v + 1]; ++k) {
        const std::int32_t u = adjncy[k];
        if (key[u] == from) {
          key[u] = static_cast<Key>(to);
          queue[tail++] = u;
        }
      }
    }
    return tail;
  };
  while (!todo.empty()) {
    const Range g = todo.back();
    todo.pop_back();
    const std::int32_t size = g.hi - g.lo, label = key[ord[g.lo]];
    if (g.p1 - g.p0 == 1 || size == 0) {
      for (std::int32_t t = g.lo; t < g.hi; ++t) owner[ord[t]] = g.p0;
      continue;
    }
    // The range in breadth-first order, component by component in the order
    // of their first nodes in the range; each from a pseudo-peripheral root:
    // the last node reached from that first node (one sweep of RCM's start).
    const std::int32_t sweep = labels++, order = labels++;
    std::int32_t tail = 0;
    for (std::int32_t t = g.lo; t < g.hi && tail < size; ++t) {
      if (key[ord[t]] != label) continue;
      const std::int32_t root = queue[bfs(ord[t], label, sweep, tail) - 1];
      tail = bfs(root, sweep, order, tail);
    }
    std::copy(queue.begin(), queue.begin() + size, ord.begin() + g.lo);
    // Split in proportion to the parts on each side: the first nodes of the
    // order (nearest the root) to the lower parts.
    const int pm = g.p0 + (g.p1 - g.p0) / 2;
    const std::int32_t mid =
        g.lo + static_cast<std::int32_t>(static_cast<std::int64_t>(size) * (pm - g.p0) / (g.p1 - g.p0));
    const std::int32_t left = labels++, right = labels++;
    for (std::int32_t t = g.lo; t < g.hi; ++t) key[ord[t]] = static_cast<Key>(t < mid ? left : right);
    todo.push_back({mid, g.hi, pm, g.p1});
    todo.push_back({g.lo, mid, g.p0, pm});
  }
  return owner;
}
}  // namespace

std::vector<int> bfs_partition(const std::vector<std::int64_t>& xadj, const std::vector<std::int32_t>& adjncy,
                               int nparts) {
  if (nparts <= kByteLabelParts) return bfs_partition_keyed<std::uint8_t>(xadj, adjncy, nparts);
  return bfs_partition_keyed<std::int32_t>(xadj, adjncy, nparts);
}

// ---- OwnerDirectory ----

namespace {
// Key histograms of more entries fall back to global-id order (keys ignored).
constexpr long long kMaxKeyBins = 1LL << 22;
}  // namespace

OwnerDirectory::OwnerDirectory(MPI_Comm comm, GlobalId n, const std::vector<int>& owners,
                               const std::vector<std::int32_t>& keys)
    : comm_(comm), n_(n) {
  const MPI_Comm c = comm_.get();
  const int size = comm_size(c);
  GlobalId e;
  block_range(n, size, comm_rank(c), begin_, e);
  if (static_cast<GlobalId>(owners.size()) != e - begin_ || (!keys.empty() && keys.size() != owners.size()))
    throw Error("internal error: owner block of wrong size");
  // A node's index on its owner: the owner's nodes in lower blocks (an
  // exclusive scan), then its place among the owner's nodes of this block in
  // (key, global id) order: block by block, so that a block holder sends an
  // owner's rows in the owner's index order and the owner receives them in
  // place (DistGraph). Bins (owner, key) laid out owner by owner, keys 0..max
  // of that owner in this block; without keys, or with more bins than
  // kMaxKeyBins, one bin per owner.
  std::vector<long long> per_owner(size, 0), base(size, 0);
  for (const int o : owners) ++per_owner[o];
  MPI_Exscan(per_owner.data(), base.data(), size, MPI_LONG_LONG, MPI_SUM, c);
  if (comm_rank(c) == 0) std::fill(base.begin(), base.end(), 0);  // Exscan leaves rank 0's undefined
  std::vector<long long> kmax(size, 0);
  for (std::size_t t = 0; t < keys.size(); ++t) kmax[owners[t]] = std::max<long long>(kmax[owners[t]], keys[t]);
  std::vector<long long> first(static_cast<std::size_t>(size) + 1, 0);
  for (int o = 0; o < size; ++o) first[o + 1] = first[o] + kmax[o] + 1;
  const bool keyed = !keys.empty() && first[size] <= kMaxKeyBins;
  if (!keyed)
    for (int o = 0; o < size; ++o) first[o + 1] = o + 1;
  auto bin = [&](std::size_t t) { return first[owners[t]] + (keyed ? keys[t] : 0); };
  std::vector<long long> next(static_cast<std::size_t>(first[size]), 0);
  for (std::size_t t = 0; t < owners.size(); ++t) ++next[bin(t)];
  for (int o = 0; o < size; ++o)
    for (long long b = first[o], below = base[o]; b < first[o + 1]; ++b) {
      const long long k = next[b];
      next[b] = below;
      below += k;
    }
  slots_.resize(owners.size());
  for (std::size_t t = 0; t < owners.size(); ++t) {
    const long long i = next[bin(t)]++;
    if (i > std::numeric_limits<LocalId>::max())
      throw Error("too many sensors on one rank for 32-bit local ids; use more ranks");
    slots_[t] = {owners[t], static_cast<std::int32_t>(i)};
  }
}

OwnerDirectory OwnerDirectory::from_dense(MPI_Comm comm, GlobalId n, const std::vector<int>& owner) {
  GlobalId b, e;
  block_range(n, comm_size(comm), comm_rank(comm), b, e);
  return OwnerDirectory(comm, n, std::vector<int>(owner.begin() + b, owner.begin() + e));
}

std::vector<GlobalId> OwnerDirectory::owned_nodes(std::vector<std::int32_t>* by_gid) const {
  // Each block sends its nodes, with their indices, to their owners in one
  // exchange; blocks arrive in rank order, each ascending, so the
  // concatenation is in global id order.
  struct Node {
    GlobalId g;
    std::int32_t index;
  };
  const MPI_Comm c = comm_.get();
  const int size = comm_size(c);
  std::vector<std::vector<Node>> out(size);
  {  // counted first: no reallocation
    std::vector<std::size_t> cnt(size, 0);
    for (const Slot& s : slots_) ++cnt[s.owner];
    for (int r = 0; r < size; ++r) out[r].reserve(cnt[r]);
  }
  for (std::size_t t = 0; t < slots_.size(); ++t)
    out[slots_[t].owner].push_back({begin_ + static_cast<GlobalId>(t), slots_[t].index});
  const std::vector<Node> got = exchange_records(c, out);
  std::vector<GlobalId> owned(got.size());
  if (by_gid) by_gid->resize(got.size());
  for (std::size_t t = 0; t < got.size(); ++t) {
    owned[static_cast<std::size_t>(got[t].index)] = got[t].g;
    if (by_gid) (*by_gid)[t] = got[t].index;
  }
  return owned;
}

std::vector<GlobalId> OwnerDirectory::counts() const {
  const int size = comm_size(comm_.get());
  std::vector<long long> cnt(size, 0), tot(size, 0);
  for (const Slot& s : slots_) ++cnt[s.owner];
  MPI_Allreduce(cnt.data(), tot.data(), size, MPI_LONG_LONG, MPI_SUM, comm_.get());
  return std::vector<GlobalId>(tot.begin(), tot.end());
}

std::vector<int> OwnerDirectory::gather_dense() const {
  const MPI_Comm c = comm_.get();
  const int size = comm_size(c);
  std::vector<int> mine(slots_.size()), counts(size), displs(size);
  for (std::size_t t = 0; t < slots_.size(); ++t) mine[t] = slots_[t].owner;
  for (int r = 0; r < size; ++r) {
    GlobalId b, e;
    block_range(n_, size, r, b, e);
    counts[r] = static_cast<int>(e - b);
    displs[r] = static_cast<int>(b);
  }
  if (n_ > std::numeric_limits<int>::max()) throw Error("gather_dense: more than 2^31 nodes");
  std::vector<int> all(static_cast<std::size_t>(n_));
  MPI_Allgatherv(mine.data(), static_cast<int>(mine.size()), MPI_INT, all.data(), counts.data(), displs.data(), MPI_INT,
                 c);
  return all;
}

namespace {

// Records the seconds since the previous mark under a phase name.
struct PhaseMarks {
  std::vector<std::pair<std::string, double>> phases;
  double mark = MPI_Wtime();
  void operator()(const char* name) {
    const double now = MPI_Wtime();
    phases.emplace_back(name, now - mark);
    mark = now;
  }
};

// A half-edge on its way to the block holder of its node: the node's offset
// in that block and the neighbour.
template <class Index>
struct HalfRow {
  std::int32_t v;
  Index u;
};

using detail::Blocks;

// root_csr, step 1: each pair's two half-edges to the block holders of their
// nodes; those of this rank's block stay (keep), the others are packed by
// destination and exchanged (got). Collective; "" or why not.
template <class Index>
std::string route_halves(MPI_Comm comm, const Blocks& blocks, const std::vector<GlobalId>& edges,
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
bool block_rows(std::int64_t nb, std::vector<HalfRow<Index>>&& keep, std::vector<HalfRow<Index>>&& got,
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
  std::string why = route_halves(comm, blocks, edges, keep, got, routed);
  if (!why.empty()) return why;
  std::vector<Offset> lx;
  std::vector<Index> ladj;
  const bool ok = block_rows(blocks.first[rank + 1] - blocks.first[rank], std::move(keep), std::move(got), lx, ladj, rows);
  if (!all_ranks(comm, ok)) return "out of memory building the partition's graph";
  why = gather_rows(comm, n, blocks, std::move(lx), std::move(ladj), xadj, adjncy, gathered);
  peak = std::max({routed, rows, gathered});
  return why;
}

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

// Breadth-first level-structure partition on rank 0 (recursive bisection
// by breadth-first order from a pseudo-peripheral node, George and Liu's
// level structures) over root_csr's graph: far cheaper than METIS, and on
// geometric graphs its parts are compact. Collective; returns "" on success,
// else why it could not run.
std::string bfs_on_root(MPI_Comm comm, GlobalId n, const std::vector<GlobalId>& edges, std::vector<int>& owner,
                        PhaseMarks& phase, std::int64_t& peak) {
  if (n > std::numeric_limits<std::int32_t>::max()) return "graph too large for the bfs partition on one rank";
  std::vector<std::int64_t> xadj;
  std::vector<std::int32_t> adjncy;
  std::string why = root_csr_impl(comm, n, edges, xadj, adjncy, peak);
  if (!why.empty()) return why;
  phase("bfs_graph");
  if (comm_rank(comm) != 0) return "";
  try {
    // The CSR and the partition's four arrays of n (labels of 1 or 4 bytes).
    const int label_bytes = comm_size(comm) <= kByteLabelParts ? 1 : 4;
    peak = std::max(peak, static_cast<std::int64_t>(xadj.size() * 8 + adjncy.size() * 4) + n * (12 + label_bytes));
    owner = bfs_partition(xadj, adjncy, comm_size(comm));
  } catch (const std::bad_alloc&) {
    return "out of memory in the bfs partition";
  }
  phase("bfs");
  return "";
}

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

#ifdef SNL_HAVE_PARMETIS
// ParMETIS's idx_t in PT-Scotch's header; the CMake module picks the 64-bit build.
using pidx_t = SCOTCH_Num;
static_assert(sizeof(pidx_t) == 8, "PT-Scotch's ParMETIS interface must be the 64-bit build (parmetis-int64)");

struct HalfEdge {
  GlobalId v, u;
};

// ParMETIS_V3_PartKway over the block-distributed graph: each edge goes to the
// block owners of both ends, which build their rows of the CSR. Collective;
// returns "" on success, else why it could not run. PT-Scotch's result may
// vary between runs (threads, message order): the iterates do not depend on it.
std::string parmetis_partition(MPI_Comm comm, GlobalId n, const std::vector<GlobalId>& edges,
                               std::vector<int>& block, PhaseMarks& phase, std::int64_t& peak) {
  const int size = comm_size(comm), rank = comm_rank(comm);
  GlobalId b, e;
  block_range(n, size, rank, b, e);
  std::vector<HalfEdge> mine;
  {
    std::vector<std::vector<HalfEdge>> out(size);
    for (std::size_t k = 0; k < edges.size(); k += 2) {
      out[block_owner(n, size, edges[k])].push_back({edges[k], edges[k + 1]});
      out[block_owner(n, size, edges[k + 1])].push_back({edges[k + 1], edges[k]});
    }
    mine = exchange_records(comm, out);
  }
  std::vector<pidx_t> vtxdist(size + 1), xadj(static_cast<std::size_t>(e - b) + 1, 0), adjncy(mine.size());
  for (int r = 0; r <= size; ++r) {
    GlobalId rb, re;
    block_range(n, size, std::min(r, size - 1), rb, re);
    vtxdist[r] = r == size ? re : rb;
  }
  for (const HalfEdge& h : mine) ++xadj[h.v - b + 1];
  for (std::size_t v = 0; v + 1 < xadj.size(); ++v) xadj[v + 1] += xadj[v];
  {
    std::vector<pidx_t> fill(xadj.begin(), xadj.end() - 1);
    for (const HalfEdge& h : mine) adjncy[fill[h.v - b]++] = h.u;
  }
  peak = static_cast<std::int64_t>(mine.capacity() * sizeof(HalfEdge) +
                                   (xadj.size() + adjncy.size() + vtxdist.size()) * sizeof(pidx_t));
  release(mine);
  phase("parmetis_graph");
  pidx_t wgtflag = 0, numflag = 0, ncon = 1, nparts = size, edgecut = 0;
  pidx_t options[3] = {0, 0, 0};
  std::vector<float> tpwgts(size, 1.0f / static_cast<float>(size));
  float ubvec = 1.03f;  // METIS's default imbalance tolerance (ufactor 30)
  std::vector<pidx_t> part(xadj.size() - 1, 0);
  MPI_Comm c = comm;
  int status = METIS_ERROR;
  try {
    status = ParMETIS_V3_PartKway(vtxdist.data(), xadj.data(), adjncy.data(), nullptr, nullptr, &wgtflag, &numflag,
                                  &ncon, &nparts, tpwgts.data(), &ubvec, options, &edgecut, part.data(), &c);
  } catch (...) {
    status = METIS_ERROR;
  }
  if (!all_ranks(comm, status == METIS_OK)) return "ParMETIS (PT-Scotch) failed";
  block.assign(part.begin(), part.end());
  phase("parmetis");
  return "";
}
#endif

// The bfs partition over this rank's block rows (lx, ladj of neighbour ids
// of type Index). Collective; "", kPastMaxLevels or why not.
template <class Index>
std::string bfs_on_rows(MPI_Comm comm, const Blocks& blocks, const std::vector<std::int64_t>& lx,
                        const std::vector<Index>& ladj, int nparts, std::int64_t max_levels, std::vector<int>& block,
                        std::int64_t& peak, std::vector<std::int32_t>* keys) {
  std::int64_t bytes = 0;
  const bool ok = detail::level_bisection(comm, blocks, lx, ladj, nparts, max_levels, block, bytes, keys);
  peak = std::max(peak, bytes + static_cast<std::int64_t>(lx.capacity() * 8 + ladj.capacity() * sizeof(Index)));
  return ok ? "" : detail::kPastMaxLevels;
}

// detail::bfs_blocks with neighbour ids of type Index.
template <class Index>
std::string bfs_blocks_impl(MPI_Comm comm, GlobalId n, const std::vector<GlobalId>& edges, int nparts,
                            std::int64_t max_levels, std::vector<int>& block, std::int64_t& peak,
                            const std::function<void(const char*)>& mark, std::vector<std::int32_t>* keys) {
  const Blocks blocks(n, comm_size(comm));
  const int rank = comm_rank(comm);
  const std::int64_t nb = blocks.first[rank + 1] - blocks.first[rank];
  if (!all_ranks(comm, nb < std::numeric_limits<std::int32_t>::max()))
    return "graph too large for the bfs partition on this many ranks (2^31 nodes per rank)";
  std::vector<HalfRow<Index>> keep, got;
  std::int64_t routed = 0, rows = 0;
  std::string why = route_halves(comm, blocks, edges, keep, got, routed);
  if (!why.empty()) return why;
  std::vector<std::int64_t> lx;
  std::vector<Index> ladj;
  if (!all_ranks(comm, block_rows(nb, std::move(keep), std::move(got), lx, ladj, rows)))
    return "out of memory building the partition's graph";
  if (mark) mark("bfs_graph");
  peak = std::max({peak, routed, rows});
  why = bfs_on_rows(comm, blocks, lx, ladj, nparts, max_levels, block, peak, keys);
  if (why.empty() && mark) mark("bfs");
  return why;
}

// The bfs partition by every rank, over the block rows where they are given
// (else built from the edges); on a graph whose breadth-first passes run
// past default_max_levels (long chains) the one on rank 0, which walks them
// without a collective per level.
std::string bfs_partition_blocks(MPI_Comm comm, GlobalId n, const std::vector<GlobalId>& edges,
                                 const BlockRows* rows, std::vector<int>& block, std::vector<std::int32_t>& keys,
                                 PhaseMarks& phase, std::int64_t& peak, std::string& note) {
  const std::int64_t max_levels = detail::default_max_levels(n);
  PhaseMarks attempt;
  std::string why;
  if (rows) {
    const Blocks blocks(n, comm_size(comm));
    why = rows->wide ? bfs_on_rows(comm, blocks, rows->offsets, rows->nbr64, comm_size(comm), max_levels, block, peak,
                                   &keys)
                     : bfs_on_rows(comm, blocks, rows->offsets, rows->nbr32, comm_size(comm), max_levels, block, peak,
                                   &keys);
    if (why.empty()) attempt("bfs");
  } else {
    why = detail::bfs_blocks(comm, n, edges, comm_size(comm), max_levels, block, peak,
                             [&](const char* s) { attempt(s); }, &keys);
  }
  if (why != detail::kPastMaxLevels) {
    phase.phases.insert(phase.phases.end(), attempt.phases.begin(), attempt.phases.end());
    phase.mark = attempt.mark;
    return why;
  }
  keys.clear();
  note = "the bfs partition ran on rank 0 (a breadth-first pass of over " + std::to_string(max_levels) + " levels)";
  phase("bfs_abandoned");  // the attempt, rows and passes, as one phase
  return partition_on_root(comm, n, rows ? rows->edges() : edges, PartitionMethod::kBfs, block, phase, peak);
}

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
    why = bfs_partition_blocks(comm, n, edges, rows, block, keys, phase, peak, note);
    if (why.empty()) used = "bfs";
  } else if (method == PartitionMethod::kMetis && size > 1) {
    why = partition_on_root(comm, n, edges, method, block, phase, peak);
    if (why.empty()) used = "metis";
  } else if (method == PartitionMethod::kParMetis && size > 1) {
#ifdef SNL_HAVE_PARMETIS
    // PT-Scotch needs vertices on every rank: tiny graphs go to METIS.
    why = n >= 2 * static_cast<GlobalId>(size) ? parmetis_partition(comm, n, edges, block, phase, peak)
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

std::string detail::bfs_blocks(MPI_Comm comm, GlobalId n, const std::vector<GlobalId>& edges, int nparts,
                               std::int64_t max_levels, std::vector<int>& block, std::int64_t& peak,
                               const std::function<void(const char*)>& mark, std::vector<std::int32_t>* keys) {
  if (n <= std::numeric_limits<std::int32_t>::max())
    return bfs_blocks_impl<std::int32_t>(comm, n, edges, nparts, max_levels, block, peak, mark, keys);
  return bfs_blocks_impl<GlobalId>(comm, n, edges, nparts, max_levels, block, peak, mark, keys);
}

std::string detail::root_csr(MPI_Comm comm, GlobalId n, const std::vector<GlobalId>& edges,
                             std::vector<std::int64_t>& xadj, std::vector<std::int32_t>& adjncy, std::int64_t& peak) {
  return root_csr_impl(comm, n, edges, xadj, adjncy, peak);
}

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
