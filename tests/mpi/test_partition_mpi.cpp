// The bfs partition computed by every rank on its block of rows
// (detail::bfs_blocks, src/graph/level_bisection.cpp) against a plain serial
// twin of its definition, on 1, 2 and 3 ranks and for part counts other than
// the rank count: shuffled grids with several components, random geometric
// graphs, isolated nodes, duplicate pairs, more parts than nodes, a hub
// whose probe dies out at once (r from a full pass); and the
// level limit, agreed by every rank.
#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <numeric>
#include <random>
#include <set>
#include <vector>

#include "graph/partition_detail.hpp"
#include "snl/graph/dist_graph.hpp"
#include "solve_helpers.hpp"

using namespace snl;
using snl::test::world_rank;
using snl::test::world_size;

namespace {

struct Graph {
  int n = 0;
  std::vector<GlobalId> pairs;          // every rank holds all; each passes a share
  std::vector<std::vector<int>> rows;   // with duplicates, as the partition's rows
};

Graph from_pairs(int n, const std::vector<std::pair<int, int>>& p) {
  Graph g;
  g.n = n;
  g.rows.resize(n);
  for (auto [a, b] : p) {
    g.pairs.insert(g.pairs.end(), {a, b});
    g.rows[a].push_back(b);
    g.rows[b].push_back(a);
  }
  return g;
}

// side x side grids (4-neighbour), `copies` of them, ids shuffled, plus
// `isolated` nodes of no pair and every 7th pair twice.
Graph grids(int side, int copies, int isolated, unsigned seed) {
  const int m = side * side, n = m * copies + isolated;
  std::vector<int> id(n);
  std::iota(id.begin(), id.end(), 0);
  std::shuffle(id.begin(), id.end(), std::mt19937(seed));
  std::vector<std::pair<int, int>> p;
  for (int c = 0; c < copies; ++c)
    for (int y = 0; y < side; ++y)
      for (int x = 0; x < side; ++x) {
        const int v = c * m + y * side + x;
        if (x + 1 < side) p.emplace_back(id[v], id[v + 1]);
        if (y + 1 < side) p.emplace_back(id[v], id[v + side]);
        if (p.size() % 7 == 0) p.push_back(p.back());
      }
  return from_pairs(n, p);
}

Graph geometric(int n, double r, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<double> x(n), y(n);
  for (int i = 0; i < n; ++i) x[i] = u(rng), y[i] = u(rng);
  std::vector<std::pair<int, int>> p;
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      if ((x[i] - x[j]) * (x[i] - x[j]) + (y[i] - y[j]) * (y[i] - y[j]) < r * r) p.emplace_back(i, j);
  return from_pairs(n, p);
}

// A hub (the node of largest degree) whose 4 smallest neighbours are
// leaves, joined to the corner of a shuffled 20x20 grid: its probe dies out
// at once, and r comes from a full pass.
Graph hub() {
  const int side = 20, m = side * side, hub_id = 4;
  std::vector<int> id(m);
  std::iota(id.begin(), id.end(), 5);
  std::shuffle(id.begin(), id.end(), std::mt19937(11));
  std::vector<std::pair<int, int>> p;
  for (int leaf = 0; leaf < 4; ++leaf) p.emplace_back(hub_id, leaf);
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x) {
      const int v = y * side + x;
      if (x + 1 < side) p.emplace_back(id[v], id[v + 1]);
      if (y + 1 < side) p.emplace_back(id[v], id[v + side]);
      if (x < 3 && y < 3) p.emplace_back(hub_id, id[v]);
    }
  return from_pairs(m + 5, p);
}

Graph path(int n) {
  std::vector<std::pair<int, int>> p;
  for (int i = 0; i + 1 < n; ++i) p.emplace_back((i * 7) % n, ((i + 1) * 7) % n);  // 7 coprime to n
  return from_pairs(n, p);
}

// The twin: the definition of level_bisection.cpp written plainly (sets,
// maps, recursion).
// Distances from root within `within`; a probe follows from each node the
// first 4 entries of its row by id (duplicates included) only.
std::map<int, int> distances(const Graph& g, int root, const std::set<int>& within, bool probe = false) {
  std::map<int, int> d{{root, 0}};
  std::deque<int> q{root};
  while (!q.empty()) {
    const int v = q.front();
    q.pop_front();
    std::vector<int> row = g.rows[v];
    std::sort(row.begin(), row.end());
    if (probe && row.size() > 4) row.resize(4);
    for (int u : row)
      if (within.count(u) && !d.count(u)) d[u] = d[v] + 1, q.push_back(u);
  }
  return d;
}

