// DistGraph's build, in its order: local ordering (RCM, degree windows), the
// neighbour-slot directory, the rows routed to their owners in rounds, and the
// CSR and halo assembly. Over 600 lines because the four steps share the
// build's private types (Entry, Lists, Rounds) and its temporaries; splitting
// them into files behind an internal header is open work.
#include "snl/graph/dist_graph.hpp"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <type_traits>

#include "graph/partition_detail.hpp"
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

namespace {
// One neighbour of an owned node: its global id and directory slot
// (OwnerDirectory::Slot), so that no later pass reads the edge records again.
template <class Id>
struct Entry {
  Id nbr;
  std::int32_t owner, index;
};

// Within consecutive windows of kDegreeWindow nodes, nodes of equal degree
// next to each other (stable sort by degree): the node-lane kernels pad each
// chunk of SIMD lanes to its largest degree (kernels.hpp; the sigma of
// SELL-C-sigma, Kreutzer et al. 2014). Windows of 32 keep RCM's locality
// while cutting the padding.
void sort_degree_windows(std::vector<std::int64_t>& grp, const std::vector<std::int64_t>& cnt) {
  constexpr std::size_t kDegreeWindow = 32;
  auto deg = [&](std::int64_t v) { return cnt[v + 1] - cnt[v]; };
  for (std::size_t b = 0; b < grp.size(); b += kDegreeWindow) {
    const auto e = grp.begin() + std::min(grp.size(), b + kDegreeWindow);
    std::stable_sort(grp.begin() + b, e, [&](std::int64_t x, std::int64_t y) { return deg(x) > deg(y); });
  }
}

// The adjacency of one group (interior or boundary) in group positions
// (32-bit), neighbours in list order; nbr(k) is entry k's owned index, or -1
// for a ghost. The scattered nodes -> cnt -> entries -> pos lookups are done
// once here instead of in each of the two BFS sweeps of rcm_order. `spare`:
// a buffer to build the adjacency in (taken; rcm_order gives it back).
struct GroupGraph {
  std::vector<std::int64_t> off;
  std::vector<std::int32_t> adj, deg;
};

template <class Nbr>
GroupGraph group_graph(const std::vector<std::int64_t>& nodes, const std::vector<std::int64_t>& cnt, Nbr&& nbr,
                       const std::vector<std::int32_t>& pos, std::vector<std::int32_t>& spare) {
  const std::size_t m = nodes.size();
  GroupGraph g;
  g.off.assign(m + 1, 0);
  g.adj = std::move(spare);
  g.adj.clear();
  {
    std::size_t total = 0;
    for (std::size_t t = 0; t < m; ++t) total += std::size_t(cnt[nodes[t] + 1] - cnt[nodes[t]]);
    g.adj.reserve(total);
  }
  constexpr std::size_t kAhead = 4;  // nodes whose neighbours' positions are fetched ahead (random reads)
  for (std::size_t t = 0; t < m; ++t) {
    if (t + kAhead < m)
      for (auto k = cnt[nodes[t + kAhead]]; k < cnt[nodes[t + kAhead] + 1]; ++k)
        if (const std::int64_t u = nbr(k); u >= 0) __builtin_prefetch(&pos[u]);
    for (auto k = cnt[nodes[t]]; k < cnt[nodes[t] + 1]; ++k)
      if (const std::int64_t u = nbr(k); u >= 0 && pos[u] >= 0) g.adj.push_back(pos[u]);
    g.off[t + 1] = static_cast<std::int64_t>(g.adj.size());
  }
  g.deg.resize(m);
  for (std::size_t t = 0; t < m; ++t) g.deg[t] = static_cast<std::int32_t>(g.off[t + 1] - g.off[t]);
  return g;
}

// Positions by increasing degree, ties in the order of `ties` (all
// positions, by global id; a counting sort: degrees are small, and it is
// stable): the BFS start candidates. Ties by global id, not by position,
// keep the order independent of the owner-side indices' order.
std::vector<std::int64_t> by_degree(const std::vector<std::int32_t>& deg, const std::vector<std::int64_t>& ties) {
  const std::size_t m = deg.size();
  std::vector<std::int64_t> by_deg(m);
  const std::int32_t max_deg = m ? *std::max_element(deg.begin(), deg.end()) : 0;
  std::vector<std::int64_t> start(static_cast<std::size_t>(max_deg) + 2, 0);
  for (std::size_t t = 0; t < m; ++t) ++start[deg[t] + 1];
  for (std::size_t d = 1; d < start.size(); ++d) start[d] += start[d - 1];
  for (const std::int64_t t : ties) by_deg[start[deg[t]]++] = t;
  return by_deg;
}

// The BFS sweeps of rcm_order over one GroupGraph; `order` collects group
// positions in Cuthill-McKee order (not yet reversed).
class CuthillMcKee {
 public:
  explicit CuthillMcKee(const GroupGraph& g) : g_(g), seen_(g.deg.size(), 0), level_(g.deg.size(), -1) {
    order.reserve(g.deg.size());
  }
  bool seen(std::int64_t t) const { return seen_[t] != 0; }
  // Appends t as the root of a sweep.
  void add_root(std::int64_t t) {
    seen_[t] = 1;
    order.push_back(t);
  }

