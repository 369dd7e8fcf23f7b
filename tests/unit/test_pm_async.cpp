// The async method (src/solvers/async.cpp), serially: 003 Algorithm 2
// with the spec's corrected local problem (weight 1/2, L_i = delta_i + |A_i|):
// no activation increases f_hat, exact or inexact (eq. 20), on the reference
// twin; and the solver's async / async-exact ends where the twin does.
#include <gtest/gtest.h>

#include "reference/reference.hpp"
#include "snl/solvers/solver.hpp"
#include "test_networks.hpp"

using namespace snl;

TEST(AsyncMonotone, NoActivationIncreasesRelaxedCost) {
  for (int t = 0; t < 12; ++t) {
    test::NetSpec s;
    s.n = 20 + 5 * t;
    s.dim = t % 3 == 0 ? 3 : 2;
    s.radius = 0.3 + 0.02 * (t % 4);
    s.anchor_radius = 0.5;
    s.sigma = std::vector<double>{0.0, 0.01, 0.1, 0.3}[t % 4];
    s.seed = 50 + t;
    Network w = test::make_network(s);
    std::vector<double> x0(w.num_sensors * w.dim);
    for (std::size_t k = 0; k < x0.size(); ++k) x0[k] = uniform01(9, RngStream::kInit, k);
    LocalizationProblem prob(MPI_COMM_SELF, w, PartitionMethod::kBlock, nullptr);
    for (bool exact : {false, true}) {
      std::vector<double> f;
      const auto xr = reference::async(w, x0, 20 * w.num_sensors, 3 + t, exact, &f);
      for (std::size_t k = 1; k < f.size(); ++k)
        ASSERT_LE(f[k], f[k - 1] * (1 + 1e-13) + 1e-24) << "net " << t << " activation " << k << (exact ? " exact" : "");
      EXPECT_LT(f.back(), f.front()) << "net " << t;
      // 20 sweeps of the solver's method, its activations keyed by the same seed.
      SolverOptions o;
      o.algorithm = exact ? "async-exact" : "async";
      o.max_iter = 20;
      o.tol = 0;
      o.seed = 3 + t;
      std::vector<double> x;
      Solver(prob, o).solve(prob.file_rows_to_owned(x0, 0, w.dim), &x);
      const auto xg = test::allgather_positions(prob, x);
      ASSERT_EQ(xg.size(), xr.size());
      for (std::size_t k = 0; k < xg.size(); ++k)
        ASSERT_NEAR(xg[k], xr[k], 1e-10) << "net " << t << " entry " << k << (exact ? " exact" : "");
    }
  }
}
