// The sequential methods run in parallel (src/solvers/pm.cpp, async.cpp):
// the distributed Jones-Plassmann colouring equals the serial one, and PM and
// async / async-exact give the iterates of their one-at-a-time reference.
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