// owner and, in keys, each node's key in the split that gave it its part
// (parent: the keys of that split; none at the top: 0).
void twin_split(const Graph& g, const std::vector<int>& nodes, int p0, int p1, std::vector<int>& owner,
                std::vector<std::int64_t>& keys, const std::map<int, std::int64_t>* parent) {
  if (p1 - p0 == 1) {
    for (int v : nodes) owner[v] = p0, keys[v] = parent ? parent->at(v) : 0;
    return;
  }
  if (nodes.empty()) return;
  const auto m = static_cast<std::int64_t>(nodes.size());
  std::set<int> left(nodes.begin(), nodes.end());
  std::map<int, std::int64_t> key;
  std::int64_t base = 0;
  for (int round = 0; round < 8 && !left.empty(); ++round) {
    if (round > 0 && static_cast<std::int64_t>(left.size()) * 64 <= m) break;
    int s = *left.begin();
    for (int v : left)
      if (g.rows[v].size() > g.rows[s].size()) s = v;  // ascending: ties keep the smallest id
    // r: farthest from s by the probe, or by a full pass where the probe
    // reached under 1/8 of the nodes left.
    auto ds = distances(g, s, left, true);
    if (ds.size() * 8 < left.size()) ds = distances(g, s, left);
    int far = 0, r = s;
    for (auto [v, d] : ds)
      if (d > far) far = d, r = v;  // ascending ids: the first at the largest distance
    const auto dr = distances(g, r, left);
    int top = 0;
    for (auto [v, d] : dr) {
      key[v] = base + d;
      left.erase(v);
      top = std::max(top, d);
    }
    base += top + 1;
  }
  for (int v : left) key[v] = base;
  std::vector<int> order(nodes);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return key[a] != key[b] ? key[a] < key[b] : a < b; });
  const int pm = p0 + (p1 - p0) / 2;
  const std::int64_t need = m * (pm - p0) / (p1 - p0);
  std::int64_t cut = need;
  if (need > 0) {
    const std::int64_t k = key[order[need - 1]], slack = m / 256;
    std::int64_t lo = 0, up = 0;
    for (int v : order) lo += key[v] < k, up += key[v] <= k;
    if (need - lo <= slack || up - need <= slack) cut = need - lo <= up - need ? lo : up;
  }
  twin_split(g, std::vector<int>(order.begin(), order.begin() + cut), p0, pm, owner, keys, &key);
  twin_split(g, std::vector<int>(order.begin() + cut, order.end()), pm, p1, owner, keys, &key);
}

std::vector<int> twin(const Graph& g, int nparts, std::vector<std::int64_t>* keys = nullptr) {
  std::vector<int> nodes(g.n), owner(g.n, -1);
  std::vector<std::int64_t> k(g.n, -1);
  std::iota(nodes.begin(), nodes.end(), 0);
  twin_split(g, nodes, 0, nparts, owner, k, nullptr);
  if (keys) *keys = k;
  return owner;
}

// Every rank's block of v (block_range) gathered on every rank.
template <class T>
std::vector<T> gather_blocks(int n, const std::vector<T>& mine, MPI_Datatype type) {
  const int size = world_size();
  std::vector<int> counts(size), displs(size);
  for (int r = 0; r < size; ++r) {
    GlobalId b, e;
    block_range(n, size, r, b, e);
    counts[r] = static_cast<int>(e - b);
    displs[r] = static_cast<int>(b);
  }
  std::vector<T> all(n);
  MPI_Allgatherv(mine.data(), static_cast<int>(mine.size()), type, all.data(), counts.data(), displs.data(), type,
                 MPI_COMM_WORLD);
  return all;
}

