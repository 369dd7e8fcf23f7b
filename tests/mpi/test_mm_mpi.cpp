// MM (000, Alg. 1; src/solvers/mm.cpp) on 1, 2 and 3 ranks: the
// iterates of the serial reference twin, and a surrogate that never increases.
#include <gtest/gtest.h>
#include <mpi.h>

#include "reference/reference.hpp"
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

TEST(MM, MatchesSerialReferenceAndSurrogateNeverIncreases) {
  const Network w = make_network({.n = 40, .dim = 3, .radius = 0.5, .anchor_radius = 0.8, .sigma = 0.05});
  const auto x = run(MPI_COMM_WORLD, w, "mm", 50);
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  const auto x0 = allgather_positions(prob, random_initial_positions(prob, 3));
  std::vector<double> F;
  const auto xr = reference::mm(w, x0, 50, &F);
  ASSERT_EQ(x.size(), xr.size());
  for (std::size_t t = 0; t < x.size(); ++t) EXPECT_NEAR(x[t], xr[t], 1e-12) << t;
  for (std::size_t t = 1; t < F.size(); ++t) EXPECT_LE(F[t], F[t - 1] * (1 + 1e-14)) << t;
  EXPECT_LE(reference::ml_cost(w, xr), F.back() * (1 + 1e-12));  // f(x) <= F(z)
}
