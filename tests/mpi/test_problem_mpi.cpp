// The distributed problem (src/problem/problem.cpp): duplicate rows merged,
// anchor measurements moved to the ranks that own their sensors.
#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cstdint>

#include "graph/partition_detail.hpp"
#include "snl/io/network.hpp"
#include "snl/problem/analysis.hpp"
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

TEST(Problem, MergesDuplicatesAndMovesAnchorsToOwners) {
  NetSpec s;
  s.n = 60;
  s.duplicates = true;
  const Network w = make_network(s);
  ProblemReport rep;
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kBlock, &rep);
  EXPECT_GT(rep.merged.merged_sensor_pairs, 0);
  const Network m = merged(w);
  EXPECT_EQ(rep.num_sensor_edges, m.local_sensor_edges());
  EXPECT_EQ(rep.num_anchor_edges, m.local_anchor_edges());
  long long a = static_cast<long long>(prob.anchor_ids().size()), at = 0;
  MPI_Allreduce(&a, &at, 1, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_EQ(at, m.local_anchor_edges());
}

// A slab moved in is emptied of its measurement lists once they are merged
// (their memory goes back to the setup), keeps the truth rows the problem
// reads after that, and gives the problem built from a copy: the same local
// numbering, graph, ranges, sigmas and anchor measurements on every rank;
// with and without per-measurement sigmas (the graph build's two routes).
TEST(Problem, MovedSlabIsFreedAfterTheMergeAndGivesTheSameProblem) {
  for (bool sigmas : {false, true}) {
    NetSpec s;
    s.n = 80;
    s.duplicates = true;
    Network w = make_network(s);
    if (sigmas) {
      for (std::size_t e = 0; e < w.sensor_ranges.size(); ++e) w.sensor_sigmas.push_back(0.01 + 0.001 * (e % 7));
      for (std::size_t e = 0; e < w.anchor_ranges.size(); ++e) w.anchor_sigmas.push_back(0.02 + 0.001 * (e % 5));
    }
    const Network copy = slab_of(w, MPI_COMM_WORLD);
    Network moved = slab_of(w, MPI_COMM_WORLD);
    EXPECT_GT(moved.sensor_edges.size(), 0u);  // every rank's slab has rows to free
    const LocalizationProblem a(MPI_COMM_WORLD, copy, PartitionMethod::kMetis, nullptr);
    const LocalizationProblem b(MPI_COMM_WORLD, std::move(moved), PartitionMethod::kMetis, nullptr);
    EXPECT_EQ(moved.sensor_edges.capacity() + moved.sensor_ranges.capacity() + moved.sensor_sigmas.capacity(), 0u);
    EXPECT_EQ(moved.anchor_edges.capacity() + moved.anchor_ranges.capacity() + moved.anchor_sigmas.capacity(), 0u);
    EXPECT_EQ(moved.truth, copy.truth);
    EXPECT_EQ(a.num_local(), b.num_local());  // (no ASSERT: the other ranks would wait in the next collective)
    for (LocalId v = 0; v < std::min(a.num_local(), b.num_local()); ++v)
      EXPECT_EQ(a.graph().global_id(v), b.graph().global_id(v));
    EXPECT_EQ(a.graph().offsets(), b.graph().offsets());
    EXPECT_EQ(a.graph().adjacency(), b.graph().adjacency());
    EXPECT_EQ(a.graph().edge_values(), b.graph().edge_values());
    EXPECT_EQ(a.has_sensor_sigmas(), sigmas);
    EXPECT_EQ(a.sensor_sigmas(), b.sensor_sigmas());
    EXPECT_EQ(a.anchor_ids(), b.anchor_ids());
    EXPECT_EQ(a.anchor_ranges(), b.anchor_ranges());
    EXPECT_EQ(a.truth(), b.truth());
  }
}

