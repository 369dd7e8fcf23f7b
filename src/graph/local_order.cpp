// Step 3 of DistGraph's build: the local order of the owned nodes, interior
// then boundary, each group in reverse Cuthill-McKee order (seeded at the
// boundary) and sorted by degree within windows of SIMD chunks.
#include <algorithm>
#include <cstdint>
#include <vector>

#include "graph/graph_build.hpp"

namespace snl::graph_build {

namespace {

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

}  // namespace

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

template std::vector<std::int64_t> local_order(const OwnedLists<std::int32_t>&, LocalOrdering, LocalId&,
                                               std::vector<std::int32_t>&);
template std::vector<std::int64_t> local_order(const OwnedLists<std::int64_t>&, LocalOrdering, LocalId&,
                                               std::vector<std::int32_t>&);

}  // namespace snl::graph_build
