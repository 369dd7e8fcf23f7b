// Halo exchange and distributed graph (src/graph): ghosts receive their
// owners' values, interior nodes have no ghost neighbours, neighbour lists are
// in global-id order, and the owned nodes of all ranks add up to the network.
#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cstdlib>
#include <map>
#include <string>
#include <utility>

#include "snl/graph/delta_halo.hpp"
#include "solve_helpers.hpp"

using namespace snl;
using snl::test::allgather_positions;
using snl::test::make_network;
using snl::test::merged;
using snl::test::NetSpec;
using snl::test::run;
using snl::test::slab_of;
using snl::test::world_rank;
using snl::test::world_size;

TEST(Halo, GhostsReceiveOwnersValues) {
  const Network w = make_network({.n = 200, .dim = 2, .radius = 0.15});
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  const auto& g = prob.graph();
  std::vector<double> f(std::size_t(g.num_local()) * 2, -1.0);
  for (LocalId v = 0; v < g.num_owned(); ++v) {
    f[2 * v] = double(g.global_id(v));
    f[2 * v + 1] = -double(g.global_id(v));
  }
  if (world_size() > 1) EXPECT_GT(g.num_local(), g.num_owned()) << "no ghosts: the exchange is not tested";
  prob.graph().halo().exchange(f.data(), 2);
  for (LocalId v = g.num_owned(); v < g.num_local(); ++v) {
    EXPECT_EQ(f[2 * v], double(g.global_id(v)));
    EXPECT_EQ(f[2 * v + 1], -double(g.global_id(v)));
  }
  // Interior nodes have no ghost neighbours; neighbour lists are sorted by global id.
  for (LocalId v = 0; v < g.num_owned(); ++v) {
    for (auto e = g.offsets()[v]; e < g.offsets()[v + 1]; ++e) {
      if (v < g.num_interior()) EXPECT_LT(g.adjacency()[e], g.num_owned());
      if (e > g.offsets()[v]) EXPECT_LT(g.global_id(g.adjacency()[e - 1]), g.global_id(g.adjacency()[e]));
    }
  }
  long long owned = g.num_owned(), total = 0;
  MPI_Allreduce(&owned, &total, 1, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_EQ(total, 200);
}

// Every edge held by rank 0 and every node owned away from its block: the
// other ranks start with no edges and receive thousands of half-edges, then
// every row they own from other block holders. Each owned node's
// neighbours and values, in global-id order, against the edge list; with the
// build's 32-bit ids (the default below 2^31 nodes) and its 64-bit ones
// (SNL_TEST_SETUP_IDS=64).
static void check_edges_held_by_one_rank() {
  const int P = world_size(), me = world_rank();
  const GlobalId n = 4000;
  std::vector<int> owner(n);
  for (GlobalId v = 0; v < n; ++v) owner[v] = static_cast<int>((v * 7 + v / 3) % P);
  std::vector<std::vector<std::pair<GlobalId, double>>> want(n);
  std::vector<GlobalId> edges;
  std::vector<double> vals;
  for (GlobalId v = 0; v < n; ++v)
    for (const GlobalId u : {v + 1, v + 61}) {  // a band: (v, v + 1) and (v, v + 61)
      if (u >= n) continue;
      const double a = 1.0 + 0.5 * v + 0.25 * u, b = -static_cast<double>(v * 3 + u);
      want[v].push_back({u, a});
      want[u].push_back({v, a});
      if (me != 0) continue;
      edges.insert(edges.end(), {v % 2 ? u : v, v % 2 ? v : u});  // either end first
      vals.insert(vals.end(), {a, b});
    }
  const DistGraph g(MPI_COMM_WORLD, n, owner, std::move(edges), std::move(vals), 2, 2);
  long long owned = g.num_owned(), total = 0;
  MPI_Allreduce(&owned, &total, 1, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_EQ(total, static_cast<long long>(n));
  for (LocalId v = 0; v < g.num_owned(); ++v) {
    const GlobalId gv = g.global_id(v);
    EXPECT_EQ(owner[gv], me);
    auto w = want[gv];
    std::sort(w.begin(), w.end());
    ASSERT_EQ(g.offsets()[v + 1] - g.offsets()[v], static_cast<std::int64_t>(w.size())) << gv;
    for (std::size_t t = 0; t < w.size(); ++t) {
      const auto k = static_cast<std::size_t>(g.offsets()[v]) + t;
      EXPECT_EQ(g.global_id(g.adjacency()[k]), w[t].first);
      EXPECT_EQ(g.edge_values()[2 * k], w[t].second);
      const GlobalId lo = std::min(gv, w[t].first), hi = std::max(gv, w[t].first);
      EXPECT_EQ(g.edge_values()[2 * k + 1], -static_cast<double>(lo * 3 + hi));
    }
  }
}

// Edge values of 0 to 4 per edge (the block rows copy widths 0, 1 and 2 by
// fixed-width code, others by a loop): each entry of an owned row holds its
// pair's values, whichever rank gave the pair and in which orientation.
TEST(DistGraph, EdgeValuesOfAnyWidthReachBothEnds) {
  constexpr GlobalId n = 97;
  const int rank = world_rank(), size = world_size();
  auto value = [](GlobalId a, GlobalId b, int c) { return double(std::min(a, b) * 1000 + std::max(a, b)) + 0.25 * c; };
  std::vector<int> owner(n);
  for (GlobalId g = 0; g < n; ++g) owner[g] = int((g * 7) % size);
  for (int width = 0; width <= 4; ++width) {
    std::vector<GlobalId> edges;
    std::vector<double> values;
    for (GlobalId a = 0; a < n; ++a)
      for (GlobalId d : {1, 5, 31}) {
        const GlobalId b = (a + d) % n;
        if (int((a + b) % size) != rank) continue;  // each pair from one rank, some written high end first
        edges.insert(edges.end(), {d == 5 ? b : a, d == 5 ? a : b});
        for (int c = 0; c < width; ++c) values.push_back(value(a, b, c));
      }
    const DistGraph g(MPI_COMM_WORLD, n, owner, edges, values, width, 2);
    EXPECT_EQ(g.edge_width(), width);
    // No ASSERT before the collectives below and the next width's build: a
    // rank returning early would leave the others waiting. The first wrong
    // value is reported.
    std::int64_t checked = 0;
    bool ok = true;
    for (LocalId v = 0; v < g.num_owned() && ok; ++v)
      for (auto e = g.offsets()[v]; e < g.offsets()[v + 1] && ok; ++e, ++checked)
        for (int c = 0; c < width && ok; ++c) {
          const double want = value(g.global_id(v), g.global_id(g.adjacency()[e]), c);
          ok = g.edge_value(e, c) == want;
          EXPECT_EQ(g.edge_value(e, c), want) << "width " << width << ", row " << g.global_id(v) << ", value " << c;
        }
    long long total = checked;
    MPI_Allreduce(MPI_IN_PLACE, &total, 1, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
    EXPECT_EQ(total, 6 * n) << "width " << width;  // three pairs per node, in the rows of both ends
  }
}

TEST(DistGraph, EdgesHeldByOneRankReachTheirOwners) {
  check_edges_held_by_one_rank();
  setenv("SNL_TEST_SETUP_IDS", "64", 1);
  check_edges_held_by_one_rank();
  unsetenv("SNL_TEST_SETUP_IDS");
}

// The setup with 32-bit ids in its temporaries (the merge's rows, the graph
// build's records and lists) and with 64-bit ones (SNL_TEST_SETUP_IDS=64), on a
// network with sigmas and duplicate pairs (some written the other way
// round): the same merge, local numbering, CSR, values, sigmas, interior,
// cut and halo; the 64-bit build's temporaries are larger on every rank (so
// the switch, set on rank 0 alone, took everywhere).
TEST(DistGraph, ThirtyTwoAndSixtyFourBitIdsGiveTheSameGraph) {
  Network w = make_network({.n = 600, .dim = 2, .radius = 0.09});
  const std::size_t ne = w.sensor_ranges.size();
  for (std::size_t e = 0; e < ne; ++e) w.sensor_sigmas.push_back(0.01 + 0.001 * (e % 5));
  for (std::size_t e = 0; e < ne; e += 7) {  // every 7th pair again, reversed, with another range and sigma
    w.sensor_edges.insert(w.sensor_edges.end(), {w.sensor_edges[2 * e + 1], w.sensor_edges[2 * e]});
    w.sensor_ranges.push_back(w.sensor_ranges[e] * 1.01);
    w.sensor_sigmas.push_back(0.02);
  }
  ProblemReport rn, rw;
  LocalizationProblem narrow(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kBfs, &rn);
  if (world_rank() == 0) setenv("SNL_TEST_SETUP_IDS", "64", 1);  // on one rank: every rank must take 64 bits
  LocalizationProblem wide(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kBfs, &rw);
  unsetenv("SNL_TEST_SETUP_IDS");
  EXPECT_EQ(rn.merged.merged_sensor_pairs, static_cast<GlobalId>((ne + 6) / 7));
  EXPECT_EQ(rw.merged.merged_sensor_pairs, rn.merged.merged_sensor_pairs);
  EXPECT_EQ(rn.num_sensor_edges, static_cast<GlobalId>(ne));
  EXPECT_TRUE(narrow.has_sensor_sigmas());
  EXPECT_EQ(narrow.sensor_sigmas(), wide.sensor_sigmas());
  DistGraph& a = narrow.graph();
  DistGraph& b = wide.graph();
  EXPECT_EQ(a.local_to_global(), b.local_to_global());
  EXPECT_EQ(a.offsets(), b.offsets());
  EXPECT_EQ(a.adjacency(), b.adjacency());
  EXPECT_EQ(a.edge_values(), b.edge_values());
  EXPECT_EQ(a.num_interior(), b.num_interior());
  EXPECT_EQ(a.edge_cut(), b.edge_cut());
  EXPECT_EQ(a.halo().memory_bytes(), b.halo().memory_bytes());
  EXPECT_LT(a.build_peak_bytes(), b.build_peak_bytes());
  if (world_size() > 1) EXPECT_GT(a.num_ghosts(), 0) << "no ghosts: the halo is not compared";
  std::vector<double> fa(std::size_t(a.num_local()), -1.0), fb(std::size_t(b.num_local()), -2.0);
  for (LocalId v = 0; v < a.num_owned(); ++v) fa[v] = fb[v] = double(a.global_id(v));
  a.halo().exchange(fa.data(), 1);
  b.halo().exchange(fb.data(), 1);
  EXPECT_EQ(fa, fb);
}

// Two builds of one graph are the same: numbering, CSR, values, interior, cut.
static void expect_same_graph(const DistGraph& a, const DistGraph& b, const std::string& how) {
  EXPECT_EQ(a.local_to_global(), b.local_to_global()) << how << " rank " << world_rank();
  EXPECT_EQ(a.offsets(), b.offsets()) << how;
  EXPECT_EQ(a.adjacency(), b.adjacency()) << how;
  EXPECT_EQ(a.edge_values(), b.edge_values()) << how;
  EXPECT_EQ(a.num_interior(), b.num_interior()) << how;
  EXPECT_EQ(a.edge_cut(), b.edge_cut()) << how;
}

// The rows' neighbours learn their directory slots either from whole blocks
// of the directory or by asking for each id (NeighbourSlots, src/graph/
// dist_graph.cpp); SNL_TEST_SETUP_SLOTS forces one way on the rank that sets it.
// Every way, and ranks that mix them, give the same graph.
TEST(DistGraph, NeighbourSlotsSentWholeOrAskedGiveTheSameGraph) {
  const Network w = make_network({.n = 700, .dim = 2, .radius = 0.08});
  auto build = [&](const char* how, bool only_rank0) {
    if (how && (!only_rank0 || world_rank() == 0)) setenv("SNL_TEST_SETUP_SLOTS", how, 1);
    LocalizationProblem p(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kBfs, nullptr);
    unsetenv("SNL_TEST_SETUP_SLOTS");
    return p;
  };
  const LocalizationProblem base = build(nullptr, false);
  const DistGraph& a = base.graph();
  if (world_size() > 1) EXPECT_GT(a.num_ghosts(), 0) << "no ghosts: the slots of other blocks are not used";
  for (const auto& [how, only0] : {std::pair{"ask", false}, {"block", false}, {"ask", true}, {"block", true}}) {
    const LocalizationProblem other = build(how, only0);
    expect_same_graph(a, other.graph(), how);
  }
}

// The entries and the values leave for their owners in rounds of at most
// SNL_TEST_SETUP_ROUND_BYTES per rank (dist_graph.cpp, Rounds; 64 MiB unless
// set); any round size, set on one rank or all, with the slots sent whole or
// asked (asked slots are answered in the order the rounds read them), gives
// the same graph and values.
TEST(DistGraph, RowsSentInRoundsGiveTheSameGraph) {
  Network w = make_network({.n = 700, .dim = 2, .radius = 0.08});
  for (std::size_t e = 0; e < w.sensor_ranges.size(); ++e) w.sensor_sigmas.push_back(0.01 + 0.001 * double(e % 7));
  auto build = [&](const char* bytes, bool only_rank0, const char* slots) {
    if (bytes && (!only_rank0 || world_rank() == 0)) setenv("SNL_TEST_SETUP_ROUND_BYTES", bytes, 1);
    if (slots) setenv("SNL_TEST_SETUP_SLOTS", slots, 1);
    LocalizationProblem p(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kBfs, nullptr);
    unsetenv("SNL_TEST_SETUP_ROUND_BYTES");
    unsetenv("SNL_TEST_SETUP_SLOTS");
    return p;
  };
  const LocalizationProblem base = build(nullptr, false, nullptr);
  const DistGraph& a = base.graph();
  if (world_size() > 1) EXPECT_GT(a.num_ghosts(), 0) << "no ghosts: nothing is sent in rounds";
  ASSERT_EQ(a.edge_values().size(), std::size_t(a.offsets().back()));
  for (const char* bytes : {"1", "40", "1000"})
    for (const bool only0 : {false, true})
      for (const char* slots : {static_cast<const char*>(nullptr), "ask"}) {
        const LocalizationProblem other = build(bytes, only0, slots);
        const std::string how = std::string(bytes) + (only0 ? " on rank 0" : "") + (slots ? " asked" : "");
        expect_same_graph(a, other.graph(), how);
        EXPECT_EQ(base.sensor_sigmas(), other.sensor_sigmas()) << how;
      }
}

// Duplicate measurements (either orientation, on any rank) merge in the
// rows of both ends (BlockRows::from_pairs) into exactly the serial merge's
// range and sigma (merge_duplicates): each owned node's edge to a neighbour
// carries the merged pair's values, bit for bit.
TEST(DistGraph, DuplicatesMergeInTheRowsAsTheSerialMerge) {
  Network w = make_network({.n = 500, .dim = 2, .radius = 0.1});
  const std::size_t ne = w.sensor_ranges.size();
  for (std::size_t e = 0; e < ne; ++e) w.sensor_sigmas.push_back(0.01 + 0.001 * double(e % 5));
  for (std::size_t e = 0; e < ne; e += 3) {  // every 3rd pair again (reversed on odd e), twice for some
    for (int copy = 0; copy < (e % 9 == 0 ? 2 : 1); ++copy) {
      const bool rev = (e + copy) % 2 == 1;
      w.sensor_edges.insert(w.sensor_edges.end(), {w.sensor_edges[2 * e + (rev ? 1 : 0)],
                                                   w.sensor_edges[2 * e + (rev ? 0 : 1)]});
      w.sensor_ranges.push_back(w.sensor_ranges[e] * (1.0 + 0.013 * (copy + 1)));
      w.sensor_sigmas.push_back(0.02 + 0.005 * copy);
    }
  }
  w.total_sensor_edges = w.local_sensor_edges();
  std::vector<GlobalId> se = w.sensor_edges, ae;
  std::vector<double> sr = w.sensor_ranges, ss = w.sensor_sigmas, ar;
  const MergeStats ms = merge_duplicates(se, sr, MeasurementExtras{&ss, nullptr}, ae, ar, MeasurementExtras{});
  std::map<std::pair<GlobalId, GlobalId>, std::pair<double, double>> pair_values;
  for (std::size_t e = 0; e < sr.size(); ++e) pair_values[{se[2 * e], se[2 * e + 1]}] = {sr[e], ss[e]};
  ProblemReport rep;
  const LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kBfs, &rep);
  EXPECT_GT(ms.merged_sensor_pairs, 0);
  EXPECT_EQ(rep.merged.merged_sensor_pairs, ms.merged_sensor_pairs);
  EXPECT_EQ(rep.num_sensor_edges, static_cast<GlobalId>(sr.size()));
  const DistGraph& g = prob.graph();
  for (LocalId v = 0; v < g.num_owned(); ++v)
    for (auto k = g.offsets()[v]; k < g.offsets()[v + 1]; ++k) {
      const GlobalId a = g.global_id(v), b = g.global_id(g.adjacency()[k]);
      const auto it = pair_values.find({std::min(a, b), std::max(a, b)});
      ASSERT_NE(it, pair_values.end()) << a << "-" << b;
      EXPECT_EQ(g.edge_value(k), it->second.first) << a << "-" << b << " rank " << world_rank();
      EXPECT_EQ(prob.sensor_sigmas()[k], it->second.second) << a << "-" << b << " rank " << world_rank();
    }
}

// DeltaHalo (src/graph/delta_halo.cpp): one exchange delivers exactly the
// marked owned rows, with their tags, to the ranks that hold them as ghosts;
// rows changed but not marked stay as they were on the receivers; the bytes are
// the marked rows' and the headers'; the pairs stop once both ends send the stop clock.
TEST(DeltaHalo, SendsOnlyTheMarkedRowsWithTheirTags) {
  const Network w = make_network({.n = 200, .dim = 2, .radius = 0.15});
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  auto& g = prob.graph();
  std::vector<double> f(std::size_t(g.num_local()) * 2, -1.0);
  for (LocalId v = 0; v < g.num_owned(); ++v) {
    f[2 * v] = double(g.global_id(v));
    f[2 * v + 1] = -double(g.global_id(v));
  }
  g.halo().exchange(f.data(), 2);
  std::vector<std::int64_t> tags(std::size_t(g.num_local()), -1);
  DeltaHalo dh(g.halo(), 2);
  dh.reset(0, 1);
  EXPECT_EQ(dh.done(), dh.num_neighbors() == 0);
  // Every owned row changes; those of ids divisible by 3 are marked (twice: once counts).
  for (LocalId v = 0; v < g.num_owned(); ++v) {
    const GlobalId id = g.global_id(v);
    f[2 * v] = double(id) + 0.5;
    f[2 * v + 1] = 7.0;
    tags[v] = 10 * id;
    if (id % 3 == 0) {
      dh.mark(v);
      dh.mark(v);
    }
  }
  std::int64_t expect_bytes = 0;
  for (int r = 0; r < g.halo().num_neighbors(); ++r) {
    std::int64_t rows = 0;
    for (LocalId j = 0; j < g.halo().send_count(r); ++j) rows += g.global_id(g.halo().send_ids(r)[j]) % 3 == 0;
    expect_bytes += (2 + rows * (2 + 2)) * std::int64_t(sizeof(double));
  }
  dh.exchange(f.data(), tags.data(), 1);
  EXPECT_EQ(dh.bytes_sent(), expect_bytes);
  int changed = 0;
  for (LocalId v = g.num_owned(); v < g.num_local(); ++v) {
    const GlobalId id = g.global_id(v);
    if (id % 3 == 0) {
      ++changed;
      EXPECT_EQ(f[2 * v], double(id) + 0.5) << id;
      EXPECT_EQ(f[2 * v + 1], 7.0) << id;
      EXPECT_EQ(tags[v], 10 * id) << id;
    } else {
      EXPECT_EQ(f[2 * v], double(id)) << id;
      EXPECT_EQ(f[2 * v + 1], -double(id)) << id;
      EXPECT_EQ(tags[v], -1) << id;
    }
  }
  if (world_size() > 1) EXPECT_GT(changed, 0) << "no marked ghost: the exchange is not tested";
  for (int r = 0; r < dh.num_neighbors(); ++r) EXPECT_EQ(dh.clock_of(r), 1);
  EXPECT_TRUE(dh.done());
  // Nothing marked since: a new round (after reset) sends headers only.
  dh.reset(1, 2);
  const auto b0 = dh.bytes_sent();
  dh.exchange(f.data(), tags.data(), 2);
  EXPECT_EQ(dh.bytes_sent() - b0, 2 * std::int64_t(sizeof(double)) * dh.num_neighbors());
  EXPECT_TRUE(dh.done());
}
