// The CRLB on the maximal anchored rigid part: the identification of that part
// on hand-made frameworks (a rigid triangle with a dangling hinge, two rigid
// bodies joined by one bar, collinear anchors, 3D), the bound and the
// per-sensor covariances against a dense inverse of J restricted to the part
// (uniform and per-measurement sigmas), and the selected inversion against a
// dense inverse on random sparse SPD matrices.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>
#include <vector>

#include "snl/problem/analysis.hpp"
#include "snl/problem/generate.hpp"

#include "network_builder.hpp"

namespace {

using snl::GlobalId;
using snl::Network;

using Builder = snl::test::NetworkBuilder;
using snl::test::kCorners;

std::vector<GlobalId> covered(const Network& net) { return snl::rigid_anchored_part(net, net.truth).covered; }

// Dense reference: J over the sensors in `part` only (measurements among them
// and to anchors), w = 1/sigma^2 per row (sigma_s/sigma_a per row if given,
// else `sigma`); returns J^-1 (rows in the order of `part`).
Eigen::MatrixXd dense_inverse(const Network& net, const std::vector<GlobalId>& part, double sigma) {
  const int p = net.dim;
  std::vector<int> at(static_cast<std::size_t>(net.num_sensors), -1);
  for (std::size_t c = 0; c < part.size(); ++c) at[static_cast<std::size_t>(part[c])] = static_cast<int>(c);
  const int N = static_cast<int>(part.size()) * p;
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(N, N);
  auto uvec = [&](const double* a, const double* b) {
    Eigen::VectorXd u(p);
    for (int d = 0; d < p; ++d) u[d] = a[d] - b[d];
    return Eigen::VectorXd(u / u.norm());
  };
  for (std::size_t e = 0; e < net.sensor_ranges.size(); ++e) {
    const auto i = net.sensor_edges[2 * e], j = net.sensor_edges[2 * e + 1];
    const int ci = at[i], cj = at[j];
    if (ci < 0 || cj < 0) continue;
    const double s = net.sensor_sigmas.empty() ? sigma : net.sensor_sigmas[e];
    const Eigen::VectorXd u = uvec(&net.truth[i * p], &net.truth[j * p]);
    const Eigen::MatrixXd B = u * u.transpose() / (s * s);
    J.block(ci * p, ci * p, p, p) += B;
    J.block(cj * p, cj * p, p, p) += B;
    J.block(ci * p, cj * p, p, p) -= B;
    J.block(cj * p, ci * p, p, p) -= B;
  }
  for (std::size_t e = 0; e < net.anchor_ranges.size(); ++e) {
    const auto i = net.anchor_edges[2 * e], k = net.anchor_edges[2 * e + 1];
    const int ci = at[i];
    if (ci < 0) continue;
    const double s = net.anchor_sigmas.empty() ? sigma : net.anchor_sigmas[e];
    const Eigen::VectorXd u = uvec(&net.truth[i * p], &net.anchors[k * p]);
    J.block(ci * p, ci * p, p, p) += u * u.transpose() / (s * s);
  }
  EXPECT_GT(J.ldlt().vectorD().minCoeff(), 1e-8) << "reference J must be positive definite on the part";
  return J.inverse();
}

// The bound (rmse and every covariance block) against the dense inverse on the part.
void expect_matches_dense(const Network& net, double sigma, bool per_measurement) {
  snl::CrlbOptions o;
  o.sigma = per_measurement ? -1 : sigma;
  o.covariance = true;
  const auto c = snl::cramer_rao_bound(net, o);
  ASSERT_TRUE(c.defined) << c.reason;
  const auto part = covered(net);
  ASSERT_EQ(c.covered, static_cast<GlobalId>(part.size()));
  EXPECT_EQ(c.outside.size() + part.size(), static_cast<std::size_t>(net.num_sensors));
  const Eigen::MatrixXd inv = dense_inverse(net, part, sigma);
  const double want = std::sqrt(inv.trace() / static_cast<double>(part.size()));
  EXPECT_NEAR(c.rmse, want, 1e-9 * want);
  const int p = net.dim;
  std::vector<char> in(static_cast<std::size_t>(net.num_sensors), 0);
  for (std::size_t k = 0; k < part.size(); ++k) {
    in[static_cast<std::size_t>(part[k])] = 1;
    for (int a = 0; a < p; ++a)
      for (int b = 0; b < p; ++b) {
        const double got = c.covariance[(static_cast<std::size_t>(part[k]) * p + a) * p + b];
        const double ref = inv(static_cast<int>(k) * p + a, static_cast<int>(k) * p + b);
        EXPECT_NEAR(got, ref, 1e-9 * std::abs(inv(static_cast<int>(k) * p + a, static_cast<int>(k) * p + a)))
            << "sensor " << part[k] << " (" << a << "," << b << ")";
      }
  }
  for (std::size_t i = 0; i < in.size(); ++i)
    if (!in[i])
      for (int t = 0; t < p * p; ++t) EXPECT_EQ(c.covariance[i * p * p + t], 0.0) << "outside sensor " << i;
}

// Sensors 0-2: a triangle pinned by three anchor ranges (6 bars on 6 degrees
// of freedom). Sensors 3, 4: a hinge hanging from it by 3-2, 4-3, 4-1 (three
// bars on four degrees of freedom): it swings.
Builder triangle_with_hinge() {
  Builder b({0.3, 0.3, 0.6, 0.35, 0.45, 0.6, 0.5, 0.9, 0.8, 0.7}, kCorners);
  b.s(0, 1).s(1, 2).s(0, 2).a(0, 0).a(0, 2).a(1, 1);
  b.s(3, 2).s(4, 3).s(4, 1);
  return b;
}

TEST(RigidPart, TriangleWithDanglingHinge) {
  Builder b = triangle_with_hinge();
  const auto r = snl::rigid_anchored_part(b.done(), b.net.truth);
  EXPECT_TRUE(r.identified) << r.reason;
  EXPECT_EQ(r.covered, (std::vector<GlobalId>{0, 1, 2}));
  EXPECT_EQ(r.outside, (std::vector<GlobalId>{3, 4}));
  // One more bar from the hinge to the body braces it.
  b.s(4, 0);
  EXPECT_EQ(covered(b.done()), (std::vector<GlobalId>{0, 1, 2, 3, 4}));
}

TEST(RigidPart, TwoRigidBodiesJoinedByOneBar) {
  // Body A: sensors 0-2, pinned as above. Body B: triangle 3-5, braced in
  // itself, joined to A by one bar (two degrees of freedom left), then two, then three.
  Builder b({0.3, 0.3, 0.6, 0.35, 0.45, 0.6, 0.7, 0.7, 0.9, 0.75, 0.8, 0.95}, kCorners);
  b.s(0, 1).s(1, 2).s(0, 2).a(0, 0).a(0, 2).a(1, 1);
  b.s(3, 4).s(4, 5).s(3, 5);
  b.s(3, 2);
  EXPECT_EQ(covered(b.done()), (std::vector<GlobalId>{0, 1, 2}));
  b.s(4, 1);
  EXPECT_EQ(covered(b.done()), (std::vector<GlobalId>{0, 1, 2}));
  b.s(5, 2);
  EXPECT_EQ(covered(b.done()), (std::vector<GlobalId>{0, 1, 2, 3, 4, 5}));
}

TEST(RigidPart, NonGenericAndUnanchored) {
  // Sensor 0 on the line through its two anchors: counting says rigid, J is
  // singular (it moves across the line). Sensor 1 is pinned by two anchors
  // off a line; sensors 2-3 form a component with no anchor.
  std::vector<double> anchors = {0, 0.5, 1, 0.5, 0, 0, 1, 0};
  Builder b({0.5, 0.5, 0.4, 0.2, 0.2, 0.8, 0.3, 0.9}, anchors);
  b.a(0, 0).a(0, 1).a(1, 2).a(1, 3).s(2, 3);
  const auto r = snl::rigid_anchored_part(b.done(), b.net.truth);
  EXPECT_EQ(r.covered, (std::vector<GlobalId>{1}));
  EXPECT_EQ(r.outside, (std::vector<GlobalId>{0, 2, 3}));
}

TEST(RigidPart, ThreeDimensions) {
  // Sensor 0 measures four anchors off a plane. Sensors 1 and 2 each measure
  // sensor 0, one anchor and each other: three measurements each (nothing to
  // peel), five bars on six degrees of freedom: they move. One more anchor
  // range fixes them.
  const std::vector<double> anchors = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  Builder b({0.3, 0.3, 0.3, 0.7, 0.6, 0.5, 0.4, 0.8, 0.2}, anchors, 3);
  b.a(0, 0).a(0, 1).a(0, 2).a(0, 3).s(1, 0).a(1, 1).s(2, 0).a(2, 2).s(1, 2);
  EXPECT_EQ(covered(b.done()), (std::vector<GlobalId>{0}));
  b.a(1, 3);
  EXPECT_EQ(covered(b.done()), (std::vector<GlobalId>{0, 1, 2}));
}

TEST(CrlbPart, HingeMatchesDenseOnTheRigidPart) {
  Builder b = triangle_with_hinge();
  const Network net = b.done();
  expect_matches_dense(net, 0.05, false);
  // Per-measurement sigmas: w = 1/sigma_ij^2 in J.
  Network w = net;
  w.sensor_sigmas = {0.01, 0.02, 0.03, 0.04, 0.05, 0.06};
  w.anchor_sigmas = {0.05, 0.01, 0.02};
  expect_matches_dense(w, 0.0, true);
  const auto cu = snl::cramer_rao_bound(net, 0.05);
  EXPECT_FALSE(cu.weighted);
  snl::CrlbOptions o;
  const auto cw = snl::cramer_rao_bound(w, o);
  EXPECT_TRUE(cw.weighted);
  EXPECT_NE(cu.rmse, cw.rmse);
}

TEST(CrlbPart, GeneratedNetworkWithFlexiblePartMatchesDense) {
  for (int dim : {2, 3}) {
    snl::GenerateOptions o;
    o.sensors = dim == 2 ? 150 : 80;
    o.dim = dim;
    o.avg_degree = dim == 2 ? 4.5 : 6.0;
    o.seed = 11;
    o.num_random_anchors = 6;
    o.localizable = snl::GenerateOptions::Localizable::kNo;
    const Network net = snl::generate_network(o);
    const auto r = snl::rigid_anchored_part(net, net.truth);
    ASSERT_TRUE(r.identified) << r.reason;
    ASSERT_GT(r.covered.size(), 10u) << "p=" << dim;
    ASSERT_GT(r.outside.size(), 0u) << "p=" << dim << ": the test wants a flexible part";
    expect_matches_dense(net, 0.02, false);
    // The localizability report agrees: flagged unanchored/not rigid is outside,
    // unflagged is inside.
    const auto rep = snl::analyze_localizability(net, true);
    ASSERT_TRUE(rep.rigidity_checked);
    std::vector<char> in(static_cast<std::size_t>(net.num_sensors), 0);
    for (const GlobalId i : r.covered) in[static_cast<std::size_t>(i)] = 1;
    for (std::size_t i = 0; i < in.size(); ++i) {
      if (rep.flags[i] & (snl::kUnanchoredComponent | snl::kNotRigid)) EXPECT_FALSE(in[i]) << i;
      if (rep.flags[i] == 0) EXPECT_TRUE(in[i]) << i;
    }
  }
}

TEST(CrlbPart, NothingRigid) {
  Builder b({0.3, 0.4, 0.6, 0.6}, kCorners);
  b.a(0, 0).s(0, 1);
  const auto c = snl::cramer_rao_bound(b.done(), 0.1);
  EXPECT_FALSE(c.defined);
  EXPECT_FALSE(c.reason.empty());
  EXPECT_EQ(c.outside, (std::vector<GlobalId>{0, 1}));
}

TEST(SelectedInversion, RandomSparseSpdAgainstDense) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> U(-1, 1);
  for (int p : {1, 2, 3}) {
    for (int trial = 0; trial < 4; ++trial) {
      const int N = p * (20 + 15 * trial);
      Eigen::MatrixXd A = Eigen::MatrixXd::Zero(N, N);
      std::uniform_int_distribution<int> pick(0, N - 1);
      for (int k = 0; k < 3 * N; ++k) {  // random sparse off-diagonal pattern
        const int i = pick(rng), j = pick(rng);
        if (i == j) continue;
        const double v = U(rng);
        A(i, j) += v;
        A(j, i) += v;
      }
      for (int b = 0; b < N / p; ++b)  // dense diagonal blocks, as in a Fisher information
        for (int r = 0; r < p; ++r)
          for (int c = 0; c < r; ++c) A(b * p + r, b * p + c) = A(b * p + c, b * p + r) = U(rng);
      for (int i = 0; i < N; ++i) A(i, i) = A.row(i).cwiseAbs().sum() + 0.1 + std::abs(U(rng));  // SPD
      std::vector<int> rows, cols;
      std::vector<double> vals;
      for (int i = 0; i < N; ++i)
        for (int j = 0; j < N; ++j)
          if (A(i, j) != 0) rows.push_back(i), cols.push_back(j), vals.push_back(A(i, j));
      std::vector<double> blocks;
      double trace = 0;
      ASSERT_TRUE(snl::inverse_diagonal_blocks(N, rows, cols, vals, p, blocks, trace));
      const Eigen::MatrixXd inv = A.inverse();
      EXPECT_NEAR(trace, inv.trace(), 1e-11 * inv.trace());
      for (int b = 0; b < N / p; ++b)
        for (int r = 0; r < p; ++r)
          for (int c = 0; c < p; ++c)
            EXPECT_NEAR(blocks[(static_cast<std::size_t>(b) * p + r) * p + c], inv(b * p + r, b * p + c), 1e-12)
                << "p=" << p << " N=" << N << " block " << b;
    }
  }
  // Not positive definite: refused.
  std::vector<double> blocks;
  double trace = 0;
  EXPECT_FALSE(snl::inverse_diagonal_blocks(2, {0, 1}, {0, 1}, {1.0, -1.0}, 1, blocks, trace));
}

}  // namespace
