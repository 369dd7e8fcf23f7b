// Whole-network analyses on hand-made networks: degrees, localizability
// (components, anchoring, measurement counts, rigidity) and the CRLB against a
// dense computation of tr(J^-1)/n.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <vector>

#include "snl/problem/analysis.hpp"
#include "snl/problem/generate.hpp"

#include "network_builder.hpp"

namespace {

using snl::GlobalId;
using snl::Network;

using Builder = snl::test::NetworkBuilder;
using snl::test::kCorners;

// Dense reference: tr(J^-1)/n with J of the spec (sigma = 1), from the rows as given.
double dense_crlb(const Network& net, double sigma) {
  const int p = net.dim;
  const int N = static_cast<int>(net.num_sensors) * p;
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(N, N);
  auto uvec = [&](const double* a, const double* b) {
    Eigen::VectorXd u(p);
    for (int d = 0; d < p; ++d) u[d] = a[d] - b[d];
    return Eigen::VectorXd(u / u.norm());
  };
  for (std::size_t e = 0; e < net.sensor_ranges.size(); ++e) {
    const auto i = net.sensor_edges[2 * e], j = net.sensor_edges[2 * e + 1];
    const Eigen::VectorXd u = uvec(&net.truth[i * p], &net.truth[j * p]);
    const Eigen::MatrixXd B = u * u.transpose() / (sigma * sigma);
    J.block(i * p, i * p, p, p) += B;
    J.block(j * p, j * p, p, p) += B;
    J.block(i * p, j * p, p, p) -= B;
    J.block(j * p, i * p, p, p) -= B;
  }
  for (std::size_t e = 0; e < net.anchor_ranges.size(); ++e) {
    const auto i = net.anchor_edges[2 * e], k = net.anchor_edges[2 * e + 1];
    const Eigen::VectorXd u = uvec(&net.truth[i * p], &net.anchors[k * p]);
    J.block(i * p, i * p, p, p) += u * u.transpose() / (sigma * sigma);
  }
  return std::sqrt(J.inverse().trace() / net.num_sensors);
}

TEST(DegreeStats, HandNetwork) {
  Builder b({0.2, 0.2, 0.4, 0.2, 0.6, 0.2, 0.8, 0.8}, kCorners);
  b.s(0, 1).s(1, 2).s(0, 2).a(0, 0).a(0, 1).a(2, 3);
  const auto st = snl::degree_stats(b.done());
  EXPECT_DOUBLE_EQ(st.mean, 6.0 / 4);
  EXPECT_EQ(st.min, 0);
  EXPECT_EQ(st.max, 2);
  EXPECT_DOUBLE_EQ(st.mean_anchor, 3.0 / 4);
  EXPECT_EQ(st.max_anchor, 2);
  EXPECT_EQ(st.isolated, 1);
}

TEST(Localizability, RigidSingleSensor) {
  Builder b({0.3, 0.4}, kCorners);
  b.a(0, 0).a(0, 1).a(0, 2).a(0, 3);
  const auto r = snl::analyze_localizability(b.done(), true);
  EXPECT_EQ(r.components, 1);
  EXPECT_TRUE(r.rigidity_checked);
  EXPECT_TRUE(r.rigid);
  EXPECT_TRUE(r.localizable()) << r.summary();
  EXPECT_EQ(r.flags, std::vector<std::uint8_t>{0});
}

TEST(Localizability, RigidTrilaterationNetwork) {
  // Three sensors, each with two corner anchors and the two other sensors.
  Builder b({0.3, 0.3, 0.7, 0.35, 0.5, 0.75}, kCorners);
  b.s(0, 1).s(1, 2).s(2, 0).a(0, 0).a(0, 2).a(1, 1).a(1, 3).a(2, 2).a(2, 3);
  const auto r = snl::analyze_localizability(b.done(), true);
  EXPECT_TRUE(r.rigid);
  EXPECT_TRUE(r.localizable()) << r.summary();
  EXPECT_TRUE(r.not_rigid.empty());
}

TEST(Localizability, UnanchoredComponentAndFewMeasurements) {
  Builder b({0.3, 0.4, 0.5, 0.5, 0.8, 0.8, 0.9, 0.8}, kCorners);
  b.s(0, 1).s(2, 3).a(0, 0).a(0, 1).a(0, 2).a(0, 3);
  const auto r = snl::analyze_localizability(b.done(), true);
  EXPECT_EQ(r.components, 2);
  EXPECT_EQ(r.unanchored_components, 1);
  EXPECT_EQ(r.unanchored, (std::vector<GlobalId>{2, 3}));
  EXPECT_EQ(r.few_measurements, (std::vector<GlobalId>{1, 2, 3}));
  EXPECT_FALSE(r.rigid);
  EXPECT_FALSE(r.localizable());
  // Sensor 0 is pinned by four anchors; the others move.
  EXPECT_EQ(r.not_rigid, (std::vector<GlobalId>{1, 2, 3}));
  EXPECT_EQ(r.flags[0], 0);
  EXPECT_EQ(r.flags[1], snl::kFewMeasurements | snl::kNotRigid);
  EXPECT_EQ(r.flags[2], snl::kUnanchoredComponent | snl::kFewMeasurements | snl::kNotRigid);
  EXPECT_NE(r.summary().find("Not localizable"), std::string::npos);
}

TEST(Localizability, LowDegreeSensorThatIsRigid) {
  // Sensor 1 has two non-parallel constraints: infinitesimally rigid, yet fewer than p+1.
  Builder b({0.3, 0.4, 0.6, 0.7}, kCorners);
  b.s(0, 1).a(0, 0).a(0, 1).a(0, 2).a(1, 3);
  const auto r = snl::analyze_localizability(b.done(), true);
  EXPECT_EQ(r.few_measurements, std::vector<GlobalId>{1});
  EXPECT_TRUE(r.rigid);
  EXPECT_FALSE(r.localizable());
  EXPECT_EQ(r.flags[1], snl::kFewMeasurements);
}

TEST(Localizability, CollinearConstraintsAreNotRigid) {
  // Sensor 0 measures three anchors on its own horizontal line; sensor 1 is fine.
  std::vector<double> anchors = kCorners;
  for (double x : {0.0, 1.0, 0.25}) {
    anchors.push_back(x);
    anchors.push_back(0.5);
  }
  Builder b({0.5, 0.5, 0.3, 0.2}, anchors);
  b.a(0, 4).a(0, 5).a(0, 6).a(1, 0).a(1, 1).a(1, 2);
  const auto r = snl::analyze_localizability(b.done(), true);
  EXPECT_TRUE(r.unanchored.empty());
  EXPECT_TRUE(r.few_measurements.empty());
  EXPECT_TRUE(r.rigidity_checked);
  EXPECT_FALSE(r.rigid);
  EXPECT_EQ(r.not_rigid, std::vector<GlobalId>{0});
  EXPECT_EQ(r.flags, (std::vector<std::uint8_t>{snl::kNotRigid, 0}));
  EXPECT_FALSE(r.localizable());
  // The same graph at generic positions is rigid: rigidity is judged at the given positions.
  const std::vector<double> generic = {0.5, 0.6, 0.3, 0.2};
  EXPECT_TRUE(snl::analyze_localizability(b.done(), true, &generic).rigid);
}

TEST(Localizability, StraightChainIsFlexible) {
  // Anchors 0, 1 at the ends of a horizontal line with five sensors on it, each
  // linked to the next two: enough measurements, all collinear. Sensor 5 is
  // elsewhere, pinned by the corners (anchors 2..5).
  std::vector<double> anchors = {0, 0.5, 1, 0.5};
  anchors.insert(anchors.end(), kCorners.begin(), kCorners.end());
  std::vector<double> truth;
  for (int i = 0; i < 5; ++i) {
    truth.push_back((i + 1) / 6.0);
    truth.push_back(0.5);
  }
  truth.push_back(0.3);
  truth.push_back(0.2);
  Builder b(truth, anchors);
  for (int i = 0; i < 5; ++i) {
    if (i + 1 < 5) b.s(i, i + 1);
    if (i + 2 < 5) b.s(i, i + 2);
  }
  b.a(0, 0).a(1, 0).a(3, 1).a(4, 1).a(5, 2).a(5, 3).a(5, 4);
  const auto r = snl::analyze_localizability(b.done(), true);
  EXPECT_EQ(r.components, 2);
  EXPECT_TRUE(r.unanchored.empty());
  EXPECT_TRUE(r.few_measurements.empty()) << r.summary();
  EXPECT_FALSE(r.rigid);
  EXPECT_EQ(r.not_rigid, (std::vector<GlobalId>{0, 1, 2, 3, 4}));
  EXPECT_FALSE(r.localizable());
  // Bending the chain into a zigzag makes it rigid.
  std::vector<double> zig = truth;
  for (int i = 0; i < 5; ++i) zig[2 * i + 1] = 0.5 + (i % 2 ? 0.1 : -0.1);
  EXPECT_TRUE(snl::analyze_localizability(b.done(), true, &zig).rigid);
}

TEST(Localizability, DuplicatesCountOnce) {
  Builder b({0.3, 0.4, 0.6, 0.7}, kCorners);
  b.a(0, 0).a(0, 1).a(0, 2).s(1, 0).s(0, 1).s(1, 0).a(1, 3).a(1, 3);
  const auto r = snl::analyze_localizability(b.done(), false);
  EXPECT_EQ(r.few_measurements, std::vector<GlobalId>{1});  // 5 rows, 2 distinct measurements
  EXPECT_FALSE(r.rigidity_checked);
}

TEST(Localizability, RigidityNeedsPositionsAndSmallN) {
  Builder b({0.3, 0.4}, kCorners);
  b.a(0, 0).a(0, 1).a(0, 2);
  Network net = b.done();
  net.has_truth = false;
  net.truth.clear();
  auto r = snl::analyze_localizability(net, true);
  EXPECT_FALSE(r.rigidity_checked);
  EXPECT_TRUE(r.localizable());
  const std::vector<double> pos = {0.3, 0.4};
  r = snl::analyze_localizability(net, true, &pos);
  EXPECT_TRUE(r.rigidity_checked);
  EXPECT_TRUE(r.rigid);

  snl::GenerateOptions o;
  o.sensors = snl::kRigidityLimit + 1;
  o.localizable = snl::GenerateOptions::Localizable::kNo;
  const Network big = snl::generate_network(o);
  EXPECT_FALSE(snl::analyze_localizability(big, true).rigidity_checked);
}

TEST(Crlb, SingleSensorMatchesClosedForm) {
  Builder b({0.3, 0.4}, kCorners);
  b.a(0, 0).a(0, 1).a(0, 2).a(0, 3);
  const Network net = b.done();
  const auto c = snl::cramer_rao_bound(net, 0.1);
  ASSERT_TRUE(c.defined) << c.reason;
  EXPECT_NEAR(c.rmse, dense_crlb(net, 0.1), 1e-12);
}

TEST(Crlb, MatchesDenseOnGeneratedNetworks) {
  struct Case {
    int n, dim;
    double deg;
  };
  for (const Case cs : {Case{10, 2, 4.3}, Case{50, 2, 6.1}, Case{40, 3, 8.0}, Case{600, 2, 9.0}, Case{300, 3, 12.0}}) {
    snl::GenerateOptions o;
    o.sensors = cs.n;
    o.dim = cs.dim;
    o.avg_degree = cs.deg;
    o.seed = 5;
    o.num_random_anchors = cs.n > 100 ? cs.n / 10 : 0;
    if (cs.n > 100) o.anchor_radius = 0.3;
    o.localizable = snl::GenerateOptions::Localizable::kYes;
    const Network net = snl::generate_network(o);
    for (double sigma : {1.0, 0.05}) {
      const auto c = snl::cramer_rao_bound(net, sigma);
      ASSERT_TRUE(c.defined) << c.reason;
      const double want = dense_crlb(net, sigma);
      EXPECT_NEAR(c.rmse, want, 1e-8 * want) << "n=" << cs.n << " p=" << cs.dim;
    }
  }
}

TEST(Crlb, UnsortedRowsAndDuplicates) {
  Builder b({0.3, 0.3, 0.7, 0.35, 0.5, 0.75}, kCorners);
  b.s(2, 0).s(1, 2).a(2, 3).s(0, 1).a(0, 0).a(0, 2).a(1, 1).a(1, 3).a(2, 2).s(1, 0);
  const Network net = b.done();
  const auto c = snl::cramer_rao_bound(net, 0.01);
  ASSERT_TRUE(c.defined) << c.reason;
  EXPECT_NEAR(c.rmse, dense_crlb(net, 0.01), 1e-10);
}

TEST(Crlb, RefusedWhenSingularOrMissing) {
  Builder b({0.3, 0.4, 0.5, 0.5, 0.8, 0.8, 0.9, 0.8}, kCorners);
  b.s(0, 1).s(2, 3).a(0, 0).a(0, 1).a(0, 2).a(0, 3);
  // Sensor 0 is pinned by four anchors; 1 hangs from it, 2-3 see no anchor:
  // the bound covers sensor 0 only and lists the others.
  const auto c = snl::cramer_rao_bound(b.done(), 0.01);
  EXPECT_TRUE(c.defined) << c.reason;
  EXPECT_EQ(c.covered, 1);
  EXPECT_EQ(c.outside, (std::vector<GlobalId>{1, 2, 3}));

  // A chain of collinear constraints is singular too.
  std::vector<double> anchors = kCorners;
  for (double x : {0.0, 1.0, 0.25}) {
    anchors.push_back(x);
    anchors.push_back(0.5);
  }
  Builder col({0.5, 0.5}, anchors);
  col.a(0, 4).a(0, 5).a(0, 6);
  EXPECT_FALSE(snl::cramer_rao_bound(col.done(), 0.01).defined);

  Builder nt({0.3, 0.4}, kCorners);
  nt.a(0, 0).a(0, 1).a(0, 2);
  Network net = nt.done();
  net.has_truth = false;
  net.truth.clear();
  const auto m = snl::cramer_rao_bound(net, 0.01);
  EXPECT_FALSE(m.defined);
  EXPECT_FALSE(m.reason.empty());

  Network big;
  big.num_sensors = snl::kCrlbLimit + 1;
  big.has_truth = true;
  big.truth.assign(static_cast<std::size_t>(big.num_sensors) * 2, 0.5);
  big.anchors = kCorners;
  const auto l = snl::cramer_rao_bound(big, 0.01);
  EXPECT_FALSE(l.defined);
  EXPECT_NE(l.reason.find("limit"), std::string::npos);
}

}  // namespace
