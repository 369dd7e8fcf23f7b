// The bfs partition (bfs_partition, src/graph/partition.cpp) against a plain
// serial twin of the same recursive bisection on shuffled grids and random
// geometric graphs, with the properties a partition must have: every node in
// one part, part sizes in proportion, parts connected on a connected graph,
// and a cut of the order of a straight one on a grid.
#include <gtest/gtest.h>

#include <algorithm>
#include <deque>
#include <functional>
#include <numeric>
#include <random>
#include <set>

#include "snl/graph/dist_graph.hpp"

using namespace snl;

namespace {

struct Graph {
  std::vector<std::int64_t> xadj;
  std::vector<std::int32_t> adjncy;
  int n() const { return static_cast<int>(xadj.size()) - 1; }
};

Graph from_pairs(int n, const std::vector<std::pair<int, int>>& pairs) {
  std::vector<std::vector<std::int32_t>> rows(n);
  for (auto [a, b] : pairs) {
    rows[a].push_back(b);
    rows[b].push_back(a);
  }
  Graph g;
  g.xadj.push_back(0);
  for (auto& r : rows) {
    std::sort(r.begin(), r.end());
    g.adjncy.insert(g.adjncy.end(), r.begin(), r.end());
    g.xadj.push_back(static_cast<std::int64_t>(g.adjncy.size()));
  }
  return g;
}

// A side x side grid (4-neighbour), node ids shuffled; `copies` disjoint copies.
Graph grid(int side, unsigned seed, int copies = 1) {
  const int m = side * side, n = m * copies;
  std::vector<int> id(n);
  std::iota(id.begin(), id.end(), 0);
  std::shuffle(id.begin(), id.end(), std::mt19937(seed));
  std::vector<std::pair<int, int>> pairs;
  for (int c = 0; c < copies; ++c)
    for (int y = 0; y < side; ++y)
      for (int x = 0; x < side; ++x) {
        const int v = c * m + y * side + x;
        if (x + 1 < side) pairs.emplace_back(id[v], id[v + 1]);
        if (y + 1 < side) pairs.emplace_back(id[v], id[v + side]);
      }
  return from_pairs(n, pairs);
}

// n random points of the unit square, linked within radius r.
Graph geometric(int n, double r, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<double> x(n), y(n);
  for (int i = 0; i < n; ++i) x[i] = u(rng), y[i] = u(rng);
  std::vector<std::pair<int, int>> pairs;
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      if ((x[i] - x[j]) * (x[i] - x[j]) + (y[i] - y[j]) * (y[i] - y[j]) < r * r) pairs.emplace_back(i, j);
  return from_pairs(n, pairs);
}

// The twin: the same recursive bisection written plainly (sets, a deque, recursion).
void twin_split(const Graph& g, std::vector<int> nodes, int p0, int p1, std::vector<int>& owner) {
  if (p1 - p0 == 1 || nodes.empty()) {
    for (int v : nodes) owner[v] = p0;
    return;
  }
  const std::set<int> in(nodes.begin(), nodes.end());
  auto bfs = [&](int root, std::set<int>& seen) {
    std::vector<int> order{root};
    seen.insert(root);
    for (std::size_t h = 0; h < order.size(); ++h)
      for (std::int64_t k = g.xadj[order[h]]; k < g.xadj[order[h] + 1]; ++k) {
        const int u = g.adjncy[k];
        if (in.count(u) && !seen.count(u)) {
          seen.insert(u);
          order.push_back(u);
        }
      }
    return order;
  };
  // Component by component (in the order of their first nodes), each from
  // the last node reached from its first node.
  std::set<int> seen;
  std::vector<int> order;
  for (int v : nodes)
    if (!seen.count(v)) {
      std::set<int> sweep = seen;
      const int root = bfs(v, sweep).back();
      const std::vector<int> more = bfs(root, seen);
      order.insert(order.end(), more.begin(), more.end());
    }
  const int pm = p0 + (p1 - p0) / 2;
  const std::size_t mid = order.size() * static_cast<std::size_t>(pm - p0) / static_cast<std::size_t>(p1 - p0);
  twin_split(g, std::vector<int>(order.begin(), order.begin() + mid), p0, pm, owner);
  twin_split(g, std::vector<int>(order.begin() + mid, order.end()), pm, p1, owner);
}

std::vector<int> twin(const Graph& g, int nparts) {
  std::vector<int> nodes(g.n()), owner(g.n(), -1);
  std::iota(nodes.begin(), nodes.end(), 0);
  twin_split(g, nodes, 0, nparts, owner);
  return owner;
}

long long cut(const Graph& g, const std::vector<int>& owner) {
  long long c = 0;
  for (int v = 0; v < g.n(); ++v)
    for (std::int64_t k = g.xadj[v]; k < g.xadj[v + 1]; ++k) c += owner[v] != owner[g.adjncy[k]];
  return c / 2;
}

bool part_connected(const Graph& g, const std::vector<int>& owner, int p) {
  std::vector<int> nodes;
  for (int v = 0; v < g.n(); ++v)
    if (owner[v] == p) nodes.push_back(v);
  if (nodes.empty()) return true;
  std::vector<char> seen(g.n(), 0);
  std::deque<int> q{nodes.front()};
  seen[nodes.front()] = 1;
  std::size_t reached = 1;
  while (!q.empty()) {
    const int v = q.front();
    q.pop_front();
    for (std::int64_t k = g.xadj[v]; k < g.xadj[v + 1]; ++k) {
      const int u = g.adjncy[k];
      if (owner[u] == p && !seen[u]) seen[u] = 1, ++reached, q.push_back(u);
    }
  }
  return reached == nodes.size();
}

}  // namespace

