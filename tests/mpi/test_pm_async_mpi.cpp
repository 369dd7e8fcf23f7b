// The sequential methods run in parallel (src/solvers/pm.cpp, async.cpp):
// the distributed Jones-Plassmann colouring equals the serial one, and PM and
// async / async-exact give the iterates of their one-at-a-time reference.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cstring>

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

TEST(SequentialMethods, PMAndAsyncMatchTheirOneAtATimeReference) {
  const Network w = merged(make_network({.n = 70, .dim = 2, .radius = 0.25, .anchor_radius = 0.4, .sigma = 0.05}));
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  const auto x0 = allgather_positions(prob, random_initial_positions(prob, 3));
  // Colours: neighbours differ, and the distributed colouring equals the serial one.
  const auto col = jones_plassmann_coloring(prob.graph());
  const auto ref_col = reference::coloring(w);
  for (LocalId v = 0; v < prob.num_owned(); ++v) {
    EXPECT_EQ(col[v], ref_col[prob.graph().global_id(v)]);
    for (auto e = prob.graph().offsets()[v]; e < prob.graph().offsets()[v + 1]; ++e)
      EXPECT_NE(col[v], col[prob.graph().adjacency()[e]]);
  }
  const auto xp = run(MPI_COMM_WORLD, w, "pm", 25);
  const auto xpr = reference::pm(w, x0, 25);
  ASSERT_EQ(xp.size(), xpr.size());
  for (std::size_t t = 0; t < xp.size(); ++t) EXPECT_NEAR(xp[t], xpr[t], 1e-12) << t;
  for (bool exact : {false, true}) {
    const auto xa = run(MPI_COMM_WORLD, w, exact ? "async-exact" : "async", 6);
    // SolverOptions::seed (1 by default) keys the activation sequence.
    const auto xar = reference::async(w, x0, 6 * w.num_sensors, 1, exact);
    ASSERT_EQ(xa.size(), xar.size());
    for (std::size_t t = 0; t < xa.size(); ++t) EXPECT_NEAR(xa[t], xar[t], 1e-10) << t << (exact ? " exact" : "");
  }
}

// The replay (async.cpp: each rank at its own clock, rows sent when they
// changed): the bits of the one-at-a-time order on every rank count and
// partition, 2D and 3D, on networks whose boundary rows are activated often
// (the block partition cuts many edges; three ranks make ranks wait on two
// neighbours). Sub-communicators of 1..size ranks in one run.
TEST(SequentialMethods, AsyncReplayGivesTheSequentialBits) {
  struct Case {
    NetSpec spec;
    PartitionMethod pm;
    int iters;
  };
  const Case cases[] = {
      {{.n = 300, .dim = 2, .radius = 0.12, .anchor_radius = 0.3, .sigma = 0.05}, PartitionMethod::kMetis, 4},
      {{.n = 200, .dim = 2, .radius = 0.15, .anchor_radius = 0.3, .sigma = 0.05}, PartitionMethod::kBlock, 5},
      {{.n = 120, .dim = 3, .radius = 0.35, .anchor_radius = 0.4, .sigma = 0.05}, PartitionMethod::kMetis, 3},
  };
  for (const Case& c : cases) {
    const Network w = merged(make_network(c.spec));
    std::vector<double> x0;
    {
      LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), c.pm, nullptr);
      x0 = allgather_positions(prob, random_initial_positions(prob, 3));
    }
    for (bool exact : {false, true}) {
      const char* alg = exact ? "async-exact" : "async";
      const auto ref = reference::async(w, x0, long(c.iters) * w.num_sensors, 1, exact);
      for (int k = 1; k <= world_size(); ++k) {
        MPI_Comm sub;
        MPI_Comm_split(MPI_COMM_WORLD, world_rank() < k ? 0 : MPI_UNDEFINED, world_rank(), &sub);
        if (sub == MPI_COMM_NULL) continue;
        const auto x = run(sub, w, alg, c.iters, c.pm);
        ASSERT_EQ(x.size(), ref.size());
        EXPECT_EQ(0, std::memcmp(x.data(), ref.data(), x.size() * sizeof(double)))
            << alg << " on " << k << " ranks, n = " << w.num_sensors << ", dim " << w.dim;
        MPI_Comm_free(&sub);
      }
    }
  }
}
