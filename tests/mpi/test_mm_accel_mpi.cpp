// mm-accel (src/solvers/mm_accel.cpp): its serial reference twin
// (reference::mm_accel) gives the same iterates and rejections; over many random networks (2D and 3D,
// noise-free to very noisy), the MM surrogate F never increases, the ML cost
// f never rises above an earlier F (f <= F), and over 50 small ones f itself
// never rises between iterations; from the same start it ends
// below MM after the same number of iterations; the iterates are the same
// bits on 1, 2 and 3 ranks on networks with many anchored nodes (more in
// test_solver_mpi's Determinism.*); checkpoint/restart in tests/cli.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cstdlib>
#include <cstring>

#include "reference/reference.hpp"
#include "solve_helpers.hpp"

using namespace snl;
using snl::test::allgather_positions;
using snl::test::make_network;
using snl::test::slab_of;
using snl::test::world_rank;
using snl::test::world_size;

namespace {

Summary solve(const Network& w, const std::string& alg, int iters, const std::string& weights = "auto",
              const std::string& loss = "l2") {  // history at every iteration
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  SolverOptions opt;
  opt.algorithm = alg;
  opt.weights = weights;
  opt.loss = loss;
  opt.max_iter = iters;
  opt.tol = 0;
  opt.history_every = 1;
  opt.check_monotone = true;  // the Solver throws if F rises (beyond rounding) between iterations
  Solver solver(prob, opt);
  return solver.solve(random_initial_positions(prob, 5), nullptr);
}

// `iters` iterations from random_initial_positions(prob, 5) with sparse
// records (so that no record asks for the exact costs between the acceptance
// tests); sums: SNL_TEST_ACCEPT's choice (nullptr: the default). The start
// and the end positions, gathered, into *x0 and *x.
Summary run_sparse(const Network& w, int iters, const char* sums, std::vector<double>* x0, std::vector<double>* x) {
  if (sums) setenv("SNL_TEST_ACCEPT", sums, 1);
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  SolverOptions opt;
  opt.algorithm = "mm-accel";
  opt.max_iter = iters;
  opt.tol = 0;
  opt.history_every = 1000000;
  Solver solver(prob, opt);
  const auto start = random_initial_positions(prob, 5);
  std::vector<double> owned;
  const Summary s = solver.solve(start, &owned);
  if (sums) unsetenv("SNL_TEST_ACCEPT");
  if (x0) *x0 = allgather_positions(prob, start);
  *x = allgather_positions(prob, owned);
  return s;
}

std::vector<double> positions_after(const Network& w, int iters, const char* sums) {
  std::vector<double> x;
  run_sparse(w, iters, sums, nullptr, &x);
  return x;
}

}  // namespace

// The serial reference twin (reference::mm_accel: step, test and restart on
// whole vectors, plain sums) on 2D and 3D networks noisy enough that steps are
// rejected: the same iterates within rounding, and the same rejections, on
// 1, 2 and 3 ranks. (The solver takes each step one iteration ahead, in the
// pass that tests the previous one; a rejection discards it.)
TEST(MMAccel, MatchesItsSerialReferenceTwin) {
  int rejected = 0;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    const int dim = seed % 3 == 0 ? 3 : 2;
    const Network w = make_network({.n = 60, .dim = dim, .radius = dim == 3 ? 0.5 : 0.3, .anchor_radius = 0.35,
                                    .sigma = 0.05, .seed = seed});
    std::vector<double> x0, xs;
    const Summary s = run_sparse(w, 300, nullptr, &x0, &xs);
    int restarts = -1;
    const auto xr = reference::mm_accel(w, x0, 300, nullptr, &restarts);
    ASSERT_EQ(xs.size(), xr.size());
    for (std::size_t t = 0; t < xs.size(); ++t) ASSERT_NEAR(xs[t], xr[t], 1e-10) << "seed " << seed << " at " << t;
    double snl_rejected = -1;
    for (const auto& [k, v] : s.method_values)
      if (k == "rejected_steps") snl_rejected = v;
    EXPECT_EQ(snl_rejected, restarts) << "seed " << seed;
    rejected += restarts;
  }
  EXPECT_GT(rejected, 0) << "no step was rejected: the restart path went untested";
}

