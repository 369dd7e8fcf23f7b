// The distributed ESDP (src/solvers/esdp_dist.cpp): its fixed point is the
// ESDP the centralized `esdp` solves with DSDP (the oracle: the same objective
// and positions on a small noisy network; the truth on exact ranges, where the
// ESDP is tight); the iterates, history and objective are the same bits on 1,
// 2 and 3 ranks; bad options are refused.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <cstring>

#include "solve_helpers.hpp"

using namespace snl;
using snl::test::allgather_positions;
using snl::test::make_network;
using snl::test::merged;
using snl::test::slab_of;
using snl::test::world_rank;
using snl::test::world_size;

namespace {

using snl::test::method_value;
using snl::test::Outcome;

Outcome solve(MPI_Comm comm, const Network& w, const std::string& alg, std::int64_t iters, double tol = 0) {
  SolverOptions opt;
  opt.algorithm = alg;
  if (alg == "esdp-dist") {
    opt.max_iter = iters;
    opt.stop = "papers";
    opt.tol = tol;
    opt.history_every = 50;
  }
  return snl::test::solve_outcome(comm, w, opt);
}

double max_abs_diff(const std::vector<double>& a, const std::vector<double>& b) {
  double m = 0;
  for (std::size_t t = 0; t < a.size(); ++t) m = std::max(m, std::abs(a[t] - b[t]));
  return m;
}

// 12 sensors, average degree about 4 (003's network 1 has 10 and 4.3);
// all_anchors: every sensor ranged to the four corner anchors.
Network small_network(double sigma, bool all_anchors = false) {
  return merged(make_network(
      {.n = 12, .dim = 2, .radius = 0.45, .anchor_radius = all_anchors ? 2.0 : 0.45, .sigma = sigma, .seed = 5}));
}

}  // namespace

// The oracle: the centralized ESDP's objective (DSDP, relative gap 1e-9) is
// reached to 2e-3 relative after 6000 ADMM iterations (measured: 1.2e-3, and
// 1.0e-4 after 20000; ADMM's slow tail on this network, sigma = 0.2), with
// the blocks in consensus to 1e-5. The positions are compared where the ESDP
// has one solution: exact ranges to every anchor, where it is tight and its
// solution is the truth (measured after 3000 iterations: objective -1.1e-7,
// positions within 2.5e-4). Elsewhere its optimal set need not be a point, and
// DSDP and ADMM may end at different points of it.
TEST(EsdpDist, ConvergesToTheCentralizedEsdp) {
  if (world_rank() != 0) return;
  const Network w = small_network(0.2);
  const Outcome c = solve(MPI_COMM_SELF, w, "esdp", 0);
  const Outcome d = solve(MPI_COMM_SELF, w, "esdp-dist", 6000);
  const double fc = method_value(c.s, "relaxation_objective"), fd = d.s.final_cost;
  ASSERT_TRUE(std::isfinite(fc) && std::isfinite(fd));
  EXPECT_NEAR(fd, fc, 2e-3 * std::abs(fc));
  EXPECT_EQ(method_value(d.s, "relaxation_objective"), fd);
  EXPECT_LT(method_value(d.s, "consensus_residual"), 1e-5);
  EXPECT_LE(fd, d.s.costs.ml);  // a relaxation: below the ML cost at its own point

  const Network exact = small_network(0.0, true);
  const Outcome e = solve(MPI_COMM_SELF, exact, "esdp-dist", 3000);
  EXPECT_LT(std::abs(e.s.final_cost), 1e-6);
  EXPECT_LT(max_abs_diff(e.x, exact.truth), 1e-3) << "exact ranges: the ESDP is tight";
}

TEST(EsdpDist, StopsByRelativeImprovementAndCountsOneMessagePerIteration) {
  if (world_rank() != 0) return;
  const Outcome d = solve(MPI_COMM_SELF, small_network(0.2), "esdp-dist", 100000, 1e-6);
  EXPECT_EQ(d.s.termination, TerminationType::kConvergence);
  EXPECT_LT(d.s.iterations, 100000);
  EXPECT_EQ(d.s.messages_per_sensor, double(d.s.iterations));
  EXPECT_EQ(d.s.reals_per_sensor, 3.0 * d.s.iterations);  // (x_i, Y_ii), p = 2
}

TEST(EsdpDist, BitIdenticalForOneTwoThreeRanks) {
  const Network w = merged(make_network({.n = 60, .dim = 2, .radius = 0.25, .anchor_radius = 0.3, .sigma = 0.05}));
  const Outcome ref = solve(MPI_COMM_SELF, w, "esdp-dist", 150);
  for (int k = 2; k <= world_size(); ++k) {
    MPI_Comm sub;
    MPI_Comm_split(MPI_COMM_WORLD, world_rank() < k ? 0 : MPI_UNDEFINED, world_rank(), &sub);
    if (sub == MPI_COMM_NULL) continue;
    const Outcome o = solve(sub, w, "esdp-dist", 150);
    ASSERT_EQ(o.x.size(), ref.x.size());
    EXPECT_EQ(0, std::memcmp(o.x.data(), ref.x.data(), o.x.size() * sizeof(double))) << k << " ranks";
    EXPECT_EQ(o.s.final_cost, ref.s.final_cost) << k << " ranks";
    EXPECT_EQ(method_value(o.s, "consensus_residual"), method_value(ref.s, "consensus_residual")) << k << " ranks";
    ASSERT_EQ(o.s.history.size(), ref.s.history.size());
    for (std::size_t h = 0; h < o.s.history.size(); ++h) EXPECT_EQ(o.s.history[h].cost, ref.s.history[h].cost);
    MPI_Comm_free(&sub);
  }
}

TEST(EsdpDist, BadOptionsAreRefused) {
  SolverOptions o;
  o.algorithm = "esdp-dist";
  o.stop = "papers";
  EXPECT_EQ(o.validate(), "");
  for (double rho : {0.0, -1.0, double(NAN), double(INFINITY)}) {
    o.esdp_rho = rho;
    EXPECT_NE(o.validate().find("--esdp-rho must be"), std::string::npos) << rho;
  }
  o.esdp_rho = 2.0;
  EXPECT_EQ(o.validate(), "");
  o.stop = "gradient";  // the gradient rule tests f or f_hat, not the ESDP
  EXPECT_NE(o.validate().find("give --stop papers"), std::string::npos);
  o.tol = 0;  // no stopping rule: nothing to refuse
  EXPECT_EQ(o.validate(), "");
  o = SolverOptions();
  o.algorithm = "relaxation";
  o.esdp_rho = 2.0;
  EXPECT_NE(o.validate().find("--esdp-rho is not honoured by --algorithm relaxation"), std::string::npos);
}