  // One BFS from s over unseen nodes; returns the last level's min-degree
  // node (George-Liu's pseudo-peripheral node, one sweep).
  std::int64_t bfs_far(std::int64_t s) {
    queue_.assign(1, s);
    level_[s] = 0;
    std::int64_t best = s;
    for (std::size_t h = 0; h < queue_.size(); ++h) {
      const std::int64_t t = queue_[h];
      if (level_[t] > level_[best] || (level_[t] == level_[best] && g_.deg[t] < g_.deg[best])) best = t;
      for (auto k = g_.off[t]; k < g_.off[t + 1]; ++k) {
        const std::int64_t u = g_.adj[k];
        if (!seen_[u] && level_[u] < 0) {
          level_[u] = level_[t] + 1;
          queue_.push_back(u);
        }
      }
    }
    for (auto t : queue_) level_[t] = -1;
    return best;
  }

  // One Cuthill-McKee BFS from the nodes already appended at `head`: each
  // node's unseen neighbours by increasing degree.
  void sweep(std::size_t head) {
    for (; head < order.size(); ++head) {
      // The queue is known ahead: its offsets, lists and the neighbours'
      // flags are fetched ahead (a random graph order otherwise stalls on
      // each of the three in turn), as in bfs_partition.
      if (head + 16 < order.size()) __builtin_prefetch(&g_.off[order[head + 16]]);
      if (head + 8 < order.size()) __builtin_prefetch(&g_.adj[g_.off[order[head + 8]]]);
      if (head + 4 < order.size()) {
        const std::int64_t w = order[head + 4];
        for (auto k = g_.off[w]; k < g_.off[w + 1]; ++k) {
          __builtin_prefetch(&seen_[g_.adj[k]]);
          __builtin_prefetch(&g_.deg[g_.adj[k]]);
        }
      }
      const std::int64_t t = order[head];
      kids_.clear();
      for (auto k = g_.off[t]; k < g_.off[t + 1]; ++k) {
        const std::int64_t u = g_.adj[k];
        if (!seen_[u]) {
          seen_[u] = 1;
          kids_.push_back(u);
        }
      }
      // Stable insertion sort by degree: a node has few children, and
      // std::stable_sort allocates a buffer on every call (5M calls at 10M).
      for (std::size_t i = 1; i < kids_.size(); ++i) {
        const std::int64_t u = kids_[i];
        std::size_t j = i;
        for (; j > 0 && g_.deg[kids_[j - 1]] > g_.deg[u]; --j) kids_[j] = kids_[j - 1];
        kids_[j] = u;
      }
      order.insert(order.end(), kids_.begin(), kids_.end());
    }
  }

  std::vector<std::int64_t> order;

 private:
  const GroupGraph& g_;
  std::vector<char> seen_;
  std::vector<std::int32_t> level_;
  std::vector<std::int64_t> kids_, queue_;
};

// Reverse Cuthill-McKee of the graph (cnt, nbr: as group_graph) restricted to `nodes` (one
// group: interior or boundary): BFS from a pseudo-peripheral node (George-Liu,
// one sweep), children by increasing degree, then reversed. `pos[v]` is v's
// position in `nodes` or -1 for nodes outside the group. With `seeds`
// (positions in `nodes`), the first BFS starts from all of them at once, as
// its first level: the interior group is seeded with its nodes next to the
// boundary, so that after the reversal the interior runs from the nodes
// farthest from the boundary to those next to it, in layers (temporal
// blocking defers the chunks near the boundary: they are then contiguous).
// Deterministic: `ties` lists the positions by global id (by_degree); the
// sweeps break ties in list order, which is global-id order too. So the
// order does not depend on the order of `nodes`, which only lays out memory.
template <class Nbr>
std::vector<std::int64_t> rcm_order(const std::vector<std::int64_t>& nodes, const std::vector<std::int64_t>& cnt,
                                    Nbr&& nbr, const std::vector<std::int32_t>& pos,
                                    const std::vector<std::int64_t>& seeds, const std::vector<std::int64_t>& ties,
                                    std::vector<std::int32_t>& spare) {
  GroupGraph g = group_graph(nodes, cnt, nbr, pos, spare);
  const std::vector<std::int64_t> candidates = by_degree(g.deg, ties);
  CuthillMcKee cm(g);
  for (std::int64_t t : seeds)
    if (!cm.seen(t)) cm.add_root(t);
  cm.sweep(0);
  for (std::int64_t cand : candidates) {  // components without seeds
    if (cm.seen(cand)) continue;
    const std::int64_t s = cm.bfs_far(cand);
    const std::size_t head = cm.order.size();
    cm.add_root(s);
    cm.sweep(head);
  }
  std::vector<std::int64_t> order = std::move(cm.order);
  spare = std::move(g.adj);
  std::reverse(order.begin(), order.end());
  for (auto& t : order) t = nodes[t];
  return order;
}

// Seconds of the constructor's phases (DistGraph::build_phases): done(name)
// records the time since the previous mark.
class PhaseClock {
 public:
  explicit PhaseClock(std::vector<std::pair<std::string, double>>& out) : out_(out), mark_(MPI_Wtime()) {}
  void done(const char* name) {
    const double now = MPI_Wtime();
    out_.emplace_back(name, now - mark_);
    mark_ = now;
  }