TEST(BfsPartition, EqualsItsTwin) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const Graph graphs[] = {grid(23, seed), grid(12, seed, 3), geometric(700, 0.07, seed)};
    for (const Graph& g : graphs)
      for (int np : {1, 2, 3, 4, 5, 8, 70})  // 70: over 64 parts, the labels take 32 bits
        EXPECT_EQ(bfs_partition(g.xadj, g.adjncy, np), twin(g, np)) << "seed " << seed << ", " << np << " parts";
  }
}

TEST(BfsPartition, SizesInProportionAndConnectedParts) {
  const Graph g = geometric(3000, 0.045, 7);
  for (int np : {2, 3, 4, 6, 7}) {
    const std::vector<int> owner = bfs_partition(g.xadj, g.adjncy, np);
    std::vector<int> count(np, 0);
    for (int p : owner) {
      ASSERT_GE(p, 0);
      ASSERT_LT(p, np);
      ++count[p];
    }
    const double mean = 3000.0 / np;
    for (int p = 0; p < np; ++p) {
      EXPECT_LE(std::abs(count[p] - mean), 3.0) << np << " parts: part " << p << " holds " << count[p];
      // A part is a breadth-first range: connected when the graph is (this one
      // is, at this radius; if not, the test says so).
      EXPECT_TRUE(part_connected(g, owner, p)) << np << " parts: part " << p << " is not connected";
    }
  }
}

TEST(BfsPartition, GridCutNearAStraightOne) {
  // A 40 x 40 grid in random numbering: a straight cut in halves crosses 40
  // edges; breadth-first levels from a corner cut along a diagonal (2 edges per
  // node of it, 80). Ids in order (the start without the peripheral sweep) or
  // a ball from the middle cross far more.
  const Graph g = grid(40, 11);
  const std::vector<int> owner = bfs_partition(g.xadj, g.adjncy, 2);
  EXPECT_LE(cut(g, owner), 84);
  EXPECT_TRUE(part_connected(g, owner, 0));
  EXPECT_TRUE(part_connected(g, owner, 1));
}

TEST(BfsPartition, EveryComponentAssigned) {
  const Graph g = grid(10, 5, 4);  // 4 components of 100 nodes
  const std::vector<int> owner = bfs_partition(g.xadj, g.adjncy, 4);
  std::vector<int> count(4, 0);
  for (int p : owner) ++count[p];
  EXPECT_EQ(count, std::vector<int>(4, 100));
  // More parts than nodes: every node still gets a part.
  const Graph tiny = grid(2, 1);
  const std::vector<int> t = bfs_partition(tiny.xadj, tiny.adjncy, 6);
  for (int p : t) EXPECT_TRUE(p >= 0 && p < 6);
}