// The acceptance test on plain sums with their rounding bounds decides as the
// exact sums do (mm_accel.cpp, accepts; plain from 10,000 sensors, chosen here
// by SNL_TEST_ACCEPT): the same bits with every test on the exact sums, from
// rough starts to convergence (where F and f barely move).
TEST(MMAccel, PlainSumsDecideAsTheExactOnes) {
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    const double sigmas[] = {0.0, 0.01, 0.05, 0.2};
    const int dim = seed % 4 == 0 ? 3 : 2;
    const Network w = make_network({.n = GlobalId(60 + 20 * seed), .dim = dim, .radius = dim == 3 ? 0.45 : 0.3,
                                    .anchor_radius = 0.35, .sigma = sigmas[seed % 4], .seed = seed});
    const int iters = seed % 2 ? 3000 : 300;
    const auto plain = positions_after(w, iters, "plain"), exact = positions_after(w, iters, "exact");
    ASSERT_EQ(plain.size(), exact.size());
    EXPECT_EQ(0, std::memcmp(plain.data(), exact.data(), plain.size() * sizeof(double))) << "seed " << seed;
  }
}

TEST(MMAccel, MonotoneOverManyRandomNetworks) {
  int faster = 0, cases = 0;
  for (std::uint64_t seed = 1; seed <= 12; ++seed) {
    const double sigmas[] = {0.0, 0.01, 0.05, 0.2};
    const Network w = make_network({.n = GlobalId(30 + 5 * seed), .dim = seed % 3 == 0 ? 3 : 2,
                                    .radius = seed % 3 == 0 ? 0.45 : 0.3, .anchor_radius = 0.35,
                                    .sigma = sigmas[seed % 4], .seed = seed});
    Summary acc;
    ASSERT_NO_THROW(acc = solve(w, "mm-accel", 150)) << "seed " << seed;
    const Summary mm = solve(w, "mm", 150);
    double best_F = acc.history.front().cost;
    for (std::size_t t = 1; t < acc.history.size(); ++t) {
      const IterationSummary& h = acc.history[t];
      // Rejected steps keep z(k); accepted ones lower F (plain steps up to rounding).
      EXPECT_LE(h.cost, acc.history[t - 1].cost * (1 + 1e-12) + 1e-24) << "seed " << seed << " it " << h.iteration;
      EXPECT_LE(h.ml_cost, best_F * (1 + 1e-12) + 1e-24) << "seed " << seed << " it " << h.iteration;
      best_F = std::min(best_F, h.cost);
    }
    ++cases;
    faster += acc.costs.ml < mm.costs.ml * (1 - 1e-9);
  }
  // Acceleration pays on almost every network (noise-free ones included).
  EXPECT_GE(faster, cases * 3 / 4) << faster << " of " << cases;
}

// The ML cost never rises, recorded at every iteration, on 50 small random
// networks (2D and 3D, sigma 0 to 0.2): an extrapolated step that would raise
// f is rejected, and the plain step after it starts from the best edge and
// anchor variables for x(k), where F = f.
TEST(MMAccel, MLCostNeverRisesOverFiftyNetworks) {
  for (std::uint64_t seed = 101; seed <= 150; ++seed) {
    const double sigmas[] = {0.0, 0.005, 0.02, 0.05, 0.2};
    const int dim = seed % 4 == 0 ? 3 : 2;
    const Network w = make_network({.n = GlobalId(15 + seed % 25), .dim = dim, .radius = dim == 3 ? 0.5 : 0.35,
                                    .anchor_radius = 0.35, .sigma = sigmas[seed % 5], .seed = seed});
    Summary acc;
    ASSERT_NO_THROW(acc = solve(w, "mm-accel", 120)) << "seed " << seed;
    ASSERT_EQ(acc.history.size(), 121u);
    for (std::size_t t = 1; t < acc.history.size(); ++t) {
      const double prev = acc.history[t - 1].ml_cost, now = acc.history[t].ml_cost;
      EXPECT_LE(now, prev * (1 + 1e-12) + 1e-24) << "seed " << seed << " it " << acc.history[t].iteration;
    }
  }
}