// bfs_blocks with the pairs dealt round robin; the owners (and keys) of all nodes.
std::string distributed(const Graph& g, int nparts, std::int64_t max_levels, std::vector<int>& owner,
                        std::vector<std::int64_t>* keys = nullptr) {
  const int size = world_size(), rank = world_rank();
  std::vector<GlobalId> mine;
  for (std::size_t k = 0; k < g.pairs.size(); k += 2)
    if (static_cast<int>((k / 2) % size) == rank) mine.insert(mine.end(), {g.pairs[k], g.pairs[k + 1]});
  std::vector<int> block;
  std::vector<std::int32_t> key;
  std::int64_t peak = 0;
  const std::string why = detail::bfs_blocks(MPI_COMM_WORLD, g.n, mine, nparts, max_levels, block, peak, {}, &key);
  if (why.empty()) {
    owner = gather_blocks(g.n, block, MPI_INT);
    if (keys) {
      const std::vector<std::int32_t> all = gather_blocks(g.n, key, MPI_INT32_T);
      keys->assign(all.begin(), all.end());
    }
  }
  return why;
}

}  // namespace

TEST(DistributedBfs, EqualsItsTwin) {
  const std::vector<std::pair<const char*, Graph>> graphs = {
      {"geometric 700", geometric(700, 0.07, 3)},
      {"geometric 300, sparse", geometric(300, 0.05, 4)},  // many components
      {"3 grids 12x12 + 9 isolated", grids(12, 3, 9, 5)},
      {"grid 30x30", grids(30, 1, 0, 6)},
      {"path 97", path(97)},
      {"hub whose probe dies out", hub()},
      {"1 node", from_pairs(1, {})},
      {"2 nodes", from_pairs(2, {{0, 1}})},
      {"5 nodes, no pair", from_pairs(5, {})},
  };
  for (const auto& [name, g] : graphs)
    for (const int np : {1, 2, 3, 4, 5, 8, 13}) {
      std::vector<int> owner;
      std::vector<std::int64_t> keys, twin_keys;
      ASSERT_EQ(distributed(g, np, 1 << 20, owner, &keys), "") << name;
      EXPECT_EQ(owner, twin(g, np, &twin_keys)) << name << ", " << np << " parts, rank " << world_rank();
      EXPECT_EQ(keys, twin_keys) << name << ", " << np << " parts, rank " << world_rank();
    }
}

TEST(DistributedBfs, PartsInProportionConnectedOnAGridAndACutNearAStraightOne) {
  const Graph g = grids(40, 1, 0, 8);
  for (const int np : {2, 3, 4}) {
    std::vector<int> owner;
    ASSERT_EQ(distributed(g, np, 1 << 20, owner), "");
    std::vector<int> count(np, 0);
    for (int o : owner) ++count[o];
    for (int p = 0; p < np; ++p) EXPECT_NEAR(count[p], 1600.0 / np, 1600.0 / 256 * 2 + 1) << np << " parts";
    if (np == 2) {
      long long cut = 0;
      for (int v = 0; v < g.n; ++v)
        for (int u : g.rows[v]) cut += owner[u] != owner[v];
      EXPECT_LE(cut / 2, 2 * 40 * 8 / 7 + 8) << "a straight cut has 40 edges (some pairs twice)";
    }
  }
}

// A chain of 97 nodes needs about 97 levels from an end: under a limit of 20
// every rank says so; the caller then partitions on rank 0.
TEST(DistributedBfs, PastTheLevelLimitOnEveryRank) {
  const Graph g = path(97);
  std::vector<int> owner;
  EXPECT_EQ(distributed(g, 2, 20, owner), detail::kPastMaxLevels);
  EXPECT_EQ(distributed(g, 2, 200, owner), "");
  EXPECT_EQ(owner, twin(g, 2));
}

