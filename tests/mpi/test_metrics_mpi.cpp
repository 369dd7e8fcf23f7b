// The core metrics (src/problem/metrics.cpp, src/problem/analysis.cpp) against
// computations written out here, following the shared spec algorithms.md:
// ML cost f and relaxed cost f_hat with the 1/2, the gap certificate (003
// eq. 22), the a-priori bound (eq. 23), RMSE and MPE per sensor (1/n), the
// gradients, and the CRLB sqrt(tr(J^-1)/n) with J at the true positions.
// First a hand-checkable network whose values are closed-form numbers, then
// random networks against plain O(E) loops and a dense inverse of J. Every
// rank count splits the edges differently: each must still be counted once.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <vector>

#include "snl/problem/analysis.hpp"
#include "snl/problem/metrics.hpp"
#include "solve_helpers.hpp"

using namespace snl;
using snl::test::make_network;
using snl::test::NetSpec;
using snl::test::slab_of;

namespace {

// A whole network from explicit rows (dimension 2 unless said).
struct Rows {
  std::vector<double> truth, anchors;
  std::vector<GlobalId> se, ae;
  std::vector<double> sr, ar;
  Network done(int dim = 2) const {
    Network net;
    net.dim = dim;
    net.num_sensors = static_cast<GlobalId>(truth.size()) / dim;
    net.truth = truth;
    net.has_truth = true;
    net.anchors = anchors;
    net.sensor_edges = se;
    net.sensor_ranges = sr;
    net.anchor_edges = ae;
    net.anchor_ranges = ar;
    net.total_sensor_edges = net.local_sensor_edges();
    net.total_anchor_edges = net.local_anchor_edges();
    return net;
  }
};

// Global positions [n, p] -> the problem's local array (owned and ghost rows).
std::vector<double> to_local(const LocalizationProblem& prob, const std::vector<double>& xg) {
  const int p = prob.dim();
  std::vector<double> x(std::size_t(prob.num_local()) * p);
  for (LocalId v = 0; v < prob.num_local(); ++v)
    for (int c = 0; c < p; ++c) x[std::size_t(v) * p + c] = xg[std::size_t(prob.graph().global_id(v)) * p + c];
  return x;
}

// The hand network: anchors a0 = (0,0), a1 = (4,7); sensors estimated at
// x0 = (1,0), x1 = (1,3), x2 = (1,7) with truth (1,1), (1,3), (1,5).
//   edge     |z|  range  1/2(|z|-r)^2  relaxed  certificate  1/2 r^2
//   s0-s1     3    1.5      1.125       1.125        0        1.125
//   s1-s2     4    2        2           2            0        2
//   s0-s2     7   10        4.5         0            4.5     50
//   s0-a0     1    3        2           0            2        4.5
//   s2-a1     3    0.5      3.125       3.125        0        0.125
// f = 12.75, f_hat = 6.25, certificate = 6.5, a-priori = 57.75.
// Errors: |x0-t0| = 1, |x1-t1| = 0, |x2-t2| = 2: RMSE = sqrt(5/3), MPE = 1.
// s1 has 2 < p+1 measurements: flagged, so over the localizable sensors
// RMSE = sqrt(5/2), MPE = 3/2.
Network hand_network() {
  Rows r;
  r.truth = {1, 1, 1, 3, 1, 5};
  r.anchors = {0, 0, 4, 7};
  r.se = {0, 1, 1, 2, 0, 2};
  r.sr = {1.5, 2, 10};
  r.ae = {0, 0, 2, 1};
  r.ar = {3, 0.5};
  return r.done();
}
const std::vector<double> kHandX = {1, 0, 1, 3, 1, 7};

TEST(MetricsExact, HandNetworkCosts) {
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(hand_network(), MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  const auto x = to_local(prob, kHandX);
  const CostTerms c = evaluate_costs(prob, x.data());
  EXPECT_DOUBLE_EQ(c.ml, 12.75);
  EXPECT_DOUBLE_EQ(c.relaxed, 6.25);
  EXPECT_DOUBLE_EQ(c.certificate, 6.5);
  EXPECT_DOUBLE_EQ(c.apriori, 57.75);
  // The certificate bounds the gap: f(x) - f_hat(x) is exactly the sum of the
  // nonconvex terms of the edges inside their ball (003 eq. 22).
  EXPECT_DOUBLE_EQ(c.ml - c.relaxed, c.certificate);
}

TEST(MetricsExact, HandNetworkErrors) {
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(hand_network(), MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  const auto x = to_local(prob, kHandX);
  const ErrorMetrics e = evaluate_errors(prob, x.data());
  ASSERT_TRUE(e.valid);
  EXPECT_DOUBLE_EQ(e.rmse, std::sqrt(5.0 / 3.0));
  EXPECT_DOUBLE_EQ(e.mpe, 1.0);
  EXPECT_EQ(e.localizable, 2);
  EXPECT_DOUBLE_EQ(e.rmse_localizable, std::sqrt(5.0 / 2.0));
  EXPECT_DOUBLE_EQ(e.mpe_localizable, 1.5);
  // At the truth every error is zero.
  const auto t = to_local(prob, hand_network().truth);
  const ErrorMetrics z = evaluate_errors(prob, t.data());
  EXPECT_EQ(z.rmse, 0.0);
  EXPECT_EQ(z.mpe, 0.0);
}

TEST(MetricsExact, HandNetworkGradients) {
  // At s0: e(x0-x1 = (0,-3), 1.5) = (0,-1.5); x0-x2 = (0,-7) lies inside
  // its ball (r = 10): relaxed 0, ML (1-10/7)(0,-7) = (0,3); x0-a0 = (1,0)
  // inside (r = 3): relaxed 0, ML (1-3)(1,0) = (-2,0).
  // At s1: x1-x0 = (0,3) -> (0,1.5); x1-x2 = (0,-4), r = 2 -> (0,-2).
  // At s2: x2-x1 = (0,4) -> (0,2); x2-x0 = (0,7) -> ML (0,-3);
  //        x2-a1 = (-3,0), r = 0.5 -> (5/6)(-3,0) = (-2.5,0).
  const std::vector<double> want_ml = {-2, 1.5, 0, -0.5, -2.5, -1};
  const std::vector<double> want_relaxed = {0, -1.5, 0, -0.5, -2.5, 2};
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(hand_network(), MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  const auto x = to_local(prob, kHandX);
  std::vector<double> g(x.size(), 0.0), h(x.size(), 0.0);
  ml_gradient(prob, x.data(), g.data(), 0, prob.num_owned());
  relaxed_gradient(prob, x.data(), h.data(), 0, prob.num_owned());
  for (LocalId v = 0; v < prob.num_owned(); ++v) {
    const GlobalId i = prob.graph().global_id(v);
    for (int c = 0; c < 2; ++c) {
      EXPECT_NEAR(g[2 * v + c], want_ml[2 * i + c], 1e-14) << "sensor " << i;
      EXPECT_NEAR(h[2 * v + c], want_relaxed[2 * i + c], 1e-14) << "sensor " << i;
    }
  }
  // L = 2 delta_max + max |A_i| = 2*2 + 1 (003 eq. 16).
  EXPECT_EQ(relaxation_lipschitz(prob), 5.0);
}

// ---- random networks against plain loops ----

double dist(const double* a, const double* b, int p) {
  double s = 0;
  for (int c = 0; c < p; ++c) s += (a[c] - b[c]) * (a[c] - b[c]);
  return std::sqrt(s);
}

struct Direct {
  double ml = 0, relaxed = 0, certificate = 0, apriori = 0, rmse = 0, mpe = 0;
};

// One pass over the edge list and the sensors (duplicates already merged).
Direct direct(const Network& w, const std::vector<double>& x) {
  const int p = w.dim;
  Direct d;
  auto term = [&](double nz, double r) {
    const double q = 0.5 * (nz - r) * (nz - r);
    d.ml += q;
    d.relaxed += nz > r ? q : 0.0;
    d.certificate += nz < r ? q : 0.0;
    d.apriori += 0.5 * r * r;
  };
  for (std::size_t e = 0; e < w.sensor_ranges.size(); ++e)
    term(dist(&x[w.sensor_edges[2 * e] * p], &x[w.sensor_edges[2 * e + 1] * p], p), w.sensor_ranges[e]);
  for (std::size_t e = 0; e < w.anchor_ranges.size(); ++e)
    term(dist(&x[w.anchor_edges[2 * e] * p], &w.anchors[w.anchor_edges[2 * e + 1] * p], p), w.anchor_ranges[e]);
  double sq = 0, ab = 0;
  for (GlobalId i = 0; i < w.num_sensors; ++i) {
    const double r = dist(&x[i * p], &w.truth[i * p], p);
    sq += r * r;
    ab += r;
  }
  d.rmse = std::sqrt(sq / double(w.num_sensors));
  d.mpe = ab / double(w.num_sensors);
  return d;
}

TEST(MetricsExact, RandomNetworksMatchPlainLoops) {
  for (int dim : {2, 3}) {
    const Network w = snl::test::merged(
        make_network({.n = 40, .dim = dim, .radius = 0.35, .anchor_radius = 0.4, .sigma = 0.1, .seed = 21}));
    ASSERT_GT(w.sensor_ranges.size(), 40u);
    LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
    // A point away from the truth: about half the edges inside their ball.
    std::vector<double> xg(w.truth);
    for (std::size_t t = 0; t < xg.size(); ++t) xg[t] += 0.1 * std::sin(3.0 * double(t) + 1.0);
    const Direct d = direct(w, xg);
    ASSERT_GT(d.certificate, 0.0);
    ASSERT_GT(d.relaxed, 0.0);
    const auto x = to_local(prob, xg);
    const CostTerms c = evaluate_costs(prob, x.data());
    EXPECT_NEAR(c.ml, d.ml, 1e-12 * d.ml) << dim;
    EXPECT_NEAR(c.relaxed, d.relaxed, 1e-12 * d.relaxed) << dim;
    EXPECT_NEAR(c.certificate, d.certificate, 1e-12 * d.certificate) << dim;
    EXPECT_NEAR(c.apriori, d.apriori, 1e-12 * d.apriori) << dim;
    const ErrorMetrics e = evaluate_errors(prob, x.data());
    EXPECT_NEAR(e.rmse, d.rmse, 1e-13) << dim;
    EXPECT_NEAR(e.mpe, d.mpe, 1e-13) << dim;
  }
}

// The solver's one-sum and one-pass forms (its stopping tests and records)
// give evaluate_costs' and the gradients' bits.
TEST(MetricsExact, SingleSumAndFusedFormsGiveTheSameBits) {
  for (int dim : {2, 3}) {
    const Network w = snl::test::merged(
        make_network({.n = 40, .dim = dim, .radius = 0.35, .anchor_radius = 0.4, .sigma = 0.1, .seed = 22}));
    LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
    std::vector<double> xg(w.truth);
    for (std::size_t t = 0; t < xg.size(); ++t) xg[t] += 0.1 * std::sin(3.0 * double(t) + 1.0);
    const auto x = to_local(prob, xg);
    const CostTerms c = evaluate_costs(prob, x.data());
    EXPECT_EQ(evaluate_ml_cost(prob, x.data()), c.ml) << dim;
    EXPECT_EQ(evaluate_relaxed_cost(prob, x.data()), c.relaxed) << dim;
    for (bool relaxed : {false, true}) {
      std::vector<double> g(x.size(), 0.0), h(x.size(), 0.0);
      (relaxed ? relaxed_gradient : ml_gradient)(prob, x.data(), g.data(), 0, prob.num_owned());
      EXPECT_EQ(ml_cost_and_gradient(prob, x.data(), h.data(), relaxed), c.ml) << dim;
      for (std::size_t t = 0; t < std::size_t(prob.num_owned()) * dim; ++t)
        EXPECT_EQ(g[t], h[t]) << dim << " " << relaxed << " " << t;
    }
  }
}

// ---- Cramér-Rao bound ----

// tr(J^-1) of a small dense SPD matrix by Gauss-Jordan (no pivoting needed).
double trace_inverse(std::vector<double> J, int m) {
  std::vector<double> inv(std::size_t(m) * m, 0.0);
  for (int i = 0; i < m; ++i) inv[i * m + i] = 1;
  for (int k = 0; k < m; ++k) {
    const double piv = J[k * m + k];
    for (int j = 0; j < m; ++j) {
      J[k * m + j] /= piv;
      inv[k * m + j] /= piv;
    }
    for (int i = 0; i < m; ++i) {
      if (i == k) continue;
      const double f = J[i * m + k];
      for (int j = 0; j < m; ++j) {
        J[i * m + j] -= f * J[k * m + j];
        inv[i * m + j] -= f * inv[k * m + j];
      }
    }
  }
  double t = 0;
  for (int i = 0; i < m; ++i) t += inv[i * m + i];
  return t;
}

// Patwari et al. 2005 as written in algorithms.md, assembled edge by edge.
double direct_crlb(const Network& w, double sigma) {
  const int p = w.dim, m = int(w.num_sensors) * p;
  std::vector<double> J(std::size_t(m) * m, 0.0);
  auto add = [&](GlobalId i, GlobalId j, const double* xi, const double* xj) {
    const double r = dist(xi, xj, p);
    for (int a = 0; a < p; ++a)
      for (int b = 0; b < p; ++b) {
        const double q = (xi[a] - xj[a]) * (xi[b] - xj[b]) / (r * r * sigma * sigma);
        J[(i * p + a) * m + i * p + b] += q;
        if (j >= 0) {
          J[(j * p + a) * m + j * p + b] += q;
          J[(i * p + a) * m + j * p + b] -= q;
          J[(j * p + a) * m + i * p + b] -= q;
        }
      }
  };
  const auto& t = w.truth;
  for (std::size_t e = 0; e < w.sensor_ranges.size(); ++e) {
    const GlobalId i = w.sensor_edges[2 * e], j = w.sensor_edges[2 * e + 1];
    add(i, j, &t[i * p], &t[j * p]);
  }
  for (std::size_t e = 0; e < w.anchor_ranges.size(); ++e) {
    const GlobalId i = w.anchor_edges[2 * e];
    add(i, -1, &t[i * p], &w.anchors[w.anchor_edges[2 * e + 1] * p]);
  }
  return std::sqrt(trace_inverse(J, m) / double(w.num_sensors));
}

TEST(CrlbExact, OneSensorTwoOrthogonalAnchors) {
  // u = (-1,0) and (0,-1): J = I / sigma^2, tr(J^-1) = 2 sigma^2, n = 1.
  Rows r;
  r.truth = {0.5, 0.5};
  r.anchors = {1.5, 0.5, 0.5, 1.5};
  r.ae = {0, 0, 0, 1};
  r.ar = {1, 1};
  const auto c = cramer_rao_bound(r.done(), 0.1);
  ASSERT_TRUE(c.defined) << c.reason;
  EXPECT_NEAR(c.rmse, std::sqrt(2.0) * 0.1, 1e-15);
}

TEST(CrlbExact, TwoSensorsOnALine) {
  // s0 = (0,0), s1 = (1,0); s0 measures a0 = (-1,0) and a1 = (0,1), s1
  // measures a2 = (1,1), and s0-s1. x-block: [[2,-1],[-1,1]]/s^2 (inverse
  // s^2 [[1,1],[1,2]], trace 3 s^2); y-block: diag(1,1)/s^2 (trace 2 s^2).
  // RMSE_CRLB = sqrt(5 s^2 / 2).
  Rows r;
  r.truth = {0, 0, 1, 0};
  r.anchors = {-1, 0, 0, 1, 1, 1};
  r.se = {0, 1};
  r.sr = {1};
  r.ae = {0, 0, 0, 1, 1, 2};
  r.ar = {1, 1, 1};
  for (double s : {0.01, 0.3}) {
    const auto c = cramer_rao_bound(r.done(), s);
    ASSERT_TRUE(c.defined) << c.reason;
    EXPECT_NEAR(c.rmse, std::sqrt(2.5) * s, 1e-14 * s) << s;
  }
  // Without s1's anchor, s1 can turn about s0: the bound covers s0 alone
  // (J_00 = I / s^2, trace 2 s^2) and lists s1 outside.
  Rows f = r;
  f.ae = {0, 0, 0, 1};
  f.ar = {1, 1};
  const auto c = cramer_rao_bound(f.done(), 0.01);
  ASSERT_TRUE(c.defined) << c.reason;
  EXPECT_EQ(c.covered, 1);
  EXPECT_EQ(c.outside, (std::vector<GlobalId>{1}));
  EXPECT_NEAR(c.rmse, std::sqrt(2.0) * 0.01, 1e-15);
}

TEST(CrlbExact, RandomNetworkMatchesDenseInverse) {
  for (int dim : {2, 3}) {
    const Network w = snl::test::merged(
        make_network({.n = 30, .dim = dim, .radius = 0.5, .anchor_radius = 0.6, .sigma = 0.02, .seed = 4}));
    const auto rep = analyze_localizability(w, true);
    ASSERT_TRUE(rep.rigid) << rep.summary();
    for (double s : {0.02, 1.0}) {
      const auto c = cramer_rao_bound(w, s);
      ASSERT_TRUE(c.defined) << c.reason;
      const double want = direct_crlb(w, s);
      EXPECT_NEAR(c.rmse, want, 1e-9 * want) << "p=" << dim << " sigma=" << s;
    }
  }
}

}  // namespace
