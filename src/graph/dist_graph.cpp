#include "snl/graph/dist_graph.hpp"

#include <metis.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <numeric>

#include "snl/core/mpi_util.hpp"
#include "snl/io/network.hpp"

namespace snl {

PartitionMethod parse_partition_method(const std::string& s) {
  if (s == "metis") return PartitionMethod::kMetis;
  if (s == "block") return PartitionMethod::kBlock;
  throw Error("unknown partition method '" + s + "' (expected metis or block)");
}

namespace {

// METIS k-way on rank 0. Returns "" on success, else why it could not run.
// phase(name) marks the end of a phase (PartitionStats::phases).
template <class Phase>
std::string metis_partition(GlobalId n, const std::vector<GlobalId>& edges, int nparts, std::vector<int>& owner,
                            Phase&& phase) {
  const std::int64_t nnz = static_cast<std::int64_t>(edges.size());  // = 2E directed entries
  static_assert(sizeof(idx_t) == 4 || sizeof(idx_t) == 8, "unexpected METIS idx_t");
  const std::int64_t idx_max = std::numeric_limits<idx_t>::max();
  if (n > idx_max || nnz > idx_max)
    return "graph too large for this METIS build (" + std::to_string(sizeof(idx_t) * 8) + "-bit idx_t)";
  std::vector<idx_t> xadj(static_cast<std::size_t>(n) + 1, 0), adjncy(static_cast<std::size_t>(nnz));
  for (std::size_t e = 0; e < edges.size(); e += 2) {
    ++xadj[edges[e] + 1];
    ++xadj[edges[e + 1] + 1];
  }
  for (GlobalId v = 0; v < n; ++v) xadj[v + 1] += xadj[v];
  {
    std::vector<idx_t> fill(xadj.begin(), xadj.end() - 1);
    for (std::size_t e = 0; e < edges.size(); e += 2) {
      adjncy[fill[edges[e]]++] = static_cast<idx_t>(edges[e + 1]);
      adjncy[fill[edges[e + 1]]++] = static_cast<idx_t>(edges[e]);
    }
  }
  phase("metis_graph");
  idx_t nvtxs = static_cast<idx_t>(n), ncon = 1, np = nparts, objval = 0;
  idx_t options[METIS_NOPTIONS];
  METIS_SetDefaultOptions(options);
  options[METIS_OPTION_SEED] = 1;  // deterministic partitions
  options[METIS_OPTION_NUMBERING] = 0;
  std::vector<idx_t> part(static_cast<std::size_t>(n), 0);
  int status = METIS_ERROR;
  try {
    status = METIS_PartGraphKway(&nvtxs, &ncon, xadj.data(), adjncy.data(), nullptr, nullptr, nullptr, &np, nullptr,
                                 nullptr, options, &objval, part.data());
  } catch (...) {
    status = METIS_ERROR;
  }
  if (status != METIS_OK) return status == METIS_ERROR_MEMORY ? "METIS ran out of memory" : "METIS failed";
  owner.assign(part.begin(), part.end());
  phase("metis");
  return "";
}

}  // namespace

std::vector<int> partition_graph(MPI_Comm comm, GlobalId n, const std::vector<GlobalId>& edges,
                                 PartitionMethod method, PartitionStats* stats) {
  const double t0 = MPI_Wtime();
  double tmark = t0;
  std::vector<std::pair<std::string, double>> phases;
  auto phase = [&](const char* name) {
    const double now = MPI_Wtime();
    phases.emplace_back(name, now - tmark);
    tmark = now;
  };
  const int size = comm_size(comm), rank = comm_rank(comm);
  std::vector<int> owner(static_cast<std::size_t>(n));
  std::string used = "block", note;
  bool done = false;
  if (method == PartitionMethod::kMetis && size > 1) {
    std::vector<GlobalId> all = gather_to_root(comm, edges);
    phase("gather");
    std::string why;
    if (rank == 0) {
      try {
        why = metis_partition(n, all, size, owner, phase);
      } catch (const std::bad_alloc&) {
        why = "out of memory building the METIS graph";
      }
    }
    all.clear();
    all.shrink_to_fit();
    why = bcast_string(comm, why);
    if (why.empty()) {
      bcast_bytes(comm, owner.data(), owner.size() * sizeof(int));
      phase("bcast");
      used = "metis";
      done = true;
    } else {
      note = why + "; used the block partition instead";
    }
  } else if (method == PartitionMethod::kMetis) {
    used = "metis";  // one rank: the trivial partition
  }
  if (!done) {
    for (int r = 0; r < size; ++r) {
      GlobalId b, e;
      block_range(n, size, r, b, e);
      std::fill(owner.begin() + b, owner.begin() + e, r);
    }
  }
  if (stats) {
    stats->method = used;
    stats->note = note;
    long long cut = 0;
    for (std::size_t e = 0; e < edges.size(); e += 2) cut += owner[edges[e]] != owner[edges[e + 1]];
    long long gcut = 0;
    MPI_Allreduce(&cut, &gcut, 1, MPI_LONG_LONG, MPI_SUM, comm);
    stats->edge_cut = gcut;
    std::vector<GlobalId> counts(size, 0);
    for (int o : owner) ++counts[o];
    const double mean = static_cast<double>(n) / size;
    stats->imbalance = mean > 0 ? static_cast<double>(*std::max_element(counts.begin(), counts.end())) / mean : 1.0;
    phase("stats");
    stats->phases = std::move(phases);
    stats->seconds = MPI_Wtime() - t0;
  }
  return owner;
}

LocalOrdering default_local_ordering() {
  const char* e = std::getenv("SNL_LOCAL_ORDER");
  return (e && std::strcmp(e, "gid") == 0) ? LocalOrdering::kGlobalId : LocalOrdering::kRcm;
}

namespace {
struct EdgeRec {
  GlobalId a, b;
};
struct Entry {
  GlobalId nbr;
  std::int64_t src;  // index into the received edge list (for values)
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

// Reverse Cuthill-McKee of the graph (cnt, nbrs) restricted to `nodes` (one
// group: interior or boundary): BFS from a pseudo-peripheral node (George-Liu,
// one sweep), children by increasing degree, then reversed. `pos[v]` is v's
// position in `nodes` or -1 for nodes outside the group. With `seeds`
// (positions in `nodes`), the first BFS starts from all of them at once, as
// its first level: the interior group is seeded with its nodes next to the
// boundary, so that after the reversal the interior runs from the nodes
// farthest from the boundary to those next to it, in layers (temporal
// blocking defers the chunks near the boundary: they are then contiguous).
// Deterministic: ties are broken by the order of `nodes` (global id order).
std::vector<std::int64_t> rcm_order(const std::vector<std::int64_t>& nodes, const std::vector<std::int64_t>& cnt,
                                    const std::vector<std::int64_t>& nbrs, const std::vector<std::int64_t>& pos,
                                    const std::vector<std::int64_t>& seeds) {
  const std::size_t m = nodes.size();
  // The group's own adjacency in group positions (32-bit), neighbours in the
  // same order as in `nbrs`: the scattered nodes -> cnt -> nbrs -> pos lookups
  // are done once here instead of in each of the two BFS sweeps.
  std::vector<std::int64_t> off(m + 1, 0);
  std::vector<std::int32_t> adj;
  {
    std::size_t total = 0;
    for (std::size_t t = 0; t < m; ++t) total += std::size_t(cnt[nodes[t] + 1] - cnt[nodes[t]]);
    adj.reserve(total);
  }
  for (std::size_t t = 0; t < m; ++t) {
    for (auto k = cnt[nodes[t]]; k < cnt[nodes[t] + 1]; ++k)
      if (nbrs[k] >= 0 && pos[nbrs[k]] >= 0) adj.push_back(static_cast<std::int32_t>(pos[nbrs[k]]));
    off[t + 1] = static_cast<std::int64_t>(adj.size());
  }
  std::vector<std::int32_t> deg(m);
  for (std::size_t t = 0; t < m; ++t) deg[t] = static_cast<std::int32_t>(off[t + 1] - off[t]);
  std::vector<std::int64_t> order;  // positions in `nodes`
  order.reserve(m);
  std::vector<char> seen(m, 0);
  std::vector<std::int32_t> level(m, -1);
  std::vector<std::int64_t> kids;
  // One BFS from s over unseen nodes; returns the last level's min-degree node.
  std::vector<std::int64_t> queue;
  auto bfs_far = [&](std::int64_t s) {
    queue.assign(1, s);
    level[s] = 0;
    std::int64_t best = s;
    for (std::size_t h = 0; h < queue.size(); ++h) {
      const std::int64_t t = queue[h];
      if (level[t] > level[best] || (level[t] == level[best] && deg[t] < deg[best])) best = t;
      for (auto k = off[t]; k < off[t + 1]; ++k) {
        const std::int64_t u = adj[k];
        if (!seen[u] && level[u] < 0) {
          level[u] = level[t] + 1;
          queue.push_back(u);
        }
      }
    }
    for (auto t : queue) level[t] = -1;
    return best;
  };
  // Start candidates: by increasing degree, ties by global id (a counting
  // sort: degrees are small, and it is stable).
  std::vector<std::int64_t> by_deg(m);
  {
    const std::int32_t max_deg = m ? *std::max_element(deg.begin(), deg.end()) : 0;
    std::vector<std::int64_t> start(static_cast<std::size_t>(max_deg) + 2, 0);
    for (std::size_t t = 0; t < m; ++t) ++start[deg[t] + 1];
    for (std::size_t d = 1; d < start.size(); ++d) start[d] += start[d - 1];
    for (std::size_t t = 0; t < m; ++t) by_deg[start[deg[t]]++] = static_cast<std::int64_t>(t);
  }
  // One Cuthill-McKee BFS from the nodes already appended at `head`.
  auto cuthill_mckee = [&](std::size_t head) {
    for (; head < order.size(); ++head) {
      const std::int64_t t = order[head];
      kids.clear();
      for (auto k = off[t]; k < off[t + 1]; ++k) {
        const std::int64_t u = adj[k];
        if (!seen[u]) {
          seen[u] = 1;
          kids.push_back(u);
        }
      }
      // Stable insertion sort by degree: a node has few children, and
      // std::stable_sort allocates a buffer on every call (5M calls at 10M).
      for (std::size_t i = 1; i < kids.size(); ++i) {
        const std::int64_t u = kids[i];
        std::size_t j = i;
        for (; j > 0 && deg[kids[j - 1]] > deg[u]; --j) kids[j] = kids[j - 1];
        kids[j] = u;
      }
      order.insert(order.end(), kids.begin(), kids.end());
    }
  };
  for (std::int64_t t : seeds)
    if (!seen[t]) {
      seen[t] = 1;
      order.push_back(t);
    }
  cuthill_mckee(0);
  for (std::int64_t cand : by_deg) {  // components without seeds
    if (seen[cand]) continue;
    const std::int64_t s = bfs_far(cand);
    const std::size_t head = order.size();
    order.push_back(s);
    seen[s] = 1;
    cuthill_mckee(head);
  }
  std::reverse(order.begin(), order.end());
  for (auto& t : order) t = nodes[t];
  return order;
}
}  // namespace

DistGraph::DistGraph(MPI_Comm comm, GlobalId n, const std::vector<int>& owner, const std::vector<GlobalId>& edges,
                     const std::vector<double>& edge_values, int width, int halo_width, LocalOrdering ordering)
    : comm_(comm), n_global_(n), width_(width) {
  const int size = comm_size(comm), rank = comm_rank(comm);
  double tmark = MPI_Wtime();
  auto phase_done = [&](const char* name) {
    const double now = MPI_Wtime();
    build_phases_.emplace_back(name, now - tmark);
    tmark = now;
  };
  // 1. Every edge goes to the owners of both ends (once if they coincide).
  std::vector<std::vector<EdgeRec>> out(size);
  std::vector<std::vector<double>> out_vals(size);
  for (std::size_t e = 0; 2 * e < edges.size(); ++e) {
    const GlobalId a = edges[2 * e], b = edges[2 * e + 1];
    const int oa = owner[a], ob = owner[b];
    out[oa].push_back({a, b});
    out_vals[oa].insert(out_vals[oa].end(), edge_values.begin() + e * width, edge_values.begin() + (e + 1) * width);
    if (ob != oa) {
      out[ob].push_back({a, b});
      out_vals[ob].insert(out_vals[ob].end(), edge_values.begin() + e * width, edge_values.begin() + (e + 1) * width);
    }
  }
  std::vector<EdgeRec> mine = exchange_records(comm, out);
  std::vector<double> mine_vals = exchange_records(comm, out_vals);
  out.clear();
  out_vals.clear();

  phase_done("exchange");
  // 2. Owned nodes in global order, then per-node neighbour lists.
  std::vector<GlobalId> owned;
  for (GlobalId g = 0; g < n; ++g)
    if (owner[g] == rank) owned.push_back(g);
  if (owned.size() > static_cast<std::size_t>(std::numeric_limits<LocalId>::max()))
    throw Error("too many sensors on one rank for 32-bit local ids; use more ranks");
  // Global id -> index in `owned` in O(1) (4 bytes per global node, like
  // `owner`): a binary search per edge end dominated the setup at 10^7 nodes.
  std::vector<std::int32_t> owned_pos(static_cast<std::size_t>(n), -1);
  for (std::size_t v = 0; v < owned.size(); ++v) owned_pos[owned[v]] = static_cast<std::int32_t>(v);
  auto owned_index = [&](GlobalId g) -> std::int64_t { return owned_pos[g]; };
  std::vector<std::int64_t> cnt(owned.size() + 1, 0);
  for (const auto& r : mine) {
    if (owner[r.a] == rank) ++cnt[owned_index(r.a) + 1];
    if (owner[r.b] == rank) ++cnt[owned_index(r.b) + 1];
  }
  for (std::size_t v = 0; v < owned.size(); ++v) cnt[v + 1] += cnt[v];
  std::vector<Entry> entries(static_cast<std::size_t>(cnt.back()));
  {
    std::vector<std::int64_t> fill(cnt.begin(), cnt.end() - 1);
    for (std::size_t t = 0; t < mine.size(); ++t) {
      const auto& r = mine[t];
      if (owner[r.a] == rank) entries[fill[owned_index(r.a)]++] = {r.b, static_cast<std::int64_t>(t)};
      if (owner[r.b] == rank) entries[fill[owned_index(r.b)]++] = {r.a, static_cast<std::int64_t>(t)};
    }
  }
  std::vector<char> boundary(owned.size(), 0);
  for (std::size_t v = 0; v < owned.size(); ++v) {
    std::sort(entries.begin() + cnt[v], entries.begin() + cnt[v + 1],
              [](const Entry& x, const Entry& y) { return x.nbr < y.nbr; });
    for (auto k = cnt[v]; k < cnt[v + 1]; ++k)
      if (owner[entries[k].nbr] != rank) boundary[v] = 1;
  }

  phase_done("lists");
  // 3. Local numbering: interior owned, boundary owned (each group in RCM or
  //    global order), ghosts by (owner, gid) so each neighbour's slots are contiguous.
  std::vector<std::int64_t> order;  // owned index in local order
  order.reserve(owned.size());
  {
    std::vector<std::int64_t> group[2];
    for (std::size_t v = 0; v < owned.size(); ++v) group[boundary[v] ? 1 : 0].push_back(static_cast<std::int64_t>(v));
    if (ordering == LocalOrdering::kRcm) {
      // Owned-index adjacency (-1 for ghosts) and group positions for the BFS.
      std::vector<std::int64_t> nbrs(entries.size());
      for (std::size_t k = 0; k < entries.size(); ++k) nbrs[k] = owned_index(entries[k].nbr);
      std::vector<std::int64_t> pos(owned.size(), -1);
      std::vector<std::int64_t> seeds;
      for (int gi : {1, 0}) {  // the boundary first: its order seeds the interior's
        auto& grp = group[gi];
        for (std::size_t t = 0; t < grp.size(); ++t) pos[grp[t]] = static_cast<std::int64_t>(t);
        if (gi == 0)  // interior nodes next to the boundary, in the boundary's order
          for (auto b : group[1])
            for (auto k = cnt[b]; k < cnt[b + 1]; ++k)
              if (nbrs[k] >= 0 && !boundary[nbrs[k]]) seeds.push_back(pos[nbrs[k]]);
        grp = rcm_order(grp, cnt, nbrs, pos, seeds);
        for (auto v : grp) pos[v] = -1;
        sort_degree_windows(grp, cnt);
      }
    }
    order = std::move(group[0]);
    n_interior_ = static_cast<LocalId>(order.size());
    order.insert(order.end(), group[1].begin(), group[1].end());
  }
  phase_done("order");
  n_owned_ = static_cast<LocalId>(owned.size());
  std::vector<GlobalId> ghosts;
  for (const auto& en : entries)
    if (owner[en.nbr] != rank) ghosts.push_back(en.nbr);
  std::sort(ghosts.begin(), ghosts.end(), [&](GlobalId x, GlobalId y) {
    return owner[x] != owner[y] ? owner[x] < owner[y] : x < y;
  });
  ghosts.erase(std::unique(ghosts.begin(), ghosts.end()), ghosts.end());
  if (owned.size() + ghosts.size() > static_cast<std::size_t>(std::numeric_limits<LocalId>::max()))
    throw Error("too many local nodes on one rank for 32-bit local ids; use more ranks");

  local_to_global_.resize(owned.size() + ghosts.size());
  std::vector<LocalId> owned_to_local(owned.size());
  for (std::size_t l = 0; l < order.size(); ++l) {
    local_to_global_[l] = owned[order[l]];
    owned_to_local[order[l]] = static_cast<LocalId>(l);
  }
  for (std::size_t t = 0; t < ghosts.size(); ++t) local_to_global_[owned.size() + t] = ghosts[t];
  owned_sorted_.resize(owned.size());
  for (std::size_t v = 0; v < owned.size(); ++v) owned_sorted_[v] = {owned[v], owned_to_local[v]};
  std::vector<std::pair<GlobalId, LocalId>> ghost_sorted(ghosts.size());
  for (std::size_t t = 0; t < ghosts.size(); ++t)
    ghost_sorted[t] = {ghosts[t], static_cast<LocalId>(owned.size() + t)};
  std::sort(ghost_sorted.begin(), ghost_sorted.end());
  auto to_local = [&](GlobalId g) -> LocalId {
    if (owner[g] == rank) return owned_to_local[owned_index(g)];
    auto it = std::lower_bound(ghost_sorted.begin(), ghost_sorted.end(), std::make_pair(g, LocalId(-1)));
    return it->second;
  };

  // 4. CSR in local order.
  offsets_.assign(owned.size() + 1, 0);
  adjacency_.resize(entries.size());
  edge_values_.resize(entries.size() * width);
  std::int64_t pos = 0;
  for (std::size_t l = 0; l < order.size(); ++l) {
    const auto v = order[l];
    for (auto k = cnt[v]; k < cnt[v + 1]; ++k, ++pos) {
      adjacency_[pos] = to_local(entries[k].nbr);
      for (int c = 0; c < width; ++c) edge_values_[pos * width + c] = mine_vals[entries[k].src * width + c];
    }
    offsets_[l + 1] = pos;
  }

  phase_done("csr");
  // 5. Halo plan: tell each owner which of its nodes we need, in our ghost order.
  std::vector<std::vector<GlobalId>> requests(size);
  for (GlobalId g : ghosts) requests[owner[g]].push_back(g);
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
  // Who asks us, and for what: one all-to-all of the request lists.
  std::vector<std::vector<GlobalId>> tagged(size);
  for (int r = 0; r < size; ++r) {
    tagged[r].reserve(requests[r].size() + 1);
    tagged[r].push_back(static_cast<GlobalId>(requests[r].size()));
    tagged[r].insert(tagged[r].end(), requests[r].begin(), requests[r].end());
  }
  std::vector<GlobalId> asked = exchange_records(comm, tagged);
  std::vector<std::vector<LocalId>> send_ids;
  std::vector<int> senders;  // ranks that asked us, in rank order
  {
    std::size_t p = 0;
    for (int r = 0; r < size; ++r) {
      const auto k = static_cast<std::size_t>(asked[p++]);
      if (k > 0) {
        std::vector<LocalId> ids(k);
        for (std::size_t t = 0; t < k; ++t) ids[t] = owned_to_local[owned_index(asked[p + t])];
        senders.push_back(r);
        send_ids.push_back(std::move(ids));
      }
      p += k;
    }
  }
  // The graph is undirected, so the ranks we receive from are those we send to.
  if (senders != nbr_ranks) throw Error("internal error: asymmetric halo (edges not symmetric?)");
  halo_ = HaloPlan(comm, n_owned_, nbr_ranks, std::move(send_ids), recv_offset, recv_count, halo_width);
  phase_done("halo");
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

LocalId DistGraph::max_degree() const {
  LocalId d = 0;
  for (LocalId v = 0; v < n_owned_; ++v) d = std::max(d, degree(v));
  LocalId g = 0;
  MPI_Allreduce(&d, &g, 1, MPI_INT32_T, MPI_MAX, comm_);
  return g;
}

}  // namespace snl