// The directory's index: each owner's nodes block by block (the blocks of
// block_range, in rank order), within a block in (key, global id) order;
// owned_nodes lists them in index order and, by_gid, the indices in global
// id order. Keys too many for a block's bins fall back to global id order.
void check_directory(int n, const std::vector<int>& owner, const std::vector<std::int32_t>& key,
                     const std::function<bool(int)>& keyed) {
  const int size = world_size(), rank = world_rank();
  GlobalId b, e;
  block_range(n, size, rank, b, e);
  const std::vector<int> mine_owner(owner.begin() + b, owner.begin() + e);
  const std::vector<std::int32_t> mine_key =
      key.empty() ? std::vector<std::int32_t>{} : std::vector<std::int32_t>(key.begin() + b, key.begin() + e);
  const OwnerDirectory dir(MPI_COMM_WORLD, n, mine_owner, mine_key);
  // The plain order: per owner, nodes sorted by (block, key, id) (or id).
  std::vector<std::vector<GlobalId>> expect(size);
  std::vector<int> ids(n);
  std::iota(ids.begin(), ids.end(), 0);
  auto block_of = [&](int v) { return block_owner(n, size, v); };
  std::stable_sort(ids.begin(), ids.end(), [&](int x, int y) {
    if (block_of(x) != block_of(y)) return block_of(x) < block_of(y);
    return keyed(block_of(x)) && key[x] < key[y];
  });
  for (int v : ids) expect[owner[v]].push_back(v);
  for (GlobalId g = b; g < e; ++g) {
    const auto& s = dir.local(g);
    ASSERT_EQ(s.owner, owner[g]);
    ASSERT_LT(s.index, static_cast<std::int32_t>(expect[s.owner].size()));
    EXPECT_EQ(expect[s.owner][s.index], g) << "node " << g << " rank " << rank;
  }
  std::vector<std::int32_t> by_gid;
  const std::vector<GlobalId> owned = dir.owned_nodes(&by_gid);
  EXPECT_EQ(owned, expect[rank]) << "rank " << rank;
  ASSERT_EQ(by_gid.size(), owned.size());
  for (std::size_t t = 1; t < by_gid.size(); ++t) EXPECT_LT(owned[by_gid[t - 1]], owned[by_gid[t]]);
}

TEST(OwnerDirectory, IndexInKeyThenIdOrder) {
  const int size = world_size(), n = 1000;
  std::mt19937 rng(11);
  std::vector<int> owner(n);
  std::vector<std::int32_t> key(n), big(n);
  for (int v = 0; v < n; ++v) {
    owner[v] = static_cast<int>(rng() % static_cast<unsigned>(size));
    key[v] = static_cast<std::int32_t>(rng() % 40);
    big[v] = v == 500 ? (1 << 23) : key[v];  // more bins than the directory keeps
  }
  auto all = [](int) { return true; };
  auto none = [](int) { return false; };
  check_directory(n, owner, key, all);
  check_directory(n, owner, {}, none);
  check_directory(n, owner, std::vector<std::int32_t>(n, 0), none);
  // Only the block of node 500 has more bins than the directory keeps.
  check_directory(n, owner, big, [&](int b) { return b != block_owner(n, size, 500); });
}

// The graph build indexes its lists by the directory's index; the local
// order (RCM) and the CSR must not depend on that index's order: the same
// graph under keyed and unkeyed directories gives the same local numbering.
TEST(OwnerDirectory, LocalOrderIndependentOfTheIndexOrder) {
  const int size = world_size(), rank = world_rank();
  const Graph g = geometric(900, 0.06, 12);
  GlobalId b, e;
  block_range(g.n, size, rank, b, e);
  std::mt19937 rng(13);
  std::vector<int> owner(g.n);
  std::vector<std::int32_t> key(g.n);
  for (int v = 0; v < g.n; ++v) {
    owner[v] = static_cast<int>((v / 7) % size);
    key[v] = static_cast<std::int32_t>(rng() % 50);
  }
  const std::vector<int> mine_owner(owner.begin() + b, owner.begin() + e);
  const std::vector<std::int32_t> mine_key(key.begin() + b, key.begin() + e);
  auto build = [&](const std::vector<std::int32_t>& keys) {
    std::vector<GlobalId> edges;
    std::vector<double> vals;
    for (std::size_t k = 0; k < g.pairs.size(); k += 2)
      if (static_cast<int>((k / 2) % size) == rank) {
        edges.insert(edges.end(), {g.pairs[k], g.pairs[k + 1]});
        vals.push_back(static_cast<double>(k));
      }
    return DistGraph(MPI_COMM_WORLD, OwnerDirectory(MPI_COMM_WORLD, g.n, mine_owner, keys), edges, vals, 1, 2);
  };
  const DistGraph plain = build({}), keyed = build(mine_key);
  EXPECT_EQ(keyed.local_to_global(), plain.local_to_global()) << "rank " << rank;
  EXPECT_EQ(keyed.num_interior(), plain.num_interior());
  EXPECT_EQ(keyed.offsets(), plain.offsets());
  EXPECT_EQ(keyed.adjacency(), plain.adjacency());
  EXPECT_EQ(keyed.edge_values(), plain.edge_values());
}
