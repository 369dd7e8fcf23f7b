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
