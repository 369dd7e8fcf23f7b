// The async method (src/solvers/alg_sequential.cpp), serially: 003 Algorithm 2
// with the spec's corrected local problem (weight 1/2, L_i = delta_i + |A_i|):
// no activation increases f_hat, exact or inexact (eq. 20).
#include <gtest/gtest.h>

#include "reference/reference.hpp"
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
    for (bool exact : {false, true}) {
      std::vector<double> f;
      reference::async(w, x0, 20 * w.num_sensors, 3 + t, exact, &f);
      for (std::size_t k = 1; k < f.size(); ++k)
        ASSERT_LE(f[k], f[k - 1] * (1 + 1e-13) + 1e-24) << "net " << t << " activation " << k << (exact ? " exact" : "");
      EXPECT_LT(f.back(), f.front()) << "net " << t;
    }
  }
}