// The merge keeps each rank's own rows out of the exchange and puts them
// back in its rank's place among the received ones: a sorted network and the
// same rows in reverse order, each pair written the other way round (which
// merge_duplicates must sort), give the same problem, with every pair once.
TEST(Problem, SortedAndReversedRowsGiveTheSameProblem) {
  NetSpec s;
  s.n = 90;
  Network w = make_network(s);
  for (std::size_t e = 0; e < w.sensor_ranges.size(); ++e) w.sensor_sigmas.push_back(0.01 + 0.001 * (e % 7));
  Network rev = w;
  const std::size_t ne = w.sensor_ranges.size();
  for (std::size_t e = 0; e < ne; ++e) {
    rev.sensor_edges[2 * e] = w.sensor_edges[2 * (ne - 1 - e) + 1];
    rev.sensor_edges[2 * e + 1] = w.sensor_edges[2 * (ne - 1 - e)];
    rev.sensor_ranges[e] = w.sensor_ranges[ne - 1 - e];
    rev.sensor_sigmas[e] = w.sensor_sigmas[ne - 1 - e];
  }
  ProblemReport ra, rb;
  const LocalizationProblem a(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, &ra);
  const LocalizationProblem b(MPI_COMM_WORLD, slab_of(rev, MPI_COMM_WORLD), PartitionMethod::kMetis, &rb);
  EXPECT_EQ(ra.num_sensor_edges, static_cast<std::int64_t>(ne));
  EXPECT_EQ(rb.num_sensor_edges, static_cast<std::int64_t>(ne));
  EXPECT_EQ(ra.merged.merged_sensor_pairs, 0);
  EXPECT_EQ(a.num_local(), b.num_local());
  for (LocalId v = 0; v < std::min(a.num_local(), b.num_local()); ++v)
    EXPECT_EQ(a.graph().global_id(v), b.graph().global_id(v));
  EXPECT_EQ(a.graph().offsets(), b.graph().offsets());
  EXPECT_EQ(a.graph().adjacency(), b.graph().adjacency());
  EXPECT_EQ(a.graph().edge_values(), b.graph().edge_values());
  EXPECT_EQ(a.sensor_sigmas(), b.sensor_sigmas());
  // Every pair's range at both its ends, against the file.
  for (LocalId v = 0; v < a.graph().num_owned(); ++v)
    for (auto k = a.graph().offsets()[v]; k < a.graph().offsets()[v + 1]; ++k) {
      GlobalId i = a.graph().global_id(v), j = a.graph().global_id(a.graph().adjacency()[k]);
      if (i > j) std::swap(i, j);
      std::size_t e = 0;
      while (e < ne && !(w.sensor_edges[2 * e] == i && w.sensor_edges[2 * e + 1] == j)) ++e;
      EXPECT_LT(e, ne) << i << " " << j;  // (no ASSERT: the destructors free communicators)
      if (e == ne) continue;
      EXPECT_EQ(a.graph().edge_values()[k], w.sensor_ranges[e]);
      EXPECT_EQ(a.sensor_sigmas()[k], w.sensor_sigmas[e]);
    }
}

// Truth and the file's flags reach the owners of their sensors: pushed by
// the block holders where every slab holds its directory block's rows (as
// network_slab deals them), asked for where one rank holds every row. Both
// against the whole network, row by row, on bfs and METIS partitions.
TEST(Problem, TruthAndFlagsReachTheOwnersFromAnySlab) {
  const int rank = world_rank();
  NetSpec s;
  s.n = 3000;  // a directory block of over a thousand rows per rank
  s.radius = 0.05;
  Network w = make_network(s);
  w.localizability.assign(static_cast<std::size_t>(w.num_sensors), 0);
  for (GlobalId g = 0; g < w.num_sensors; g += 3) w.localizability[g] = kNotRigid;  // a bit no test of the setup sets
  Network on_root = rank == 0 ? w : Network{};
  if (rank != 0) {  // an empty slab after every row
    on_root.dim = w.dim;
    on_root.num_sensors = w.num_sensors;
    on_root.anchors = w.anchors;
    on_root.sigma = w.sigma;
    on_root.has_truth = true;
    on_root.sensor_edge_offset = w.local_sensor_edges();
    on_root.anchor_edge_offset = w.local_anchor_edges();
    on_root.sensor_row_offset = w.num_sensors;
  }
  for (const PartitionMethod pm : {PartitionMethod::kBfs, PartitionMethod::kMetis})
    for (const Network* slab : {&w, &on_root}) {
      const LocalizationProblem prob(MPI_COMM_WORLD, slab == &w ? slab_of(w, MPI_COMM_WORLD) : on_root, pm, nullptr);
      const auto n_owned = static_cast<std::size_t>(prob.graph().num_owned());
      EXPECT_EQ(prob.truth().size(), n_owned * 2);  // (no ASSERT: the other ranks go on to collectives)
      EXPECT_EQ(prob.flags().size(), n_owned);
      int bad = 0;
      for (LocalId v = 0; v < prob.graph().num_owned() && prob.truth().size() == n_owned * 2 &&
                          prob.flags().size() == n_owned; ++v) {
        const GlobalId g = prob.graph().global_id(v);
        bad += prob.truth()[2 * v] != w.truth[2 * g] || prob.truth()[2 * v + 1] != w.truth[2 * g + 1];
        bad += (prob.flags()[v] & kNotRigid) != w.localizability[g];
      }
      EXPECT_EQ(bad, 0) << "rank " << rank << (slab == &w ? ", block slabs" : ", every row on rank 0");
    }
}