 private:
  std::vector<std::pair<std::string, double>>& out_;
  double mark_;
};

// The owned nodes and their neighbour lists, indexed by position in `owned`
// (the directory's owner-side index), before the local numbering.
template <class Id>
struct OwnedLists {
  std::vector<GlobalId> owned;    // owned nodes in owner-side index order
  std::vector<std::int32_t> by_gid;  // their owner-side indices in ascending global id
  std::vector<std::int64_t> cnt;  // owned index v: entries [cnt[v], cnt[v + 1])
  std::vector<Entry<Id>> entries;  // per node sorted by neighbour global id
  std::vector<char> boundary;     // owned index v has a neighbour on another rank
  int rank = 0;
  std::int64_t peak_bytes = 0;    // the step's temporaries at their largest
  std::int32_t nbr_owner(std::int64_t k) const { return entries[k].owner; }
  std::int32_t nbr_index(std::int64_t k) const { return entries[k].index; }
};

// Step 1a: the directory slots of the rows' neighbours outside this rank's
// block. From a block that the rows name at least half as often as it has
// nodes, its whole block of slots (no ids sent: at 10M on 2 ranks each rank
// names the other's 5M nodes 40M times); from the others, the slots of the
// named ids, asked in the order the pack reads them (at(u) hands them out in
// that order). Collective.
template <class Id>
class NeighbourSlots {
 public:
  NeighbourSlots(MPI_Comm comm, const OwnerDirectory& dir, const std::vector<Id>& nbr)
      : dir_(dir), blocks_(dir.num_global(), comm_size(comm)), rank_(comm_rank(comm)) {
    const int size = blocks_.size();
    refs_.assign(static_cast<std::size_t>(size), 0);
    for (const Id u : nbr) ++refs_[blocks_.of(static_cast<GlobalId>(u))];
    dense_.assign(static_cast<std::size_t>(size), 0);
    for (int r = 0; r < size; ++r)
      dense_[r] = r != rank_ && 2 * refs_[r] >= blocks_.first[r + 1] - blocks_.first[r];
    const char* e = std::getenv("SNL_TEST_SETUP_SLOTS");  // tests: "ask" or "block" for every block
    if (e && std::strcmp(e, "ask") == 0) std::fill(dense_.begin(), dense_.end(), 0);
    if (e && std::strcmp(e, "block") == 0)
      for (int r = 0; r < size; ++r) dense_[r] = r != rank_;
  }
  bool asks() const {
    for (int r = 0; r < blocks_.size(); ++r)
      if (r != rank_ && !dense_[r] && refs_[r] > 0) return true;
    return false;
  }
  // Whether u's slot must be asked for (of block r): the caller lists such
  // ids in the order pack_rows reads them.
  bool asked(GlobalId u, int& r) const {
    r = blocks_.of(u);
    return r != rank_ && !dense_[r];
  }
  // The exchange: `ask[r]` holds the ids asked of block r, in pack order.
  void exchange(MPI_Comm comm, std::vector<std::vector<Id>>& ask);
  // u's slot; asked ids are answered in the order they were asked. A block
  // held whole (this rank's, or one sent whole) is read through its base
  // (whole_), without a branch on which it is: at 10M on 2 ranks the
  // neighbours fall in either block at random.
  const OwnerDirectory::Slot& at(GlobalId u) {
    const int r = blocks_.of(u);
    if (const OwnerDirectory::Slot* b = whole_[r]) return b[u - blocks_.first[r]];
    return got_[static_cast<std::size_t>(from_[r] + next_[r]++)];
  }
  // Where u's slot will be read, for a prefetch (asked slots are read in
  // order: their block's first answer does). The caller issues the prefetch:
  // GCC found a member function around it pure and dropped the call.
  const void* address(GlobalId u) const {
    const int r = blocks_.of(u);
    if (const OwnerDirectory::Slot* b = whole_[r]) return b + (u - blocks_.first[r]);
    return got_.data() + from_[r];
  }
  std::int64_t memory_bytes() const { return static_cast<std::int64_t>(got_.capacity() * sizeof(got_[0])); }

