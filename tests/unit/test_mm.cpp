// MM (000, Algorithm 1; src/solvers/mm.cpp), serially: it never
// increases its surrogate F(z), and f(x) <= F(z): checked at every iteration
// over many random networks and noise levels, on the reference twin and on
// the distributed solver (whose check_monotone option throws on any
// increase), which must agree.
#include <gtest/gtest.h>

#include "reference/reference.hpp"
#include "snl/solvers/solver.hpp"
#include "test_networks.hpp"

using namespace snl;

TEST(MMMonotone, SurrogateNeverIncreasesOverRandomNetworks) {
  int checked = 0;
  for (int t = 0; t < 48; ++t) {
    test::NetSpec s;
    s.n = 10 + (t * 7) % 70;
    s.dim = t % 3 == 0 ? 3 : 2;
    s.radius = 0.25 + 0.05 * (t % 5);
    s.anchor_radius = (t % 4 == 0) ? 2.0 : s.radius + 0.1;
    s.sigma = std::vector<double>{0.0, 0.01, 0.05, 0.1, 0.3}[t % 5];
    s.seed = 1000 + t;
    s.duplicates = t % 6 == 1;
    Network w = test::make_network(s);
    merge_duplicates(w.sensor_edges, w.sensor_ranges, w.anchor_edges, w.anchor_ranges);
    w.total_sensor_edges = w.local_sensor_edges();
    w.total_anchor_edges = w.local_anchor_edges();
    LocalizationProblem prob(MPI_COMM_SELF, w, PartitionMethod::kBlock, nullptr);
    const auto x0 = random_initial_positions(prob, 7 + t);  // local order
    const auto x0g = test::allgather_positions(prob, x0);   // global order, as the reference takes it
    // Reference twin: F after every iteration.
    std::vector<double> F;
    const auto xr = reference::mm(w, x0g, 300, &F);
    EXPECT_NEAR(F.front(), reference::ml_cost(w, x0g), 1e-12 * (1 + F.front()));  // F(z0) = f(x0)
    for (std::size_t k = 1; k < F.size(); ++k) {
      ASSERT_LE(F[k], F[k - 1] * (1 + 1e-13) + 1e-24) << "network " << t << " iteration " << k;
      ++checked;
    }
    EXPECT_LE(reference::ml_cost(w, xr), F.back() * (1 + 1e-12) + 1e-300);
    // The distributed solver with the per-iteration check (throws on increase).
    SolverOptions o;
    o.algorithm = "mm";
    o.max_iter = 300;
    o.tol = 0;
    o.check_monotone = true;
    std::vector<double> x;
    Summary sum;
    ASSERT_NO_THROW(sum = Solver(prob, o).solve(x0, &x)) << "network " << t;
    EXPECT_LE(sum.costs.ml, reference::ml_cost(w, x0g) * (1 + 1e-12) + 1e-300);
    // ... at the reference's positions.
    const auto xg = test::allgather_positions(prob, x);
    ASSERT_EQ(xg.size(), xr.size());
    for (std::size_t k = 0; k < xg.size(); ++k) ASSERT_NEAR(xg[k], xr[k], 1e-10) << "network " << t << " entry " << k;
  }
  EXPECT_EQ(checked, 48 * 300);
}
