// The breadth-first level-structure partition (recursive bisection by
// breadth-first order from a pseudo-peripheral node, George and Liu's level
// structures): serially on rank 0 over the partition graph's CSR, or by every
// rank over its block rows (level_bisection.cpp).
#include <algorithm>
#include <functional>
#include <limits>
#include <numeric>

#include "graph/partition_detail.hpp"
#include "snl/core/mpi_util.hpp"
#include "snl/graph/dist_graph.hpp"
#include "snl/graph/partition.hpp"
#include "snl/io/network.hpp"

namespace snl {

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

namespace detail {

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
  std::string why = route_half_rows(comm, blocks, edges, keep, got, routed);
  if (!why.empty()) return why;
  std::vector<std::int64_t> lx;
  std::vector<Index> ladj;
  if (!all_ranks(comm, fill_block_rows(nb, std::move(keep), std::move(got), lx, ladj, rows)))
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

}  // namespace detail

std::string detail::bfs_blocks(MPI_Comm comm, GlobalId n, const std::vector<GlobalId>& edges, int nparts,
                               std::int64_t max_levels, std::vector<int>& block, std::int64_t& peak,
                               const std::function<void(const char*)>& mark, std::vector<std::int32_t>* keys) {
  if (n <= std::numeric_limits<std::int32_t>::max())
    return bfs_blocks_impl<std::int32_t>(comm, n, edges, nparts, max_levels, block, peak, mark, keys);
  return bfs_blocks_impl<GlobalId>(comm, n, edges, nparts, max_levels, block, peak, mark, keys);
}

}  // namespace snl
