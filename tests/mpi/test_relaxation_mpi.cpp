// The disk relaxation (003, Alg. 1; src/solvers/relaxation.cpp): the same
// iterates as the serial reference twin on any number of ranks, the Nesterov
// rate, and exact recovery where the relaxation is tight.
#include <gtest/gtest.h>
#include <mpi.h>

#include "reference/reference.hpp"
#include "snl/problem/metrics.hpp"
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

TEST(Relaxation, MatchesSerialReference) {
  NetSpec s;
  s.duplicates = true;
  const Network w = make_network(s);
  const Network m = merged(w);
  const auto x = run(MPI_COMM_WORLD, w, "relaxation", 60);
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  const auto x0 = allgather_positions(prob, random_initial_positions(prob, 3));
  const auto xr = reference::nesterov(m, x0, 60);
  ASSERT_EQ(x.size(), xr.size());
  for (std::size_t t = 0; t < x.size(); ++t) EXPECT_NEAR(x[t], xr[t], 1e-12) << t;
}

TEST(Relaxation, ConvergesAtTheNesterovRate) {
  // f_hat(x(k)) - f_hat* <= 2 L ||x(0) - x*||^2 / (k+1)^2 (003, Sec. IV-B), for
  // the solver's iterates x(k); f_hat* and x* from the reference twin.
  const Network w = merged(make_network({.n = 50, .dim = 2, .radius = 0.3, .anchor_radius = 0.3, .sigma = 0.05}));
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  const auto x0 = allgather_positions(prob, random_initial_positions(prob, 3));
  const double L = reference::relaxation_lipschitz(w);
  EXPECT_EQ(L, relaxation_lipschitz(prob));
  const auto xstar = reference::nesterov(w, x0, 20000);
  const double fstar = reference::relaxed_cost(w, xstar);
  double r2 = 0;
  for (std::size_t t = 0; t < x0.size(); ++t) r2 += (x0[t] - xstar[t]) * (x0[t] - xstar[t]);
  for (int k : {1, 2, 5, 10, 50, 100, 500, 1000}) {
    const auto xk = run(MPI_COMM_WORLD, w, "relaxation", k);
    EXPECT_LE(reference::relaxed_cost(w, xk) - fstar, 2 * L * r2 / ((k + 1.0) * (k + 1.0)) + 1e-12) << k;
  }
}

TEST(Relaxation, NoiselessFullAnchorNetworkIsRecoveredExactly) {
  // Every sensor measures every anchor and sigma = 0: the relaxation is tight.
  const Network w = make_network({.n = 30, .dim = 2, .radius = 0.35, .anchor_radius = 2.0, .sigma = 0.0});
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  SolverOptions opt;
  opt.algorithm = "relaxation";
  opt.max_iter = 20000;
  opt.stop = "papers";
  opt.tol = 1e-13;
  Solver solver(prob, opt);
  const Summary s = solver.solve(random_initial_positions(prob, 1), nullptr);
  EXPECT_LT(s.errors.rmse, 1e-6);
  EXPECT_LT(s.costs.certificate, 1e-10);
  EXPECT_LT(s.gap_certificate, 1e-10);
  EXPECT_GT(s.costs.apriori, 1.0);
}
