#include "snl/graph/dist_graph.hpp"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <numeric>

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

std::size_t edge_capacity(std::size_t n) { return n + n / 16 + 1024; }

LocalOrdering default_local_ordering() {
  const char* e = std::getenv("SNL_LOCAL_ORDER");
  return (e && std::strcmp(e, "gid") == 0) ? LocalOrdering::kGlobalId : LocalOrdering::kRcm;
}

bool setup_wide_ids(MPI_Comm comm, GlobalId n) {
  const char* e = std::getenv("SNL_SETUP_IDS");
  int mine = (e && std::strcmp(e, "64") == 0) ? 1 : 0, any = 0;
  MPI_Allreduce(&mine, &any, 1, MPI_INT, MPI_MAX, comm);
  return n > std::numeric_limits<std::int32_t>::max() || any != 0;
}

namespace {
// Copies one edge's `width` values. std::copy with a run-time count became a
// call to memmove per edge (80M calls per rank at 10M sensors in the lists
// alone); the usual one or two values are copied inline.
inline void copy_values(const double* src, double* dst, int width) {
  if (width == 1) {
    dst[0] = src[0];
  } else if (width == 2) {
    dst[0] = src[0];
    dst[1] = src[1];
  } else if (width > 2) {  // (none: memcpy's pointers may not be null, and a graph without values has none)
    std::memcpy(dst, src, sizeof(double) * static_cast<std::size_t>(width));
  }
}

// An edge with the owner and owner-side index of both ends (OwnerDirectory::Slot).
// Id: the node ids' type, 32-bit below 2^31 nodes (DistGraph::build).
template <class Id>
struct EdgeRec {
  Id a, b;
  std::int32_t oa, ia, ob, ib;
};
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
// SELL-C-sigma, Kreutzer et al. 2014). Windows of 32 keep RCM's locality:
// 10M on 2 ranks, relaxation 36.7-37.7 vs 42.7-43.9 ms/iteration without the
// sort, MM 62.8-64.4 vs 71.4-77.3 (docs/performance.md).
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
// once here instead of in each of the two BFS sweeps of rcm_order.
struct GroupGraph {
  std::vector<std::int64_t> off;
  std::vector<std::int32_t> adj, deg;
};

template <class Nbr>
GroupGraph group_graph(const std::vector<std::int64_t>& nodes, const std::vector<std::int64_t>& cnt, Nbr&& nbr,
                       const std::vector<std::int32_t>& pos) {
  const std::size_t m = nodes.size();
  GroupGraph g;
  g.off.assign(m + 1, 0);
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
                                    const std::vector<std::int64_t>& seeds, const std::vector<std::int64_t>& ties) {
  const GroupGraph g = group_graph(nodes, cnt, nbr, pos);
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

// Moves records (with `width` values each) to the rank dest(k) returns for
// record k, and also to also(k) where that is another rank (-1: none);
// returns in `got` what this rank keeps (k order) and then what it received
// (rank order, then k order), values alongside. Consumes recs and vals. The
// records that stay on this rank are not copied out and back: they are
// moved to the head of recs in place, whose storage becomes `got`; only the
// others are packed into a send buffer in rank order (at 10M on 2 ranks half
// of the records, where all of them went through the send buffer and
// MPI's copy to self before). dest and also are called twice per record
// (count, then pack): they must be cheap.
template <class Rec, class Dest, class Also>
void send_records(MPI_Comm comm, std::vector<Rec>&& recs, std::vector<double>&& vals, int width, Dest&& dest,
                  Also&& also, std::vector<Rec>& got, std::vector<double>& got_vals) {
  const int size = comm_size(comm), rank = comm_rank(comm);
  const auto w = static_cast<std::size_t>(width);
  std::vector<std::int64_t> start(static_cast<std::size_t>(size) + 1, 0);
  for (std::size_t k = 0; k < recs.size(); ++k) {
    const int r = dest(k), r2 = also(k);
    if (r != rank) ++start[r + 1];
    if (r2 >= 0 && r2 != r && r2 != rank) ++start[r2 + 1];
  }
  std::vector<int> scount, vcount(size);
  pack_offsets(start, scount, width, "edge exchange");
  for (int r = 0; r < size; ++r) vcount[r] = scount[r] * width;
  std::vector<Rec> sbuf(static_cast<std::size_t>(start[size]));
  std::vector<double> svals(sbuf.size() * w);
  auto put = [&](int r, std::size_t k) {
    const auto pos = start[r]++;
    sbuf[pos] = recs[k];
    copy_values(vals.data() + k * w, svals.data() + pos * w, width);
  };
  std::size_t kept = 0;  // records [0, kept) stay here; kept <= k, so record k is read before it is overwritten
  for (std::size_t k = 0; k < recs.size(); ++k) {
    const int r = dest(k), r2 = also(k);
    if (r != rank) put(r, k);
    if (r2 >= 0 && r2 != r && r2 != rank) put(r2, k);
    if (r != rank && r2 != rank) continue;
    if (kept != k) {
      recs[kept] = recs[k];
      copy_values(vals.data() + k * w, vals.data() + kept * w, width);
    }
    ++kept;
  }
  got = std::move(recs);
  got_vals = std::move(vals);
  exchange_packed_into(comm, sbuf, scount, got, kept);
  release(sbuf);
  exchange_packed_into(comm, svals, vcount, got_vals, kept * w);
}

// Tags each record's b with its directory slot (ob, ib): looked up here when
// b is in this rank's block, else asked of its block holder (the ids out and
// the slots back, 8 + sizeof(Id) bytes per edge, where moving the records to
// the block holder and on from there moved the whole records with their
// values and allocated a second copy of them). Collective.
template <class Id>
void tag_b(MPI_Comm comm, const OwnerDirectory& dir, std::vector<EdgeRec<Id>>& recs) {
  const int size = comm_size(comm);
  const detail::Blocks blocks(dir.num_global(), size);
  auto mine = [&](GlobalId g) { return g >= dir.block_begin() && g < dir.block_end(); };
  std::vector<std::int64_t> start(static_cast<std::size_t>(size) + 1, 0);
  for (const auto& e : recs)
    if (!mine(e.b)) ++start[blocks.of(e.b) + 1];
  std::vector<int> scount;
  pack_offsets(start, scount, 1, "directory lookup");
  std::vector<std::int64_t> first(start.begin(), start.end() - 1);
  std::vector<Id> ask(static_cast<std::size_t>(start[size]));
  constexpr std::size_t kAhead = 16;  // directory lookups in flight (OwnerDirectory::prefetch)
  for (std::size_t k = 0; k < recs.size(); ++k) {
    if (k + kAhead < recs.size() && mine(recs[k + kAhead].b)) dir.prefetch(recs[k + kAhead].b);
    auto& e = recs[k];
    if (!mine(e.b)) {
      ask[start[blocks.of(e.b)]++] = e.b;
      continue;
    }
    const auto& s = dir.local(e.b);
    e.ob = s.owner;
    e.ib = s.index;
  }
  // The questions to their block holders, the answers back in the same order.
  std::vector<int> rcount(size), sdisp(size), rdisp(size);
  MPI_Alltoall(scount.data(), 1, MPI_INT, rcount.data(), 1, MPI_INT, comm);
  std::int64_t rtot = 0;
  for (int r = 0; r < size; ++r) {
    sdisp[r] = static_cast<int>(first[r]);
    rdisp[r] = static_cast<int>(rtot);
    rtot += rcount[r];
  }
  int ok = rtot <= INT32_MAX && start[size] <= INT32_MAX, all_ok = 0;
  MPI_Allreduce(&ok, &all_ok, 1, MPI_INT, MPI_MIN, comm);
  if (!all_ok) throw Error("directory lookup: more than 2^31 ids on one rank; use more ranks");
  std::vector<Id> asked(static_cast<std::size_t>(rtot));
  const MPI_Datatype id_type = sizeof(Id) == 4 ? MPI_INT32_T : MPI_INT64_T;
  MPI_Alltoallv(ask.data(), scount.data(), sdisp.data(), id_type, asked.data(), rcount.data(), rdisp.data(), id_type,
                comm);
  release(ask);
  std::vector<OwnerDirectory::Slot> answer(asked.size());
  for (std::size_t k = 0; k < asked.size(); ++k) {
    if (k + kAhead < asked.size()) dir.prefetch(asked[k + kAhead]);
    answer[k] = dir.local(asked[k]);
  }
  release(asked);
  std::vector<OwnerDirectory::Slot> got(static_cast<std::size_t>(start[size]));
  MPI_Datatype slot_type;
  MPI_Type_contiguous(2, MPI_INT32_T, &slot_type);
  MPI_Type_commit(&slot_type);
  MPI_Alltoallv(answer.data(), rcount.data(), rdisp.data(), slot_type, got.data(), scount.data(), sdisp.data(),
                slot_type, comm);
  MPI_Type_free(&slot_type);
  release(answer);
  for (auto& e : recs)
    if (!mine(e.b)) {
      const auto& s = got[first[blocks.of(e.b)]++];
      e.ob = s.owner;
      e.ib = s.index;
    }
}

// Step 1: every edge goes to the owners of both ends (once if they
// coincide), with its `width` values and both ends' directory slots. None of
// it needs anything of size n: the records go to the block holder of a
// (skipped when every rank holds only edges with an end in its block, as
// the problem's merged measurements are; that end is then a), which tags a's
// owner, asks the block holder of b for b's (tag_b), counts the cut and
// sends them to the owners. Edges are undirected: a and b may swap. Returns
// the local edge cut. Consumes edges and edge_values (freed once the first
// records are built).
template <class Id>
GlobalId route_edges(MPI_Comm comm, const OwnerDirectory& dir, std::vector<GlobalId>&& edges,
                     std::vector<double>&& edge_values, int width, std::vector<EdgeRec<Id>>& mine,
                     std::vector<double>& mine_vals) {
  const detail::Blocks blocks(dir.num_global(), comm_size(comm));
  auto none = [](std::size_t) { return -1; };
  std::vector<EdgeRec<Id>> recs;
  std::vector<double> vals;
  {
    int local = 1, all = 0;
    auto in_block = [&](GlobalId g) { return g >= dir.block_begin() && g < dir.block_end(); };
    for (std::size_t k = 0; k < edges.size() && local; k += 2) local = in_block(edges[k]) || in_block(edges[k + 1]);
    MPI_Allreduce(&local, &all, 1, MPI_INT, MPI_MIN, comm);
    std::vector<EdgeRec<Id>> pairs;
    pairs.reserve(edge_capacity(edges.size() / 2));  // send_records receives after the records it keeps
    pairs.resize(edges.size() / 2);
    std::vector<double> pair_vals = std::move(edge_values);
    for (std::size_t e = 0; e < pairs.size(); ++e) {
      const bool swap = all && !in_block(edges[2 * e]);
      pairs[e] = {static_cast<Id>(edges[2 * e + (swap ? 1 : 0)]), static_cast<Id>(edges[2 * e + (swap ? 0 : 1)]),
                  -1, -1, -1, -1};
    }
    release(edges);
    if (all) {
      recs = std::move(pairs);
      vals = std::move(pair_vals);
    } else {
      send_records(comm, std::move(pairs), std::move(pair_vals), width,
                   [&](std::size_t k) { return blocks.of(pairs[k].a); }, none, recs, vals);
    }
  }
  constexpr std::size_t kAhead = 16;  // directory lookups in flight (OwnerDirectory::prefetch)
  for (std::size_t k = 0; k < recs.size(); ++k) {
    if (k + kAhead < recs.size()) dir.prefetch(recs[k + kAhead].a);
    const auto& s = dir.local(recs[k].a);
    recs[k].oa = s.owner;
    recs[k].ia = s.index;
  }
  tag_b(comm, dir, recs);
  GlobalId cut = 0;
  for (const auto& e : recs) cut += e.oa != e.ob;
  send_records(comm, std::move(recs), std::move(vals), width, [&](std::size_t k) { return recs[k].oa; },
               [&](std::size_t k) { return recs[k].ob; }, mine, mine_vals);
  return cut;
}

// The owned nodes and their neighbour lists, indexed by position in `owned`
// (the directory's owner-side index), before the local numbering.
template <class Id>
struct OwnedLists {
  std::vector<GlobalId> owned;    // owned nodes in owner-side index order
  std::vector<std::int32_t> by_gid;  // their owner-side indices in ascending global id
  std::vector<std::int64_t> cnt;  // owned index v: entries [cnt[v], cnt[v + 1])
  std::vector<Entry<Id>> entries;  // per node sorted by neighbour global id
  std::vector<double> vals;       // `width` values per entry
  std::vector<char> boundary;     // owned index v has a neighbour on another rank
  int rank = 0, width = 0;
  std::int64_t peak_bytes = 0;    // the step's temporaries at their largest
  std::int32_t nbr_owner(std::int64_t k) const { return entries[k].owner; }
  std::int32_t nbr_index(std::int64_t k) const { return entries[k].index; }
};

// Sorts node v's entries [b, e) (and their values) by neighbour global id:
// insertion sort for the usual few, an index sort for hubs.
template <class Id>
void sort_by_neighbour(OwnedLists<Id>& L, std::int64_t b, std::int64_t e, std::vector<double>& tmp,
                       std::vector<std::int64_t>& perm) {
  const int w = L.width;
  Entry<Id>* ent = L.entries.data();
  double* val = L.vals.data();
  if (e - b <= 32) {
    for (std::int64_t i = b + 1; i < e; ++i) {
      if (!(ent[i].nbr < ent[i - 1].nbr)) continue;
      const Entry<Id> x = ent[i];
      copy_values(val + i * w, tmp.data(), w);
      std::int64_t j = i;
      for (; j > b && x.nbr < ent[j - 1].nbr; --j) {
        ent[j] = ent[j - 1];
        copy_values(val + (j - 1) * w, val + j * w, w);
      }
      ent[j] = x;
      copy_values(tmp.data(), val + j * w, w);
    }
    return;
  }
  perm.resize(static_cast<std::size_t>(e - b));
  std::iota(perm.begin(), perm.end(), b);
  std::sort(perm.begin(), perm.end(), [&](std::int64_t x, std::int64_t y) { return ent[x].nbr < ent[y].nbr; });
  std::vector<Entry<Id>> se(perm.size());
  std::vector<double> sv(perm.size() * w);
  for (std::size_t t = 0; t < perm.size(); ++t) {
    se[t] = ent[perm[t]];
    copy_values(val + perm[t] * w, sv.data() + t * w, w);
  }
  std::copy(se.begin(), se.end(), ent + b);
  std::copy(sv.begin(), sv.end(), val + b * w);
}

// Step 2: the owned nodes in owner-side index order, then per-node neighbour lists
// sorted by global id (the fixed summation order) from the received edges,
// which it consumes. A two-level bucket sort by owner-side index: one
// streaming pass scatters the half-edges into at most kBuckets buckets of
// consecutive owned indices (few write streams), the edge records are freed,
// then each bucket is copied out (it fits in cache) and counting-sorted back
// in place. Every later pass reads the lists in order, with each neighbour's
// directory slot and values at hand: none goes back to the edge records at
// random (at 10M on 2 ranks that indirection made the build latency-bound).
template <class Id>
OwnedLists<Id> neighbour_lists(const OwnerDirectory& dir, int rank, std::vector<EdgeRec<Id>>&& mine,
                           std::vector<double>&& mine_vals, int width) {
  constexpr std::int64_t kBuckets = 4096;
  OwnedLists<Id> L;
  L.rank = rank;
  L.width = width;
  const auto n_owned = static_cast<std::int64_t>(dir.counts()[static_cast<std::size_t>(rank)]);
  if (n_owned > static_cast<std::int64_t>(std::numeric_limits<LocalId>::max()))
    throw Error("too many sensors on one rank for 32-bit local ids; use more ranks");
  int shift = 0;
  while ((n_owned >> shift) >= kBuckets) ++shift;
  const std::int64_t nb = (n_owned >> shift) + 1;
  std::vector<std::int64_t> bstart(static_cast<std::size_t>(nb) + 1, 0);
  for (const auto& r : mine) {
    if (r.oa == rank) ++bstart[(r.ia >> shift) + 1];
    if (r.ob == rank) ++bstart[(r.ib >> shift) + 1];
  }
  for (std::int64_t b = 0; b < nb; ++b) bstart[b + 1] += bstart[b];
  const std::int64_t total = bstart[nb];
  L.entries.resize(static_cast<std::size_t>(total));
  L.vals.resize(static_cast<std::size_t>(total * width));
  std::vector<std::int32_t> key(static_cast<std::size_t>(total));  // the owned end of each half-edge
  {
    std::vector<std::int64_t> fill(bstart.begin(), bstart.end() - 1);
    auto put = [&](std::int32_t v, const Entry<Id>& e, const double* src) {
      const auto p = fill[v >> shift]++;
      L.entries[p] = e;
      key[p] = v;
      copy_values(src, L.vals.data() + p * width, width);
    };
    for (std::size_t t = 0; t < mine.size(); ++t) {
      const auto& r = mine[t];
      const double* src = mine_vals.data() + t * width;
      if (r.oa == rank) put(r.ia, {r.b, r.ob, r.ib}, src);
      if (r.ob == rank) put(r.ib, {r.a, r.oa, r.ia}, src);
    }
  }
  // (The records' size, not their capacity: the room reserved beyond them for
  // the exchange is not touched unless filled.)
  L.peak_bytes = static_cast<std::int64_t>(mine.size() * sizeof(EdgeRec<Id>) + mine_vals.size() * sizeof(double) +
                                           L.entries.capacity() * sizeof(Entry<Id>) + key.capacity() * 4 +
                                           L.vals.capacity() * sizeof(double) + bstart.capacity() * 16);
  release(mine);
  release(mine_vals);
  // The owned nodes only now, in the records' freed memory, not on top of the peak.
  L.owned = dir.owned_nodes(&L.by_gid);
  L.cnt.assign(static_cast<std::size_t>(n_owned) + 1, 0);
  L.boundary.assign(static_cast<std::size_t>(n_owned), 0);
  std::vector<Entry<Id>> b_ent;
  std::vector<std::int32_t> b_key;
  std::vector<double> b_val, tmp(static_cast<std::size_t>(std::max(width, 1)));
  std::vector<std::int64_t> perm, fill;
  for (std::int64_t b = 0; b < nb; ++b) {
    const std::int64_t v0 = b << shift, v1 = std::min(n_owned, (b + 1) << shift);
    const std::int64_t s = bstart[b], e = bstart[b + 1];
    if (v0 >= v1) continue;
    for (auto p = s; p < e; ++p) ++L.cnt[key[p] + 1];
    for (auto v = v0; v < v1; ++v) L.cnt[v + 1] += L.cnt[v];
    b_ent.assign(L.entries.begin() + s, L.entries.begin() + e);
    b_key.assign(key.begin() + s, key.begin() + e);
    b_val.assign(L.vals.begin() + s * width, L.vals.begin() + e * width);
    fill.assign(L.cnt.begin() + v0, L.cnt.begin() + v1);
    for (std::int64_t p = 0; p < e - s; ++p) {
      const auto q = fill[b_key[p] - v0]++;
      L.entries[q] = b_ent[p];
      copy_values(b_val.data() + p * width, L.vals.data() + q * width, width);
    }
    for (auto v = v0; v < v1; ++v) {
      sort_by_neighbour(L, L.cnt[v], L.cnt[v + 1], tmp, perm);
      for (auto k = L.cnt[v]; k < L.cnt[v + 1]; ++k)
        if (L.entries[k].owner != rank) L.boundary[v] = 1;
    }
  }
  return L;
}

// RCM order of the two groups of owned indices (group[0] interior, group[1]
// boundary), each then sorted by degree within windows.
template <class Id>
void rcm_groups(const OwnedLists<Id>& L, std::vector<std::int64_t> (&group)[2]) {
  // Owned-index adjacency (-1 for ghosts) and group positions for the BFS.
  auto nbr = [&L](std::int64_t k) -> std::int64_t { return L.nbr_owner(k) == L.rank ? L.nbr_index(k) : -1; };
  std::vector<std::int32_t> pos(L.owned.size(), -1);  // 32-bit: n_owned < 2^31 (neighbour_lists)
  std::vector<std::int64_t> seeds, ties;
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
    grp = rcm_order(grp, L.cnt, nbr, pos, seeds, ties);
    for (auto v : grp) pos[v] = -1;
    sort_degree_windows(grp, L.cnt);
  }
}

// Step 3: owned indices in local order: interior, then boundary, each group
// in RCM (from owner-side index order: the bfs partition's bands keep its
// scans near in memory) or global id order. Sets n_interior.
template <class Id>
std::vector<std::int64_t> local_order(const OwnedLists<Id>& L, LocalOrdering ordering, LocalId& n_interior) {
  std::vector<std::int64_t> group[2];
  const bool rcm = ordering == LocalOrdering::kRcm;
  for (std::size_t t = 0; t < L.owned.size(); ++t) {
    const std::int64_t v = rcm ? static_cast<std::int64_t>(t) : L.by_gid[t];
    group[L.boundary[v] ? 1 : 0].push_back(v);
  }
  if (rcm) rcm_groups(L, group);
  std::vector<std::int64_t> order = std::move(group[0]);
  n_interior = static_cast<LocalId>(order.size());
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

// Step 5: the CSR in local order, neighbours in global-id order, with the
// edges' values.
template <class Id>
void fill_csr(const OwnedLists<Id>& L, const std::vector<std::int64_t>& order, const LocalIds& ids,
              int rank, int width,
              std::vector<std::int64_t>& offsets, std::vector<LocalId>& adjacency, std::vector<double>& values) {
  const std::size_t n = order.size();
  offsets.assign(n + 1, 0);
  adjacency.resize(L.entries.size());
  values.resize(L.entries.size() * width);
  for (std::size_t l = 0; l < n; ++l) {
    if (l + 16 < n) __builtin_prefetch(&L.cnt[order[l + 16]]);
    offsets[l + 1] = offsets[l] + (L.cnt[order[l] + 1] - L.cnt[order[l]]);
  }
  // The lists are read in their own (global) order and each node's block is
  // written to its place in the local order: reading them in local order
  // instead made order -> cnt -> entries a chain of dependent misses (at 10M
  // on 2 ranks 3.9 s, three loads taking 75% of it). Stores do not wait.
  constexpr std::size_t kAhead = 16, kDestAhead = 8, kIdsAhead = 4;
  for (std::size_t v = 0; v < n; ++v) {
    if (v + kAhead < n) __builtin_prefetch(&offsets[ids.owned_to_local[v + kAhead]]);
    if (v + kDestAhead < n) {  // the block's first lines, for writing: the stores otherwise stall on their misses
      const std::int64_t p = offsets[ids.owned_to_local[v + kDestAhead]];
      __builtin_prefetch(adjacency.data() + p, 1);
      if (width > 0) {  // (no values: data() may be null, and no offset may be added to it)
        __builtin_prefetch(values.data() + p * width, 1);
        __builtin_prefetch(values.data() + p * width + 8, 1);
      }
    }
    if (v + kIdsAhead < n)  // the neighbours' local ids, read at random
      for (auto k = L.cnt[v + kIdsAhead]; k < L.cnt[v + kIdsAhead + 1]; ++k)
        if (L.nbr_owner(k) == rank) __builtin_prefetch(&ids.owned_to_local[L.nbr_index(k)]);
    std::int64_t pos = offsets[ids.owned_to_local[v]];
    for (auto k = L.cnt[v]; k < L.cnt[v + 1]; ++k, ++pos) {
      adjacency[pos] = L.nbr_owner(k) == rank ? ids.owned_to_local[L.nbr_index(k)] : ids.ghost(L.entries[k].nbr);
      copy_values(L.vals.data() + k * width, values.data() + pos * width, width);
    }
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
    : comm_(comm), n_global_(owners.num_global()), width_(width) {
  // Below 2^31 nodes the build's records and lists carry 32-bit ids: at 10M
  // sensors on 2 ranks 8 bytes less per edge record and 4 per list entry
  // (docs/performance.md).
  if (setup_wide_ids(comm_.get(), n_global_))
    build<GlobalId>(owners, std::move(edges), std::move(edge_values), halo_width, ordering);
  else
    build<std::int32_t>(owners, std::move(edges), std::move(edge_values), halo_width, ordering);
}

template <class Id>
void DistGraph::build(const OwnerDirectory& owners, std::vector<GlobalId>&& edges, std::vector<double>&& edge_values,
                      int halo_width, LocalOrdering ordering) {
  const MPI_Comm gc = comm_.get();  // the graph's own duplicate (halo traffic apart from the caller's)
  const int rank = comm_rank(gc), width = width_;
  PhaseClock clock(build_phases_);
  std::vector<EdgeRec<Id>> mine;
  std::vector<double> mine_vals;
  long long cut = route_edges(gc, owners, std::move(edges), std::move(edge_values), width, mine, mine_vals), gcut = 0;
  MPI_Allreduce(&cut, &gcut, 1, MPI_LONG_LONG, MPI_SUM, gc);
  edge_cut_ = gcut;
  clock.done("exchange");
  const OwnedLists<Id> lists = neighbour_lists(owners, rank, std::move(mine), std::move(mine_vals), width);
  clock.done("lists");
  const std::vector<std::int64_t> order = local_order(lists, ordering, n_interior_);
  clock.done("order");
  n_owned_ = static_cast<LocalId>(lists.owned.size());
  const std::vector<Ghost> ghosts = ghost_nodes(lists, rank);
  const LocalIds ids = number_nodes(lists, order, ghosts, local_to_global_, owned_sorted_);
  fill_csr(lists, order, ids, rank, width, offsets_, adjacency_, edge_values_);
  clock.done("csr");
  // The build's temporaries at their largest (edge records, lists, ghosts).
  build_peak_bytes_ = std::max<std::int64_t>(lists.peak_bytes, static_cast<std::int64_t>(
      lists.entries.capacity() * sizeof(Entry<Id>) + lists.vals.capacity() * sizeof(double) +
      (lists.cnt.capacity() + lists.owned.capacity()) * 8 + lists.by_gid.capacity() * 4 +
      ghosts.capacity() * sizeof(Ghost) + ids.ghost_sorted.capacity() * sizeof(ids.ghost_sorted[0]) +
      ids.owned_to_local.capacity() * sizeof(LocalId) + order.capacity() * 8));
  halo_ = make_halo(gc, ghosts, lists, ids, halo_width);
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
