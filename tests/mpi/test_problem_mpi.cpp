// The distributed problem (src/problem/problem.cpp): duplicate rows merged,
// anchor measurements moved to the ranks that own their sensors.
#include <gtest/gtest.h>
#include <mpi.h>

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