 private:
  const OwnerDirectory& dir_;
  detail::Blocks blocks_;
  int rank_;
  std::vector<std::int64_t> refs_, from_, next_;
  std::vector<char> dense_;
  std::vector<OwnerDirectory::Slot> got_;
  std::vector<const OwnerDirectory::Slot*> whole_;  // per block: its first node's slot where held whole, else null
};

template <class Id>
void NeighbourSlots<Id>::exchange(MPI_Comm comm, std::vector<std::vector<Id>>& ask) {
  const int size = blocks_.size();
  // Per pair: whether the whole block is wanted, and how many ids are asked.
  std::vector<std::int64_t> want(2 * static_cast<std::size_t>(size)), wanted(want.size());
  for (int r = 0; r < size; ++r) {
    want[2 * r] = dense_[r];
    want[2 * r + 1] = static_cast<std::int64_t>(ask[r].size());
  }
  MPI_Alltoall(want.data(), 2, MPI_INT64_T, wanted.data(), 2, MPI_INT64_T, comm);
  std::vector<std::int64_t> qstart(static_cast<std::size_t>(size) + 1, 0);
  for (int r = 0; r < size; ++r) qstart[r + 1] = static_cast<std::int64_t>(ask[r].size());
  std::vector<int> qcount;
  pack_offsets(qstart, qcount, 1, "neighbour slots");
  std::vector<Id> qbuf;
  qbuf.reserve(static_cast<std::size_t>(qstart[size]));
  for (auto& a : ask) {
    qbuf.insert(qbuf.end(), a.begin(), a.end());
    release(a);
  }
  std::vector<int> rq;
  const std::vector<Id> questions = exchange_packed(comm, std::move(qbuf), qcount, &rq);
  // The answers: a whole block where it is wanted, else each asked id's slot.
  const std::int64_t nb = blocks_.first[rank_ + 1] - blocks_.first[rank_];
  std::vector<std::int64_t> astart(static_cast<std::size_t>(size) + 1, 0);
  for (int r = 0; r < size; ++r) astart[r + 1] = wanted[2 * r] ? nb : rq[r];
  std::vector<int> acount;
  pack_offsets(astart, acount, 2, "neighbour slots");
  std::vector<OwnerDirectory::Slot> abuf(static_cast<std::size_t>(astart[size]));
  for (std::size_t r = 0, q = 0, p = 0; r < static_cast<std::size_t>(size); q += static_cast<std::size_t>(rq[r++])) {
    if (wanted[2 * r])
      for (std::int64_t t = 0; t < nb; ++t) abuf[p++] = dir_.local(blocks_.first[rank_] + t);
    else
      for (int t = 0; t < rq[r]; ++t) abuf[p++] = dir_.local(static_cast<GlobalId>(questions[q + t]));
  }
  std::vector<int> rcount;
  got_ = exchange_packed(comm, std::move(abuf), acount, &rcount);
  from_.assign(static_cast<std::size_t>(size), 0);
  next_.assign(static_cast<std::size_t>(size), 0);
  for (int r = 1; r < size; ++r) from_[r] = from_[r - 1] + rcount[r - 1];
  whole_.assign(static_cast<std::size_t>(size), nullptr);
  for (int r = 0; r < size; ++r)
    if (r == rank_ && nb > 0) whole_[r] = &dir_.local(blocks_.first[r]);
    else if (dense_[r] && rcount[r] > 0) whole_[r] = got_.data() + from_[r];
}

// A row's header on its way to its owner: the node, its degree and, in a
// second order, an owner-side index (see plan_rows).
struct RowHeader {
  GlobalId g;
  std::int32_t degree, by_gid;
};

// Where a block holder's rows go. The directory numbers an owner's nodes
// block by block (OwnerDirectory), so this rank's rows for owner o take
// consecutive indices there: in the owner's index order ("pack order"),
// owner by owner, they are pack positions first[o] .. first[o + 1]. Each
// owner's part (its entries from this rank, in pack order) is sent as it
// lands in the owner's lists.
struct RowPlan {
  std::vector<std::int64_t> rows_to, ents_to, first;  // per owner: rows, entries; first pack position
  std::vector<RowHeader> hdr;  // by pack position: node and degree; by_gid: the owner's k-th node of this block by id
  std::vector<std::int32_t> row;      // by pack position: the block row
  std::vector<std::int64_t> within;   // by pack position: the row's first entry within its owner's part
};

RowPlan plan_rows(const OwnerDirectory& dir, const BlockRows& R, int size) {
  const std::int64_t nb = R.num_rows();
  RowPlan P;
  P.rows_to.assign(static_cast<std::size_t>(size), 0);
  P.ents_to = P.rows_to;
  std::vector<std::int64_t> base(static_cast<std::size_t>(size), std::numeric_limits<std::int64_t>::max());
  for (std::int64_t t = 0; t < nb; ++t) {
    const auto& s = dir.local(R.begin + t);
    ++P.rows_to[s.owner];
    P.ents_to[s.owner] += R.offsets[t + 1] - R.offsets[t];
    base[s.owner] = std::min<std::int64_t>(base[s.owner], s.index);
  }
  P.first.assign(static_cast<std::size_t>(size) + 1, 0);
  for (int o = 0; o < size; ++o) P.first[o + 1] = P.first[o] + P.rows_to[o];
  std::vector<std::int64_t> seen(P.first.begin(), P.first.end() - 1);
  P.hdr.resize(static_cast<std::size_t>(nb));
  P.row.resize(static_cast<std::size_t>(nb));
  for (std::int64_t t = 0; t < nb; ++t) {
    const auto& s = dir.local(R.begin + t);
    const std::int64_t p = P.first[s.owner] + (s.index - base[s.owner]);
    if (s.index < base[s.owner] || p >= P.first[s.owner + 1])
      throw std::logic_error("graph build: an owner's indices of one block are not consecutive");
    P.row[static_cast<std::size_t>(p)] = static_cast<std::int32_t>(t);
    P.hdr[static_cast<std::size_t>(p)].g = R.begin + t;
    P.hdr[static_cast<std::size_t>(p)].degree = static_cast<std::int32_t>(R.offsets[t + 1] - R.offsets[t]);
    P.hdr[static_cast<std::size_t>(seen[s.owner]++)].by_gid = s.index;  // the k-th in global id order
  }
  P.within.resize(static_cast<std::size_t>(nb));
  for (int o = 0; o < size; ++o)
    for (std::int64_t p = P.first[o], a = 0; p < P.first[o + 1]; ++p) {
      P.within[static_cast<std::size_t>(p)] = a;
      a += P.hdr[static_cast<std::size_t>(p)].degree;
    }
  return P;
}

// The headers to the owners: each owner's nodes in index order, their
// degrees (the lists' offsets) and their indices by global id. Sets L.owned,
// L.by_gid, L.cnt; `seg[r]`: the first owned index of the rows block r sends.
template <class Id>
void receive_headers(MPI_Comm comm, RowPlan& P, OwnedLists<Id>& L, std::vector<std::int64_t>& seg) {
  const int size = comm_size(comm);
  std::vector<int> hcount(size), rrows;
  for (int o = 0; o < size; ++o) hcount[o] = static_cast<int>(P.rows_to[o]);
  const std::vector<RowHeader> got = exchange_packed(comm, std::move(P.hdr), hcount, &rrows);
  if (got.size() > static_cast<std::size_t>(std::numeric_limits<LocalId>::max()))
    throw Error("too many sensors on one rank for 32-bit local ids; use more ranks");
  L.owned.resize(got.size());
  L.by_gid.resize(got.size());
  L.cnt.assign(got.size() + 1, 0);
  for (std::size_t i = 0; i < got.size(); ++i) {
    L.owned[i] = got[i].g;
    L.by_gid[i] = got[i].by_gid;
    L.cnt[i + 1] = L.cnt[i] + got[i].degree;
  }
  if (L.cnt.back() > INT32_MAX) throw Error("graph build: more than 2^31 entries on one rank; use more ranks");
  seg.assign(static_cast<std::size_t>(size) + 1, 0);
  for (int r = 0; r < size; ++r) seg[r + 1] = seg[r] + rrows[r];
}

// The entries leaving for other owners go in rounds: round c carries entries
// [c * per_owner, (c + 1) * per_owner) of every owner's part, so that the
// send and receive buffers stay small (64 MiB of entries per rank) beside the
// rows and the lists (a send buffer of all leaving entries was the build's
// high-water mark). per_owner and count are the same on every rank.
struct Rounds {
  std::int64_t per_owner = 1;
  int count = 0;
  std::int64_t piece(std::int64_t total, int c) const {  // entries of a part of `total` in round c
    return std::clamp<std::int64_t>(total - c * per_owner, 0, per_owner);
  }
  // A round's entries at most, parts of `total` (per rank; not this rank's own).
  std::int64_t largest(const std::vector<std::int64_t>& total, int rank) const {
    std::int64_t sum = 0;
    for (std::size_t r = 0; r < total.size(); ++r)
      if (static_cast<int>(r) != rank) sum += std::min(total[r], per_owner);
    return sum;
  }
};

Rounds plan_rounds(MPI_Comm comm, const RowPlan& P, std::size_t entry_bytes) {
  std::int64_t round_bytes = std::int64_t(64) << 20;
  if (const char* e = std::getenv("SNL_TEST_SETUP_ROUND_BYTES")) round_bytes = std::max(1LL, std::atoll(e));  // tests
  const int size = comm_size(comm), rank = comm_rank(comm);
  long long k = std::max<long long>(1, round_bytes / static_cast<long long>(entry_bytes * std::max(1, size - 1)));
  MPI_Allreduce(MPI_IN_PLACE, &k, 1, MPI_LONG_LONG, MPI_MIN, comm);
  long long most = 0;
  for (int o = 0; o < size; ++o)
    if (o != rank) most = std::max<long long>(most, (P.ents_to[o] + k - 1) / k);
  MPI_Allreduce(MPI_IN_PLACE, &most, 1, MPI_LONG_LONG, MPI_MAX, comm);
  if (most > INT32_MAX) throw Error("graph build: too many rounds");
  return Rounds{k, static_cast<int>(most)};
}

// Calls f(t, j0, j1) for the pieces of block rows (row t's entries j0 .. j1)
// that make up entries [k0, k1) of an owner's part, in pack order; `p`, a
// pack position in that part, moves on with them (a piece may end mid-row).
// The rows are read at random: their offsets and their data (at data(t))
// are fetched ahead.
template <class D, class F>
void for_each_piece(const RowPlan& P, const BlockRows& R, std::int64_t k0, std::int64_t k1, std::int64_t& p, D&& data,
                    F&& f) {
  constexpr std::int64_t kOffsetsAhead = 16, kDataAhead = 8;
  const auto np = static_cast<std::int64_t>(P.row.size());
  while (k0 < k1) {
    if (p + kOffsetsAhead < np) __builtin_prefetch(&R.offsets[P.row[static_cast<std::size_t>(p + kOffsetsAhead)]]);
    if (p + kDataAhead < np) __builtin_prefetch(data(P.row[static_cast<std::size_t>(p + kDataAhead)]));
    const std::int64_t t = P.row[static_cast<std::size_t>(p)], b = P.within[static_cast<std::size_t>(p)];
    const std::int64_t deg = R.offsets[t + 1] - R.offsets[t], j1 = std::min(deg, k1 - b);
    if (j1 > k0 - b) f(t, k0 - b, j1);
    k0 = b + j1;
    if (j1 == deg) ++p;
  }
}

// Entries [k0, k1) of owner o's part with their neighbours' slots, to `dst`:
// by chunks, the ids gathered from their rows, then the slots looked up in
// one stream (fetched ahead). Returns the entries whose ends have different
// owners.
template <class Id>
std::int64_t pack_part(const RowPlan& P, const BlockRows& R, const std::vector<Id>& nbr, NeighbourSlots<Id>& slots,
                       int o, std::int64_t k0, std::int64_t k1, std::int64_t& p, Entry<Id>* dst) {
  constexpr std::int64_t kAhead = 32, kChunk = 1 << 15;  // lookups in flight; entries per chunk (in cache)
  auto ids_at = [&](std::int64_t t) { return nbr.data() + R.offsets[t]; };
  std::int64_t cut = 0;
  for (std::int64_t a = k0; a < k1; a += kChunk) {
    const std::int64_t b = std::min(k1, a + kChunk);
    Entry<Id>* e = dst + (a - k0);
    Entry<Id>* w = e;
    for_each_piece(P, R, a, b, p, ids_at, [&](std::int64_t t, std::int64_t j0, std::int64_t j1) {
      for (const Id* src = nbr.data() + R.offsets[t]; j0 < j1; ++j0) (w++)->nbr = src[j0];
    });
    for (std::int64_t k = 0; k < b - a; ++k) {
      if (k + kAhead < b - a) __builtin_prefetch(slots.address(static_cast<GlobalId>(e[k + kAhead].nbr)));
      const auto& s = slots.at(static_cast<GlobalId>(e[k].nbr));
      e[k].owner = s.owner;
      e[k].index = s.index;
      cut += s.owner != o;
    }
  }
  return cut;
}

// The order in which pack_part reads the parts: this rank's own whole, then
// round by round each other owner's piece; f(o, k0, k1, p).
template <class F>
void for_each_part_piece(const RowPlan& P, const Rounds& rd, int rank, std::vector<std::int64_t>& p, F&& f) {
  const int size = static_cast<int>(P.ents_to.size());
  f(rank, std::int64_t(0), P.ents_to[rank], p[rank]);
  for (int c = 0; c < rd.count; ++c)
    for (int o = 0; o < size; ++o)
      if (o != rank) f(o, c * rd.per_owner, c * rd.per_owner + rd.piece(P.ents_to[o], c), p[o]);
}

// The ids whose slots are asked of sparse blocks, in the order pack_part
// looks them up (NeighbourSlots hands the answers out in that order).
template <class Id>
void ask_slots(MPI_Comm comm, const RowPlan& P, const Rounds& rd, const BlockRows& R, const std::vector<Id>& nbr,
               NeighbourSlots<Id>& slots) {
  std::vector<std::vector<Id>> ask(static_cast<std::size_t>(comm_size(comm)));
  if (slots.asks()) {
    std::vector<std::int64_t> p(P.first.begin(), P.first.end() - 1);
    for_each_part_piece(P, rd, comm_rank(comm), p, [&](int, std::int64_t k0, std::int64_t k1, std::int64_t& q) {
      auto ids_at = [&](std::int64_t t) { return nbr.data() + R.offsets[t]; };
      for_each_piece(P, R, k0, k1, q, ids_at, [&](std::int64_t t, std::int64_t j0, std::int64_t j1) {
        for (const Id* src = nbr.data() + R.offsets[t]; j0 < j1; ++j0)
          if (int r = 0; slots.asked(static_cast<GlobalId>(src[j0]), r)) ask[r].push_back(src[j0]);
      });
    });
  }
  slots.exchange(comm, ask);
}

// Per rank: `count` items of a round and where they begin (items of `width`
// per entry, all below 2^31: receive_headers, plan_rounds).
struct RoundCounts {
  std::vector<int> scount, sdisp, rcount, rdisp;
  explicit RoundCounts(int size) : scount(size), sdisp(size), rcount(size), rdisp(size) {}
};

// Step 1: every block row to the owner of its node, with its neighbours'
// directory slots (the values follow once the CSR is laid out:
// values_to_csr). Each block's rows arrive in the owner's index order, so a
// sender's part lands where its index range begins in the owner's lists
// (`seg`); a rank's own part is written there, not sent to itself; the
// others go in rounds (Rounds). Neighbours stay in global-id order. `cut`:
// this rank's entries whose ends have different owners
// (each cut edge is counted by both of its rows).
template <class Id>
OwnedLists<Id> rows_to_owners(MPI_Comm comm, const OwnerDirectory& dir, const BlockRows& R, std::vector<Id>& nbr,
                              RowPlan& P, std::vector<std::int64_t>& seg, Rounds& rd, GlobalId& cut,
                              PhaseClock& clock) {
  const int size = comm_size(comm), rank = comm_rank(comm);
  OwnedLists<Id> L;
  L.rank = rank;
  P = plan_rows(dir, R, size);
  receive_headers(comm, P, L, seg);
  rd = plan_rounds(comm, P, sizeof(Entry<Id>));
  NeighbourSlots<Id> slots(comm, dir, nbr);
  ask_slots(comm, P, rd, R, nbr, slots);
  clock.done("slots");
  L.entries.resize(static_cast<std::size_t>(L.cnt.back()));
  std::vector<Entry<Id>> sbuf(static_cast<std::size_t>(rd.largest(P.ents_to, rank)));
  std::vector<std::int64_t> p(P.first.begin(), P.first.end() - 1);
  cut = pack_part(P, R, nbr, slots, rank, 0, P.ents_to[rank], p[rank], L.entries.data() + L.cnt[seg[rank]]);
  MPI_Datatype rec;
  MPI_Type_contiguous(static_cast<int>(sizeof(Entry<Id>)), MPI_BYTE, &rec);
  MPI_Type_commit(&rec);
  RoundCounts n(size);
  for (int c = 0; c < rd.count; ++c) {
    for (int r = 0, s = 0; r < size; ++r) {
      n.scount[r] = r == rank ? 0 : static_cast<int>(rd.piece(P.ents_to[r], c));
      n.sdisp[r] = s;
      s += n.scount[r];
      n.rcount[r] = r == rank ? 0 : static_cast<int>(rd.piece(L.cnt[seg[r + 1]] - L.cnt[seg[r]], c));
      n.rdisp[r] = n.rcount[r] > 0 ? static_cast<int>(L.cnt[seg[r]] + c * rd.per_owner) : 0;
      if (r != rank)
        cut += pack_part(P, R, nbr, slots, r, c * rd.per_owner, c * rd.per_owner + n.scount[r], p[r],
                         sbuf.data() + n.sdisp[r]);
    }
    MPI_Alltoallv(sbuf.data(), n.scount.data(), n.sdisp.data(), rec, L.entries.data(), n.rcount.data(),
                  n.rdisp.data(), rec, comm);
  }
  MPI_Type_free(&rec);
  L.peak_bytes = R.memory_bytes() + static_cast<std::int64_t>(nbr.capacity() * sizeof(Id)) + slots.memory_bytes() +
                 static_cast<std::int64_t>(P.row.size() * 12 + (sbuf.size() + L.entries.size()) * sizeof(Entry<Id>) +
                                           (L.cnt.size() + L.owned.size()) * 8 + L.by_gid.size() * 4);
  release(sbuf);
  clock.done("exchange");
  L.boundary.assign(L.owned.size(), 0);
  for (std::size_t v = 0; v < L.owned.size(); ++v)
    for (auto k = L.cnt[v]; k < L.cnt[v + 1]; ++k)
      if (L.entries[k].owner != rank) {
        L.boundary[v] = 1;
        break;
      }
  return L;
}

// Step 6: the rows' values (`width` per entry) to the owners, straight into
// the CSR's edge values (`values`, laid out: fill_csr): in the same rounds
// and pack order as the entries, each received piece copied to its rows'
// places (row i of the lists is local row owned_to_local[i], in the same
// neighbour order). Where the values waited in the lists beside their
// entries (8 bytes per entry), the CSR was filled from them.
void values_to_csr(MPI_Comm comm, const RowPlan& P, const Rounds& rd, const BlockRows& R,
                   const std::vector<std::int64_t>& cnt, const std::vector<std::int64_t>& seg,
                   const std::vector<LocalId>& owned_to_local, const std::vector<std::int64_t>& offsets,
                   std::vector<double>& values, std::int64_t& peak) {
  const int size = comm_size(comm), rank = comm_rank(comm), width = R.width;
  values.resize(static_cast<std::size_t>(cnt.back()) * static_cast<std::size_t>(width));
  if (width == 0) return;
  const auto w = static_cast<std::size_t>(width);
  // Row i of the lists at its place in the CSR; its offsets are read at
  // random, so they and the place are fetched ahead.
  constexpr std::int64_t kOffsetsAhead = 16, kPlaceAhead = 8;
  const auto n_owned = static_cast<std::int64_t>(owned_to_local.size());
  auto place = [&](std::int64_t i) {
    if (i + kOffsetsAhead < n_owned) __builtin_prefetch(&offsets[owned_to_local[i + kOffsetsAhead]]);
    if (i + kPlaceAhead < n_owned)
      __builtin_prefetch(values.data() + offsets[owned_to_local[i + kPlaceAhead]] * width, 1);
    return values.data() + offsets[owned_to_local[i]] * width;
  };
  auto values_at = [&](std::int64_t t) { return R.values.data() + R.offsets[t] * width; };
  const std::int64_t own_end = P.first[rank + 1];
  for (std::int64_t p = P.first[rank], i = seg[rank]; p < own_end; ++p, ++i) {  // this rank's own rows
    if (p + kOffsetsAhead < own_end) __builtin_prefetch(&R.offsets[P.row[static_cast<std::size_t>(p + kOffsetsAhead)]]);
    if (p + kPlaceAhead < own_end) __builtin_prefetch(values_at(P.row[static_cast<std::size_t>(p + kPlaceAhead)]));
    const std::int64_t t = P.row[static_cast<std::size_t>(p)];
    std::copy(values_at(t), values_at(t + 1), place(i));
  }
  std::vector<std::int64_t> from(static_cast<std::size_t>(size));  // entries from each sender
  for (int r = 0; r < size; ++r) from[r] = cnt[seg[r + 1]] - cnt[seg[r]];
  std::vector<double> sv(static_cast<std::size_t>(rd.largest(P.ents_to, rank)) * w),
      rv(static_cast<std::size_t>(rd.largest(from, rank)) * w);
  peak = std::max<std::int64_t>(peak, R.memory_bytes() + static_cast<std::int64_t>(
                                          P.row.size() * 12 + (sv.size() + rv.size()) * 8 +
                                          owned_to_local.size() * 4 + cnt.size() * 8));
  std::vector<std::int64_t> p(P.first.begin(), P.first.end() - 1), at(seg.begin(), seg.end() - 1);
  RoundCounts n(size);
  for (int c = 0; c < rd.count; ++c) {
    for (int r = 0, s = 0, q = 0; r < size; ++r) {
      const std::int64_t k0 = c * rd.per_owner, sent = r == rank ? 0 : rd.piece(P.ents_to[r], c);
      n.scount[r] = static_cast<int>(sent * width);
      n.sdisp[r] = s;
      n.rcount[r] = r == rank ? 0 : static_cast<int>(rd.piece(from[r], c) * width);
      n.rdisp[r] = q;
      double* dst = sv.data() + s;
      for_each_piece(P, R, k0, k0 + sent, p[r], values_at, [&](std::int64_t t, std::int64_t j0, std::int64_t j1) {
        dst = std::copy(R.values.data() + (R.offsets[t] + j0) * width, R.values.data() + (R.offsets[t] + j1) * width,
                        dst);
      });
      s += n.scount[r];
      q += n.rcount[r];
    }
    MPI_Alltoallv(sv.data(), n.scount.data(), n.sdisp.data(), MPI_DOUBLE, rv.data(), n.rcount.data(),
                  n.rdisp.data(), MPI_DOUBLE, comm);
    for (int r = 0; r < size; ++r) {  // sender r's piece: its entries k .. end of the lists, row by row
      std::int64_t k = cnt[seg[r]] + c * rd.per_owner;
      const std::int64_t end = k + n.rcount[r] / width;
      const double* src = rv.data() + n.rdisp[r];
      for (std::int64_t& i = at[r]; k < end;) {
        const std::int64_t e = std::min(end, cnt[i + 1]);
        std::copy(src, src + (e - k) * width, place(i) + (k - cnt[i]) * width);
        src += (e - k) * width;
        k = e;
        if (k == cnt[i + 1]) ++i;
      }
    }
  }
}

// RCM order of the two groups of owned indices (group[0] interior, group[1]
// boundary), each then sorted by degree within windows.
template <class Id>
void rcm_groups(const OwnedLists<Id>& L, std::vector<std::int64_t> (&group)[2], std::vector<std::int32_t>& spare) {
  // Owned-index adjacency (-1 for ghosts) and group positions for the BFS.
  auto nbr = [&L](std::int64_t k) -> std::int64_t { return L.nbr_owner(k) == L.rank ? L.nbr_index(k) : -1; };
  std::vector<std::int32_t> pos(L.owned.size(), -1);  // 32-bit: n_owned < 2^31 (receive_headers)
  std::vector<std::int64_t> seeds, ties;
  ties.reserve(L.owned.size());  // (grown by doubling, its blocks split the heap's free blocks; also below)
  for (int gi : {1, 0}) {  // the boundary first: its order seeds the interior's
    auto& grp = group[gi];
    for (std::size_t t = 0; t < grp.size(); ++t) pos[grp[t]] = static_cast<std::int32_t>(t);
    ties.clear();
    for (const std::int32_t v : L.by_gid)
      if (pos[v] >= 0) ties.push_back(pos[v]);
    if (gi == 0)  // interior nodes next to the boundary, in the boundary's order
      for (auto b : group[1])
        for (auto k = L.cnt[b]; k < L.cnt[b + 1]; ++k)
          if (const std::int64_t u = nbr(k); u >= 0 && !L.boundary[u]) seeds.push_back(pos[u]);
    grp = rcm_order(grp, L.cnt, nbr, pos, seeds, ties, spare);
    for (auto v : grp) pos[v] = -1;
    sort_degree_windows(grp, L.cnt);
  }
}

// Step 3: owned indices in local order: interior, then boundary, each group
// in RCM (from owner-side index order: the bfs partition's bands keep its
// scans near in memory) or global id order. Sets n_interior. `spare`: a
// buffer for RCM's group adjacency (rcm_order).
template <class Id>
std::vector<std::int64_t> local_order(const OwnedLists<Id>& L, LocalOrdering ordering, LocalId& n_interior,
                                      std::vector<std::int32_t>& spare) {
  std::vector<std::int64_t> group[2];
  const bool rcm = ordering == LocalOrdering::kRcm;
  const auto n_boundary = static_cast<std::size_t>(std::count(L.boundary.begin(), L.boundary.end(), 1));
  group[0].reserve(L.owned.size() - n_boundary);
  group[1].reserve(n_boundary);
  for (std::size_t t = 0; t < L.owned.size(); ++t) {
    const std::int64_t v = rcm ? static_cast<std::int64_t>(t) : L.by_gid[t];
    group[L.boundary[v] ? 1 : 0].push_back(v);
  }
  if (rcm) rcm_groups(L, group, spare);
  n_interior = static_cast<LocalId>(group[0].size());
  std::vector<std::int64_t> order;
  order.reserve(L.owned.size());
  order.insert(order.end(), group[0].begin(), group[0].end());
  order.insert(order.end(), group[1].begin(), group[1].end());
  return order;
}

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
