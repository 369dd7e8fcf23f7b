// Halo exchange and distributed graph (src/graph): ghosts receive their
// owners' values, interior nodes have no ghost neighbours, neighbour lists are
// in global-id order, and the owned nodes of all ranks add up to the network.
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
