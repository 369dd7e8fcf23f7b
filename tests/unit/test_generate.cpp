// Network generator: determinism, exact degree, reference twin, noise (003 eq. 28),
// anchors, localizability redraws.
#include <gtest/gtest.h>

#include <cmath>
#include <tuple>
#include <vector>

#include "snl/problem/analysis.hpp"
#include "snl/problem/generate.hpp"
#include "snl/core/random.hpp"

namespace {

using snl::GenerateOptions;
using snl::GenerateReport;
using snl::Network;
using Loc = GenerateOptions::Localizable;

GenerateOptions opts(snl::GlobalId n, int dim, double deg, double sigma = 0.01, std::uint64_t seed = 7) {
  GenerateOptions o;
  o.sensors = n;
  o.dim = dim;
  o.avg_degree = deg;
  o.sigma = sigma;
  o.seed = seed;
  o.localizable = Loc::kNo;
  o.num_random_anchors = 0;  // the papers' setting: corners, unit square
  o.side = 1.0;
  return o;
}

double dist2(const double* a, const double* b, int p) {
  double s = 0;
  for (int d = 0; d < p; ++d) s += (a[d] - b[d]) * (a[d] - b[d]);
  return s;
}

void expect_same(const Network& a, const Network& b) {
  EXPECT_EQ(a.dim, b.dim);
  EXPECT_EQ(a.num_sensors, b.num_sensors);
  EXPECT_EQ(a.anchors, b.anchors);
  EXPECT_EQ(a.truth, b.truth);
  EXPECT_EQ(a.sensor_edges, b.sensor_edges);
  EXPECT_EQ(a.sensor_ranges, b.sensor_ranges);
  EXPECT_EQ(a.anchor_edges, b.anchor_edges);
  EXPECT_EQ(a.anchor_ranges, b.anchor_ranges);
  EXPECT_EQ(a.localizability, b.localizability);
}

TEST(Generate, DeterministicForASeed) {
  const auto o = opts(2000, 2, 6.0);
  GenerateReport r1, r2;
  const Network a = snl::generate_network(o, &r1), b = snl::generate_network(o, &r2);
  expect_same(a, b);
  EXPECT_EQ(r1.radius, r2.radius);
}

TEST(Generate, DifferentSeedsDiffer) {
  const Network a = snl::generate_network(opts(500, 2, 6.0, 0.01, 1));
  const Network b = snl::generate_network(opts(500, 2, 6.0, 0.01, 2));
  EXPECT_NE(a.truth, b.truth);
  EXPECT_NE(a.sensor_edges, b.sensor_edges);
}

TEST(Generate, ShapesAndConventions) {
  const auto o = opts(300, 3, 6.0);
  GenerateReport rep;
  const Network net = snl::generate_network(o, &rep);
  EXPECT_EQ(net.dim, 3);
  EXPECT_EQ(net.num_sensors, 300);
  EXPECT_TRUE(net.has_truth);
  ASSERT_EQ(net.truth.size(), 900u);
  ASSERT_TRUE(net.sigma.has_value());
  EXPECT_EQ(*net.sigma, 0.01);
  EXPECT_EQ(net.localizability.size(), 300u);
  EXPECT_EQ(net.total_sensor_edges, net.local_sensor_edges());
  EXPECT_EQ(net.total_anchor_edges, net.local_anchor_edges());
  // First coordinate as documented: counter-based, stream kSensorPositions.
  EXPECT_EQ(net.truth[5], snl::uniform01(7, snl::RngStream::kSensorPositions, 5));
  for (double v : net.truth) {
    EXPECT_GT(v, 0.0);
    EXPECT_LT(v, 1.0);
  }
  // Sorted by (i, j), i < j, no duplicates.
  for (snl::GlobalId e = 0; e < net.local_sensor_edges(); ++e) {
    EXPECT_LT(net.sensor_edges[2 * e], net.sensor_edges[2 * e + 1]);
    if (e > 0) {
      const auto prev = std::make_pair(net.sensor_edges[2 * e - 2], net.sensor_edges[2 * e - 1]);
      EXPECT_LT(prev, std::make_pair(net.sensor_edges[2 * e], net.sensor_edges[2 * e + 1]));
    }
  }
  for (snl::GlobalId e = 1; e < net.local_anchor_edges(); ++e) {
    const auto prev = std::make_pair(net.anchor_edges[2 * e - 2], net.anchor_edges[2 * e - 1]);
    EXPECT_LT(prev, std::make_pair(net.anchor_edges[2 * e], net.anchor_edges[2 * e + 1]));
  }
}

class DegreeTest : public testing::TestWithParam<std::tuple<int, int, double>> {};

// The README's promise: the requested average degree exactly, +-1 edge
// (E = round(deg n / 2), up to a tie at the radius).
TEST_P(DegreeTest, AchievedWithinOneEdge) {
  const auto [n, dim, deg] = GetParam();
  GenerateReport rep;
  const Network net = snl::generate_network(opts(n, dim, deg), &rep);
  const double achieved = 2.0 * static_cast<double>(net.local_sensor_edges()) / n;
  EXPECT_LE(std::abs(net.local_sensor_edges() - std::llround(deg * n / 2)), 1) << "n=" << n << " p=" << dim;
  EXPECT_DOUBLE_EQ(achieved, rep.achieved_avg_degree);
  // Every edge lies within the reported radius, and the anchor radius defaults to it.
  const double r2 = rep.radius * rep.radius;
  for (snl::GlobalId e = 0; e < net.local_sensor_edges(); ++e) {
    const auto i = net.sensor_edges[2 * e], j = net.sensor_edges[2 * e + 1];
    ASSERT_LE(dist2(&net.truth[i * dim], &net.truth[j * dim], dim), r2 * (1 + 1e-12));
  }
  EXPECT_EQ(rep.anchor_radius, rep.radius);
  const auto stats = snl::degree_stats(net);
  EXPECT_DOUBLE_EQ(stats.mean, achieved);
}

INSTANTIATE_TEST_SUITE_P(Sizes, DegreeTest,
                         testing::Combine(testing::Values(50, 1000, 100000), testing::Values(1, 2, 3),
                                          testing::Values(4.3, 6.1, 10.0)));

// The spatial hash must find exactly the pairs the O(n^2) search finds.
TEST(Generate, HashedEqualsBruteForceTwin) {
  for (int dim : {1, 2, 3})
    for (int n : {2, 10, 57, 400, 2500})
      for (double deg : {0.0, 1.0, 4.3, 10.0, 0.8 * (n - 1), double(n - 1)}) {
        if (deg > n - 1 || (deg > 10 && n > 400)) continue;
        auto o = opts(n, dim, deg, 0.02, 11 + n);
        // 1-D draws at these degrees are seldom localizable: one draw, not 100 redraws.
        if (dim == 1) o.localizable = GenerateOptions::Localizable::kNo;
        GenerateReport ra, rb;
        const Network a = snl::generate_network(o, &ra);
        const Network b = snl::generate_network_reference(o, &rb);
        SCOPED_TRACE("n=" + std::to_string(n) + " p=" + std::to_string(dim) + " deg=" + std::to_string(deg));
        expect_same(a, b);
        EXPECT_EQ(ra.radius, rb.radius);
      }
}

// Independent brute force: the edge set is exactly {pairs with d <= radius}.
TEST(Generate, EdgeSetIsAllPairsWithinRadius) {
  for (int dim : {1, 2, 3}) {
    GenerateReport rep;
    const Network net = snl::generate_network(opts(1500, dim, 7.0), &rep);
    const double r2 = rep.radius * rep.radius;
    std::vector<std::pair<snl::GlobalId, snl::GlobalId>> want;
    for (int i = 0; i < 1500; ++i)
      for (int j = i + 1; j < 1500; ++j)
        if (dist2(&net.truth[i * dim], &net.truth[j * dim], dim) <= r2 * (1 + 1e-12)) want.emplace_back(i, j);
    ASSERT_EQ(static_cast<std::size_t>(net.local_sensor_edges()), want.size());
    for (std::size_t e = 0; e < want.size(); ++e) {
      ASSERT_EQ(net.sensor_edges[2 * e], want[e].first);
      ASSERT_EQ(net.sensor_edges[2 * e + 1], want[e].second);
    }
  }
}

TEST(Generate, ZeroSigmaGivesExactDistances) {
  const int dim = 2;
  auto o = opts(3000, dim, 6.0, 0.0);
  o.side = 0;  // auto: a square of side sqrt(3); the ranges are the distances of the scaled truth, to the bit
  o.num_random_anchors = snl::kAutoAnchors;
  const Network net = snl::generate_network(o);
  ASSERT_EQ(net.num_anchors(), 4 + 30);
  for (snl::GlobalId e = 0; e < net.local_sensor_edges(); ++e) {
    const auto i = net.sensor_edges[2 * e], j = net.sensor_edges[2 * e + 1];
    ASSERT_DOUBLE_EQ(net.sensor_ranges[e], std::sqrt(dist2(&net.truth[i * dim], &net.truth[j * dim], dim)));
  }
  for (snl::GlobalId e = 0; e < net.local_anchor_edges(); ++e) {
    const auto i = net.anchor_edges[2 * e], k = net.anchor_edges[2 * e + 1];
    ASSERT_DOUBLE_EQ(net.anchor_ranges[e], std::sqrt(dist2(&net.truth[i * dim], &net.anchors[k * dim], dim)));
  }
}

// 003, eq. (28): d = |t + nu|, nu ~ N(0, sigma^2). Anchor ranges (t ~ 0.5 >> sigma)
// test the Gaussian directly; sensor ranges (t ~ sigma) test the folded law.
TEST(Generate, NoiseStatistics) {
  const double sigma = 0.05;
  const int n = 100000, dim = 2;
  auto o = opts(n, dim, 6.0, sigma, 3);
  o.anchor_radius = 2.0;
  const Network net = snl::generate_network(o);
  ASSERT_EQ(net.local_anchor_edges(), 4 * n);
  double s1 = 0, s2 = 0;
  const double N = static_cast<double>(net.local_anchor_edges());
  for (snl::GlobalId e = 0; e < net.local_anchor_edges(); ++e) {
    const auto i = net.anchor_edges[2 * e], k = net.anchor_edges[2 * e + 1];
    const double t = std::sqrt(dist2(&net.truth[i * dim], &net.anchors[k * dim], dim));
    const double res = net.anchor_ranges[e] - t;
    s1 += res;
    s2 += res * res;
  }
  const double mean = s1 / N, sd = std::sqrt(s2 / N - mean * mean);
  EXPECT_NEAR(mean, 0.0, 5 * sigma / std::sqrt(N));
  EXPECT_NEAR(sd, sigma, 0.01 * sigma);

  // Sensor ranges: E[d^2] = t^2 + sigma^2 and E[d] = E|N(t, sigma^2)| (folded normal).
  double m2 = 0, m1 = 0;
  const double Ne = static_cast<double>(net.local_sensor_edges());
  for (snl::GlobalId e = 0; e < net.local_sensor_edges(); ++e) {
    const auto i = net.sensor_edges[2 * e], j = net.sensor_edges[2 * e + 1];
    const double t = std::sqrt(dist2(&net.truth[i * dim], &net.truth[j * dim], dim));
    const double d = net.sensor_ranges[e];
    ASSERT_GE(d, 0.0);
    m2 += d * d - t * t - sigma * sigma;
    const double folded = sigma * std::sqrt(2 / M_PI) * std::exp(-t * t / (2 * sigma * sigma)) + t * std::erf(t / (sigma * std::sqrt(2.0)));
    m1 += d - folded;
  }
  EXPECT_NEAR(m2 / Ne, 0.0, 5 * std::sqrt(2.0) * sigma * sigma / std::sqrt(Ne));
  EXPECT_NEAR(m1 / Ne, 0.0, 5 * sigma / std::sqrt(Ne));
}

TEST(Generate, CornerAnchors) {
  const Network a = snl::generate_network(opts(20, 2, 4.0));
  EXPECT_EQ(a.anchors, (std::vector<double>{0, 0, 1, 0, 0, 1, 1, 1}));
  const Network b = snl::generate_network(opts(20, 3, 4.0));
  ASSERT_EQ(b.num_anchors(), 8);
  for (int k = 0; k < 8; ++k)
    for (int d = 0; d < 3; ++d) EXPECT_EQ(b.anchors[k * 3 + d], double((k >> d) & 1));
}

TEST(Generate, RandomAnchors) {
  auto o = opts(5000, 2, 6.0);
  o.num_random_anchors = 300;
  const Network a = snl::generate_network(o);
  ASSERT_EQ(a.num_anchors(), 300);
  for (double v : a.anchors) {
    EXPECT_GT(v, 0.0);
    EXPECT_LT(v, 1.0);
  }
  EXPECT_EQ(a.anchors[3], snl::uniform01(o.seed, snl::RngStream::kAnchorPositions, 3));
  // The anchor grid finds exactly the anchors within the radius.
  GenerateReport rep;
  o.anchor_radius = 0.05;
  const Network b = snl::generate_network(o, &rep);
  EXPECT_EQ(rep.anchor_radius, 0.05);
  std::vector<snl::GlobalId> want;
  for (int i = 0; i < 5000; ++i)
    for (int k = 0; k < 300; ++k)
      if (dist2(&b.truth[i * 2], &b.anchors[k * 2], 2) <= 0.05 * 0.05) {
        want.push_back(i);
        want.push_back(k);
      }
  EXPECT_GT(want.size(), 0u);
  EXPECT_EQ(b.anchor_edges, want);
}

TEST(Generate, LargeAnchorRadiusMeasuresEveryAnchor) {
  for (int dim : {2, 3}) {
    auto o = opts(200, dim, 5.0);
    o.anchor_radius = 2.0;
    const Network net = snl::generate_network(o);
    const snl::GlobalId m = net.num_anchors();
    ASSERT_EQ(net.local_anchor_edges(), 200 * m);
    for (snl::GlobalId e = 0; e < net.local_anchor_edges(); ++e) {
      EXPECT_EQ(net.anchor_edges[2 * e], e / m);
      EXPECT_EQ(net.anchor_edges[2 * e + 1], e % m);
    }
  }
}

// The papers' networks (003, Sec. V): 10 sensors avg degree 4.3, 50 sensors 6.1.
TEST(Generate, PaperNetworksLocalizable) {
  for (auto [n, deg] : {std::pair<int, double>{10, 4.3}, {50, 6.1}}) {
    auto o = opts(n, 2, deg, 0.01, 42);
    o.localizable = Loc::kYes;
    GenerateReport rep;
    const Network net = snl::generate_network(o, &rep);
    EXPECT_GT(rep.draws, 1) << "the first draw was localizable: the redraw seed below is not tested";
    EXPECT_TRUE(rep.localizability.localizable());
    EXPECT_TRUE(rep.localizability.rigidity_checked);
    const auto again = snl::analyze_localizability(net, true);
    EXPECT_TRUE(again.localizable()) << again.summary();
    for (auto f : net.localizability) EXPECT_EQ(f, 0);
    EXPECT_LE(std::abs(net.local_sensor_edges() - std::llround(deg * n / 2)), 1);  // +-1 edge
    // The returned network is draw number rep.draws, reproducible from its seed.
    EXPECT_EQ(rep.draw_seed, snl::random_bits(42, snl::RngStream::kRedraw, rep.draws - 1));
    auto o2 = o;
    o2.seed = rep.draw_seed;
    o2.localizable = Loc::kNo;
    EXPECT_EQ(snl::generate_network(o2).truth, net.truth);
  }
}

TEST(Generate, AutoRedrawsSmallNetworks) {
  auto o = opts(10, 2, 4.3, 0.01, 42);
  o.localizable = Loc::kAuto;
  GenerateReport rep;
  snl::generate_network(o, &rep);
  EXPECT_TRUE(rep.localizability.localizable());
}

TEST(Generate, ThrowsWhenNoDrawIsLocalizable) {
  auto o = opts(10, 2, 0.5);
  o.localizable = Loc::kYes;
  o.max_draws = 3;
  EXPECT_THROW(snl::generate_network(o), snl::Error);
  // kAuto does not throw: it returns the last draw, flagged.
  o.localizable = Loc::kAuto;
  GenerateReport rep;
  const Network net = snl::generate_network(o, &rep);
  EXPECT_EQ(rep.draws, 3);
  EXPECT_FALSE(rep.localizability.localizable());
  bool any = false;
  for (auto f : net.localizability) any = any || f != 0;
  EXPECT_TRUE(any);
}

// The defaults: corners + 1% random anchors, the default degree, a region
// growing at constant density; default networks are localizable (redrawn).
TEST(Generate, DefaultNetworksAreLocalizable) {
  for (const snl::GlobalId n : {2000, 20000}) {
    GenerateOptions o;
    o.sensors = n;
    GenerateReport rep;
    const Network net = snl::generate_network(o, &rep);
    EXPECT_TRUE(rep.localizability.rigidity_checked) << "n=" << n;
    EXPECT_TRUE(rep.localizability.localizable()) << "n=" << n << ": " << rep.localizability.summary();
    EXPECT_EQ(rep.warning, "") << "n=" << n;
    EXPECT_EQ(net.num_anchors(), 4 + n / 100);
    EXPECT_NEAR(rep.achieved_avg_degree, snl::default_avg_degree(2), 0.01);
    EXPECT_DOUBLE_EQ(rep.side, std::sqrt(static_cast<double>(n) / snl::kReferenceSensors));
    for (const double v : net.truth) ASSERT_TRUE(v >= 0 && v <= rep.side);
    // The noise regime does not depend on n: sigma / radius is about that of 1,000 sensors in the unit square.
    EXPECT_NEAR(rep.radius, 0.0715, 0.004) << "n=" << n;
  }
}

TEST(Generate, RegionSideAndRelativeSigma) {
  GenerateOptions o;
  o.sensors = 1000;
  EXPECT_EQ(snl::region_side(o), 1.0);
  o.sensors = 8000;
  o.dim = 3;
  EXPECT_DOUBLE_EQ(snl::region_side(o), 2.0);
  o.side = 0.5;
  EXPECT_EQ(snl::region_side(o), 0.5);
  auto r = opts(500, 2, 8.0, 0.01, 9);
  r.sigma_rel = 0.05;
  GenerateReport rep;
  const Network net = snl::generate_network(r, &rep);
  ASSERT_TRUE(net.sigma.has_value());
  EXPECT_DOUBLE_EQ(*net.sigma, 0.05 * rep.radius);
  EXPECT_DOUBLE_EQ(rep.sigma, *net.sigma);
  r.sigma_rel = -1;
  EXPECT_NE(r.validate(), "");
}

TEST(Generate, WarnsWithNumbersWhenNotLocalizable) {
  auto o = opts(2000, 2, 6.0);  // the papers' corners at 2,000 sensors: hopeless
  o.localizable = Loc::kAuto;
  o.max_draws = 3;
  GenerateReport rep;
  snl::generate_network(o, &rep);
  EXPECT_NE(rep.warning.find("no fully localizable network in 3 draw(s)"), std::string::npos) << rep.warning;
  EXPECT_NE(rep.warning.find("of 2000 sensors"), std::string::npos) << rep.warning;
  EXPECT_NE(rep.warning.find("--avg-degree"), std::string::npos) << rep.warning;
  // Without redraws: a warning only above 1% of the sensors.
  o.localizable = Loc::kNo;
  o.avg_degree = 16;
  o.num_random_anchors = snl::kAutoAnchors;
  o.side = 0;
  snl::generate_network(o, &rep);
  EXPECT_EQ(rep.warning, "") << rep.warning;
}

TEST(Generate, NoRedrawFillsFlags) {
  GenerateReport rep;
  const Network net = snl::generate_network(opts(30000, 2, 5.0), &rep);
  EXPECT_EQ(rep.draws, 1);
  EXPECT_FALSE(rep.localizability.rigidity_checked);  // n > kRigidityLimit
  EXPECT_EQ(net.localizability, rep.localizability.flags);
  ASSERT_FALSE(rep.localizability.few_measurements.empty());  // Poisson degree 5: many have < 3
  for (auto i : rep.localizability.few_measurements) EXPECT_TRUE(net.localizability[i] & snl::kFewMeasurements);
}

TEST(Generate, Validation) {
  EXPECT_EQ(opts(10, 2, 4.3).validate(), "");
  EXPECT_NE(opts(0, 2, 4.3).validate(), "");
  EXPECT_NE(opts(10, 4, 4.3).validate(), "");
  EXPECT_EQ(opts(10, 2, snl::kAutoDegree).validate(), "");
  EXPECT_NE(opts(10, 2, -2).validate(), "");
  EXPECT_NE(opts(10, 2, 9.5).validate(), "");
  EXPECT_NE(opts(10, 2, NAN).validate(), "");
  EXPECT_NE(opts(10, 2, 4.3, -0.1).validate(), "");
  // Every later rule still applies at the default degree.
  EXPECT_NE(opts(10, 2, snl::kAutoDegree, -0.1).validate(), "");
  auto o = opts(10, 2, snl::kAutoDegree);
  o.side = NAN;
  EXPECT_NE(o.validate(), "");
  o = opts(10, 2, 4.3);
  o.num_random_anchors = -2;
  EXPECT_NE(o.validate(), "");
  o = opts(10, 2, 4.3);
  o.max_draws = 0;
  EXPECT_NE(o.validate(), "");
  EXPECT_THROW(snl::generate_network(opts(10, 2, 20)), snl::Error);
  // Complete graph is allowed.
  const Network full = snl::generate_network(opts(10, 3, 9));
  EXPECT_EQ(full.local_sensor_edges(), 45);
  EXPECT_EQ(snl::generate_network(opts(1, 2, 0)).local_sensor_edges(), 0);
  EXPECT_NE(opts(10, 0, 4.3).validate(), "");
  EXPECT_EQ(opts(10, 1, 4.3).validate(), "");
}

// 003 Fig. 2's star: one sensor at star_center, every anchor its neighbour,
// ranges |d + sigma N| with the anchor-noise counters; refusals.
TEST(Generate, Star) {
  snl::GenerateOptions o;
  o.dim = 1;
  o.sensors = 1;
  o.topology = snl::GenerateOptions::Topology::kStar;
  o.sigma = 0;
  const Network exact = snl::generate_network(o);
  EXPECT_EQ(exact.dim, 1);
  EXPECT_EQ(exact.truth, std::vector<double>{3.0});
  EXPECT_EQ(exact.anchors, (std::vector<double>{2.0, 4.0, 5.0}));
  EXPECT_EQ(exact.anchor_edges, (std::vector<snl::GlobalId>{0, 0, 0, 1, 0, 2}));
  EXPECT_EQ(exact.anchor_ranges, (std::vector<double>{1.0, 1.0, 2.0}));
  EXPECT_EQ(exact.local_sensor_edges(), 0);
  o.sigma = 0.25;
  o.seed = 9;
  const Network noisy = snl::generate_network(o);
  for (int k = 0; k < 3; ++k)
    EXPECT_EQ(noisy.anchor_ranges[k],
              std::abs(exact.anchor_ranges[k] + 0.25 * snl::standard_normal(9, snl::RngStream::kAnchorNoise, k)));
  EXPECT_NE(noisy.anchor_ranges, exact.anchor_ranges);
  auto bad = o;
  bad.dim = 2;
  EXPECT_NE(bad.validate().find("give --dim 1"), std::string::npos);
  bad = o;
  bad.sensors = 3;
  EXPECT_NE(bad.validate().find("give --sensors 1"), std::string::npos);
  bad = o;
  bad.star_anchors.clear();
  EXPECT_NE(bad.validate(), "");
  bad = o;
  bad.sigma_rel = 0.1;
  EXPECT_NE(bad.validate(), "");
}

}  // namespace