// The connectivity report run by every rank (components of the owned
// subgraph joined over the cut on rank 0) against the serial analysis: a
// sparse network of many components, some within reach of the corner
// anchors and some not, on bfs, METIS and block partitions.
TEST(Problem, ConnectivityFlagsEqualTheSerialAnalysis) {
  NetSpec s;
  s.n = 3000;
  s.radius = 0.025;  // mean degree about 6: hundreds of components
  s.anchor_radius = 0.25;
  const Network w = make_network(s);
  const LocalizabilityReport serial = analyze_localizability(w, false);
  ASSERT_GT(serial.unanchored_components, 10);
  ASSERT_LT(serial.unanchored.size(), static_cast<std::size_t>(s.n / 2));
  constexpr std::uint8_t kMask = kUnanchoredComponent | kFewMeasurements;
  for (const PartitionMethod pm : {PartitionMethod::kBfs, PartitionMethod::kMetis, PartitionMethod::kBlock}) {
    const LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), pm, nullptr);
    int bad = 0;
    for (LocalId v = 0; v < prob.graph().num_owned(); ++v) {
      const GlobalId g = prob.graph().global_id(v);
      bad += (prob.flags()[v] & kMask) != (serial.flags[g] & kMask);
    }
    EXPECT_EQ(bad, 0) << "rank " << world_rank() << ", partition " << static_cast<int>(pm);
  }
}

// The serial twin of the partition's graph: every pair's two half-edges
// counted, scattered and each row sorted, on the whole pair list at once.
static void reference_root_csr(GlobalId n, const std::vector<GlobalId>& pairs, std::vector<std::int64_t>& xadj,
                               std::vector<std::int32_t>& adjncy) {
  xadj.assign(static_cast<std::size_t>(n) + 1, 0);
  adjncy.assign(pairs.size(), 0);
  for (const GlobalId v : pairs) ++xadj[v + 1];
  for (GlobalId v = 0; v < n; ++v) xadj[v + 1] += xadj[v];
  std::vector<std::int64_t> fill(xadj.begin(), xadj.end() - 1);
  for (std::size_t k = 0; k < pairs.size(); k += 2) {
    adjncy[fill[pairs[k]]++] = static_cast<std::int32_t>(pairs[k + 1]);
    adjncy[fill[pairs[k + 1]]++] = static_cast<std::int32_t>(pairs[k]);
  }
  for (GlobalId v = 0; v < n; ++v) std::sort(adjncy.begin() + xadj[v], adjncy.begin() + xadj[v + 1]);
}

// The partition's graph on rank 0, built by the block holders of its rows,
// equals the serial twin's on the whole pair list: with pairs dealt to the
// ranks round robin (both ends anywhere) and by the block of their first end
// (the merged measurements' layout, where only cut half-edges move); with
// duplicate pairs, both orders of a pair, nodes of no pair, and more ranks
// than nodes.
TEST(Partition, RootGraphEqualsTheSerialTwin) {
  const int size = world_size(), rank = world_rank();
  // 5000 nodes: blocks of over 1024 rows, which block_rows buckets several rows at a time.
  for (const GlobalId n : {GlobalId{1}, GlobalId{2}, GlobalId{97}, GlobalId{5000}}) {
    std::vector<GlobalId> pairs;
    std::uint64_t x = 12345;
    auto next = [&] { return x = x * 6364136223846793005ULL + 1442695040888963407ULL, (x >> 33); };
    for (int k = 0; k < (n > 1000 ? 40000 : 300) && n > 1; ++k) {
      const GlobalId a = static_cast<GlobalId>(next() % static_cast<std::uint64_t>(n * 3 / 4 + 1));
      GlobalId b = static_cast<GlobalId>(next() % static_cast<std::uint64_t>(n));
      if (b == a) b = (a + 1) % n;
      pairs.insert(pairs.end(), {a, b});
      if (k % 10 == 0) pairs.insert(pairs.end(), {b, a});  // the same pair again, reversed
      if (k % 13 == 0) pairs.insert(pairs.end(), {a, b});  // a duplicate
    }
    std::vector<std::int64_t> want_x;
    std::vector<std::int32_t> want_a;
    reference_root_csr(n, pairs, want_x, want_a);
    for (const bool by_block : {false, true}) {
      std::vector<GlobalId> mine;
      for (std::size_t k = 0; k < pairs.size(); k += 2) {
        const int to = by_block ? block_owner(n, size, pairs[k]) : static_cast<int>((k / 2) % size);
        if (to == rank) mine.insert(mine.end(), {pairs[k], pairs[k + 1]});
      }
      std::vector<std::int64_t> xadj;
      std::vector<std::int32_t> adjncy;
      std::int64_t peak = 0;
      EXPECT_EQ(detail::root_csr(MPI_COMM_WORLD, n, mine, xadj, adjncy, peak), "");
      if (rank == 0) {
        EXPECT_EQ(xadj, want_x) << "n = " << n << (by_block ? ", pairs by block" : ", pairs round robin");
        EXPECT_EQ(adjncy, want_a) << "n = " << n << (by_block ? ", pairs by block" : ", pairs round robin");
        EXPECT_GE(peak, static_cast<std::int64_t>(want_x.size() * 8 + want_a.size() * 4));
      } else {
        EXPECT_TRUE(xadj.empty() && adjncy.empty());
      }
    }
  }
}
