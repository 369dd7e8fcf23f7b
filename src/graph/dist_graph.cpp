// DistGraph's build as its steps (DistGraph::build): the rows routed to
// their owners (row_routing.cpp), the local order (local_order.cpp), then
// here the ghosts, the local numbering, the CSR and the halo plan.
#include "snl/graph/dist_graph.hpp"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <type_traits>

#include "graph/graph_build.hpp"
#include "snl/core/mpi_util.hpp"

namespace snl {

void pack_offsets(std::vector<std::int64_t>& start, std::vector<int>& scount, int width, const char* what) {
  const int size = static_cast<int>(start.size()) - 1;
  scount.assign(static_cast<std::size_t>(size), 0);
  for (int r = 0; r < size; ++r) {
    if (start[r + 1] > INT32_MAX / std::max(width, 1))
      throw Error(std::string(what) + ": more than 2^31 items for one rank in one message; use more ranks");
    scount[r] = static_cast<int>(start[r + 1]);
    start[r + 1] += start[r];
  }
}

LocalOrdering default_local_ordering() {
  const char* e = std::getenv("SNL_TEST_LOCAL_ORDER");
  return (e && std::strcmp(e, "gid") == 0) ? LocalOrdering::kGlobalId : LocalOrdering::kRcm;
}

bool setup_wide_ids(MPI_Comm comm, GlobalId n) {
  const char* e = std::getenv("SNL_TEST_SETUP_IDS");
  int mine = (e && std::strcmp(e, "64") == 0) ? 1 : 0, any = 0;
  MPI_Allreduce(&mine, &any, 1, MPI_INT, MPI_MAX, comm);
  return n > std::numeric_limits<std::int32_t>::max() || any != 0;
}

using namespace graph_build;

namespace {

// Step 4: the ghosts, by (owner, gid) so that each neighbour rank's slots are
// contiguous.
struct Ghost {
  std::int32_t owner, index;  // the owner and its index there (OwnerDirectory::Slot)
  GlobalId g;
};

template <class Id>
std::vector<Ghost> ghost_nodes(const OwnedLists<Id>& L, int rank) {
  std::vector<Ghost> ghosts;
  for (std::size_t k = 0; k < L.entries.size(); ++k)
    if (L.nbr_owner(k) != rank) ghosts.push_back({L.nbr_owner(k), L.nbr_index(k), L.entries[k].nbr});
  std::sort(ghosts.begin(), ghosts.end(),
            [](const Ghost& x, const Ghost& y) { return x.owner != y.owner ? x.owner < y.owner : x.g < y.g; });
  ghosts.erase(std::unique(ghosts.begin(), ghosts.end(), [](const Ghost& x, const Ghost& y) { return x.g == y.g; }),
               ghosts.end());
  if (L.owned.size() + ghosts.size() > static_cast<std::size_t>(std::numeric_limits<LocalId>::max()))
    throw Error("too many local nodes on one rank for 32-bit local ids; use more ranks");
  return ghosts;
}

// Global id -> local id during the build: owned nodes through their owned
// index, ghosts by binary search.
struct LocalIds {
  std::vector<LocalId> owned_to_local;                    // owned index -> local id
  std::vector<std::pair<GlobalId, LocalId>> ghost_sorted;  // (gid, local id), by gid
  LocalId ghost(GlobalId g) const {
    return std::lower_bound(ghost_sorted.begin(), ghost_sorted.end(), std::make_pair(g, LocalId(-1)))->second;
  }
};

// Step 4 (cont.): local ids: owned nodes in `order`, then the ghosts; fills
// the graph's local_to_global and owned_sorted.
template <class Id>
LocalIds number_nodes(const OwnedLists<Id>& L, const std::vector<std::int64_t>& order, const std::vector<Ghost>& ghosts,
                      std::vector<GlobalId>& local_to_global, std::vector<std::pair<GlobalId, LocalId>>& owned_sorted) {
  const std::size_t n_owned = L.owned.size();
  LocalIds ids;
  local_to_global.resize(n_owned + ghosts.size());
  ids.owned_to_local.resize(n_owned);
  for (std::size_t l = 0; l < order.size(); ++l) {
    local_to_global[l] = L.owned[order[l]];
    ids.owned_to_local[order[l]] = static_cast<LocalId>(l);
  }
  for (std::size_t t = 0; t < ghosts.size(); ++t) local_to_global[n_owned + t] = ghosts[t].g;
  owned_sorted.resize(n_owned);
  for (std::size_t t = 0; t < n_owned; ++t) owned_sorted[t] = {L.owned[L.by_gid[t]], ids.owned_to_local[L.by_gid[t]]};
  ids.ghost_sorted.resize(ghosts.size());
  for (std::size_t t = 0; t < ghosts.size(); ++t)
    ids.ghost_sorted[t] = {ghosts[t].g, static_cast<LocalId>(n_owned + t)};
  std::sort(ids.ghost_sorted.begin(), ids.ghost_sorted.end());
  return ids;
}

// Step 5: the CSR in local order, neighbours in global-id order (the edges'
// values follow: values_to_csr).
template <class Id>
void fill_csr(const OwnedLists<Id>& L, const std::vector<std::int64_t>& order, const LocalIds& ids, int rank,
              std::vector<std::int64_t>& offsets, std::vector<LocalId>& adjacency) {
  const std::size_t n = order.size();
  offsets.assign(n + 1, 0);
  adjacency.resize(L.entries.size());
  for (std::size_t l = 0; l < n; ++l) {
    if (l + 16 < n) __builtin_prefetch(&L.cnt[order[l + 16]]);
    offsets[l + 1] = offsets[l] + (L.cnt[order[l] + 1] - L.cnt[order[l]]);
  }
  // The lists are read in their own (global) order and each node's block is
  // written to its place in the local order: reading them in local order
  // instead would make order -> cnt -> entries a chain of dependent misses.
  // Stores do not wait.
  constexpr std::size_t kAhead = 16, kDestAhead = 8, kIdsAhead = 4;
  for (std::size_t v = 0; v < n; ++v) {
    if (v + kAhead < n) __builtin_prefetch(&offsets[ids.owned_to_local[v + kAhead]]);
    if (v + kDestAhead < n)  // the block's first line, for writing: the stores otherwise stall on their misses
      __builtin_prefetch(adjacency.data() + offsets[ids.owned_to_local[v + kDestAhead]], 1);
    if (v + kIdsAhead < n)  // the neighbours' local ids, read at random
      for (auto k = L.cnt[v + kIdsAhead]; k < L.cnt[v + kIdsAhead + 1]; ++k)
        if (L.nbr_owner(k) == rank) __builtin_prefetch(&ids.owned_to_local[L.nbr_index(k)]);
    std::int64_t pos = offsets[ids.owned_to_local[v]];
    for (auto k = L.cnt[v]; k < L.cnt[v + 1]; ++k, ++pos)
      adjacency[pos] = L.nbr_owner(k) == rank ? ids.owned_to_local[L.nbr_index(k)] : ids.ghost(L.entries[k].nbr);
  }
}

// Step 6: the halo plan. Each owner is told which of its nodes we need, in
// our ghost order (one all-to-all of the request lists); what the others ask
// of us becomes our send lists. Requests name the owner-side index.
template <class Id>
HaloPlan make_halo(MPI_Comm comm, const std::vector<Ghost>& ghosts, const OwnedLists<Id>& L, const LocalIds& ids,
                   int halo_width) {
  const int size = comm_size(comm);
  std::vector<std::vector<GlobalId>> requests(size);
  for (const Ghost& h : ghosts) requests[h.owner].push_back(h.index);
  std::vector<int> nbr_ranks;
  std::vector<LocalId> recv_offset, recv_count;
  LocalId off = 0;
  for (int r = 0; r < size; ++r) {
    if (requests[r].empty()) continue;
    nbr_ranks.push_back(r);
    recv_offset.push_back(off);
    recv_count.push_back(static_cast<LocalId>(requests[r].size()));
    off += static_cast<LocalId>(requests[r].size());
  }
  std::vector<std::vector<GlobalId>> tagged(size);  // per rank: count, then the ids
  for (int r = 0; r < size; ++r) {
    tagged[r].reserve(requests[r].size() + 1);
    tagged[r].push_back(static_cast<GlobalId>(requests[r].size()));
    tagged[r].insert(tagged[r].end(), requests[r].begin(), requests[r].end());
  }
  const std::vector<GlobalId> asked = exchange_records(comm, tagged);
  std::vector<std::vector<LocalId>> send_ids;
  std::vector<int> senders;  // ranks that asked us, in rank order
  std::size_t p = 0;
  for (int r = 0; r < size; ++r) {
    const auto k = static_cast<std::size_t>(asked[p++]);
    if (k > 0) {
      std::vector<LocalId> sids(k);
      for (std::size_t t = 0; t < k; ++t) sids[t] = ids.owned_to_local[static_cast<std::size_t>(asked[p + t])];
      senders.push_back(r);
      send_ids.push_back(std::move(sids));
    }
    p += k;
  }
  // The graph is undirected, so the ranks we receive from are those we send to.
  if (senders != nbr_ranks) throw Error("internal error: asymmetric halo (edges not symmetric?)");
  return HaloPlan(comm, static_cast<LocalId>(L.owned.size()), nbr_ranks, std::move(send_ids), recv_offset,
                  recv_count, halo_width);
}

}  // namespace

DistGraph::DistGraph(MPI_Comm comm, GlobalId n, const std::vector<int>& owner, std::vector<GlobalId> edges,
                     std::vector<double> edge_values, int width, int halo_width, LocalOrdering ordering)
    : DistGraph(comm, OwnerDirectory::from_dense(comm, n, owner), std::move(edges), std::move(edge_values), width,
                halo_width, ordering) {}

DistGraph::DistGraph(MPI_Comm comm, const OwnerDirectory& owners, std::vector<GlobalId> edges,
                     std::vector<double> edge_values, int width, int halo_width, LocalOrdering ordering)
    : DistGraph(comm, owners,
                BlockRows::from_edges(comm, owners.num_global(), std::move(edges), std::move(edge_values), width),
                halo_width, ordering) {}

DistGraph::DistGraph(MPI_Comm comm, const OwnerDirectory& owners, BlockRows&& rows, int halo_width,
                     LocalOrdering ordering)
    : comm_(comm), n_global_(owners.num_global()), width_(rows.width) {
  if (rows.n != owners.num_global() || rows.begin != owners.block_begin() ||
      rows.num_rows() != static_cast<std::int64_t>(owners.block_end() - owners.block_begin()))
    throw std::logic_error("DistGraph: the rows' blocks are not the directory's");
  // Below 2^31 nodes the rows and lists carry 32-bit ids (BlockRows::wide).
  if (rows.wide) build(owners, std::move(rows), rows.nbr64, halo_width, ordering);
  else build(owners, std::move(rows), rows.nbr32, halo_width, ordering);
}

template <class Id>
void DistGraph::build(const OwnerDirectory& owners, BlockRows&& rows, std::vector<Id>& nbr, int halo_width,
                      LocalOrdering ordering) {
  const MPI_Comm gc = comm_.get();  // the graph's own duplicate (halo traffic apart from the caller's)
  const int rank = comm_rank(gc);
  PhaseClock clock(build_phases_);
  GlobalId cut = 0;
  std::vector<Id> ids = std::move(nbr);
  RowPlan plan;
  std::vector<std::int64_t> seg;
  Rounds rounds;
  OwnedLists<Id> lists = rows_to_owners(gc, owners, rows, ids, plan, seg, rounds, cut, clock);
  long long c = static_cast<long long>(cut), gcut = 0;
  MPI_Allreduce(&c, &gcut, 1, MPI_LONG_LONG, MPI_SUM, gc);
  edge_cut_ = gcut / 2;  // each cut edge is in the rows of both its ends
  clock.done("lists");
  // The rows' ids, read no more, hold RCM's group adjacency and then the
  // CSR's (4 bytes per entry, as 32-bit ids): freed, their block was taken
  // apart by smaller ones, and each adjacency took fresh pages (126 MiB at
  // 10M on 2 ranks). The CSR keeps the block where it is at most 1/8 larger.
  std::vector<std::int32_t> spare;
  if constexpr (std::is_same_v<Id, std::int32_t>) spare = std::move(ids);
  release(ids);
  const std::vector<std::int64_t> order = local_order(lists, ordering, n_interior_, spare);
  clock.done("order");
  n_owned_ = static_cast<LocalId>(lists.owned.size());
  const std::vector<Ghost> ghosts = ghost_nodes(lists, rank);
  LocalIds lids = number_nodes(lists, order, ghosts, local_to_global_, owned_sorted_);
  const std::size_t n_entries = lists.entries.size();
  if (spare.capacity() >= n_entries && spare.capacity() - n_entries <= n_entries / 8) adjacency_ = std::move(spare);
  release(spare);
  fill_csr(lists, order, lids, rank, offsets_, adjacency_);
  clock.done("csr");
  // The build's temporaries at their largest: the rows and lists while the
  // entries are sent (rows_to_owners); the lists beside the rows' values and
  // the ids' block (RCM's, then the CSR's adjacency); the values' rounds
  // (values_to_csr).
  build_peak_bytes_ = std::max<std::int64_t>(lists.peak_bytes, rows.memory_bytes() + static_cast<std::int64_t>(
      lists.entries.capacity() * sizeof(Entry<Id>) + plan.row.capacity() * 12 + adjacency_.capacity() * 4 +
      (lists.cnt.capacity() + lists.owned.capacity()) * 8 + lists.by_gid.capacity() * 4 +
      ghosts.capacity() * sizeof(Ghost) + lids.ghost_sorted.capacity() * sizeof(lids.ghost_sorted[0]) +
      lids.owned_to_local.capacity() * sizeof(LocalId) + order.capacity() * 8));
  release(lists.entries);
  release(lids.ghost_sorted);
  values_to_csr(gc, plan, rounds, rows, lists.cnt, seg, lids.owned_to_local, offsets_, edge_values_,
                build_peak_bytes_);
  rows = BlockRows();
  clock.done("values");
  halo_ = make_halo(gc, ghosts, lists, lids, halo_width);
  clock.done("halo");
}

std::int64_t DistGraph::memory_bytes() const {
  return static_cast<std::int64_t>(local_to_global_.capacity() * sizeof(GlobalId) +
                                   offsets_.capacity() * sizeof(std::int64_t) +
                                   adjacency_.capacity() * sizeof(LocalId) + edge_values_.capacity() * sizeof(double) +
                                   owned_sorted_.capacity() * sizeof(std::pair<GlobalId, LocalId>)) +
         halo_.memory_bytes();
}

LocalId DistGraph::owned_local(GlobalId g) const {
  auto it = std::lower_bound(owned_sorted_.begin(), owned_sorted_.end(), std::make_pair(g, LocalId(-1)));
  return (it != owned_sorted_.end() && it->first == g) ? it->second : -1;
}

std::vector<double> DistGraph::take_last_edge_column() {
  const std::size_t slots = width_ > 0 ? edge_values_.size() / width_ : 0;
  std::vector<double> last(slots), rest(slots * (width_ - 1));
  for (std::size_t e = 0; e < slots; ++e) {
    for (int c = 0; c + 1 < width_; ++c) rest[e * (width_ - 1) + c] = edge_values_[e * width_ + c];
    last[e] = edge_values_[e * width_ + width_ - 1];
  }
  edge_values_.swap(rest);
  --width_;
  return last;
}

LocalId DistGraph::max_degree() const {
  LocalId d = 0;
  for (LocalId v = 0; v < n_owned_; ++v) d = std::max(d, degree(v));
  LocalId g = 0;
  MPI_Allreduce(&d, &g, 1, MPI_INT32_T, MPI_MAX, comm_.get());
  return g;
}

}  // namespace snl