// Under a measurement model (weights from per-range sigmas spread over a
// factor 5, a few ranges with a positive bias, l2 or Huber): neither the
// surrogate Phi nor the weighted / Huber ML cost ever rises, and from the
// same start mm-accel ends below MM on most networks.
TEST(MMAccel, ModelMonotoneOverManyRandomNetworks) {
  int faster = 0, cases = 0;
  for (std::uint64_t seed = 201; seed <= 224; ++seed) {
    const int dim = seed % 3 == 0 ? 3 : 2;
    Network w = make_network({.n = GlobalId(25 + seed % 20), .dim = dim, .radius = dim == 3 ? 0.5 : 0.35,
                              .anchor_radius = 0.4, .sigma = 0.01 * double(seed % 4), .seed = seed});
    w.sensor_sigmas.resize(w.sensor_ranges.size());
    w.anchor_sigmas.resize(w.anchor_ranges.size());
    for (std::size_t e = 0; e < w.sensor_ranges.size(); ++e) {
      w.sensor_sigmas[e] = 0.01 * (1 + double((e + seed) % 5));
      if ((e + seed) % 9 == 4) w.sensor_ranges[e] += 0.15;
    }
    for (std::size_t e = 0; e < w.anchor_ranges.size(); ++e) w.anchor_sigmas[e] = 0.01 * (1 + double(e % 3));
    const std::string loss = seed % 2 ? "huber:0.03" : "l2";
    Summary acc;
    ASSERT_NO_THROW(acc = solve(w, "mm-accel", 150, "file", loss)) << "seed " << seed;
    ASSERT_EQ(acc.history.size(), 151u);
    for (std::size_t t = 1; t < acc.history.size(); ++t) {
      const IterationSummary &h = acc.history[t], &g = acc.history[t - 1];
      EXPECT_LE(h.cost, g.cost * (1 + 1e-12) + 1e-24) << "seed " << seed << " it " << h.iteration;
      EXPECT_LE(h.ml_cost, g.ml_cost * (1 + 1e-12) + 1e-24) << "seed " << seed << " it " << h.iteration;
    }
    const Summary mm = solve(w, "mm", 150, "file", loss);
    ++cases;
    faster += acc.costs.ml < mm.costs.ml * (1 - 1e-9);
  }
  EXPECT_GE(faster, cases * 3 / 4) << faster << " of " << cases;
}

// Anchored nodes on a partition's boundary: the step once stepped the first
// boundary nodes' anchor variables twice where the interior ended in a
// partial SIMD chunk, so 2 ranks differed from 1 (snl generate --sensors 300
// --seed 3, kernel dispatch.cpp). Many anchored nodes and several networks
// make such a node follow a partial chunk on some rank.
TEST(MMAccel, BitIdenticalForOneTwoThreeRanksWithManyAnchoredNodes) {
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    const Network w = make_network({.n = 150, .dim = 2, .radius = 0.16, .anchor_radius = 0.45, .sigma = 0.02,
                                    .seed = seed});
    const auto ref = snl::test::run(MPI_COMM_SELF, w, "mm-accel", 6);
    for (int k = 2; k <= world_size(); ++k) {
      MPI_Comm sub;
      MPI_Comm_split(MPI_COMM_WORLD, world_rank() < k ? 0 : MPI_UNDEFINED, world_rank(), &sub);
      if (sub == MPI_COMM_NULL) continue;
      const auto x = snl::test::run(sub, w, "mm-accel", 6);
      ASSERT_EQ(x.size(), ref.size());
      EXPECT_EQ(0, std::memcmp(x.data(), ref.data(), x.size() * sizeof(double)))
          << "seed " << seed << ": " << k << " ranks differ from 1";
      MPI_Comm_free(&sub);
    }
  }
}
