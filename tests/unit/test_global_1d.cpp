// The exact global ML optimum of 1-D networks (src/problem/global_1d.cpp)
// against brute force: a dense grid (one sensor) and a grid refined around
// its best point (two sensors); its refusals.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "snl/problem/global_1d.hpp"
#include "io_helpers.hpp"

using namespace snl;

namespace {

// The message of the Error that global_ml_optimum_1d throws ("(no error)" if none).
std::string refusal(const Network& n, const GlobalOptimum1DOptions& o = {}) {
  try {
    global_ml_optimum_1d(n, o);
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

double ml_cost(const Network& n, const std::vector<double>& x) {
  double f = 0;
  for (std::size_t e = 0; e < n.sensor_ranges.size(); ++e) {
    const double z = std::abs(x[n.sensor_edges[2 * e]] - x[n.sensor_edges[2 * e + 1]]) - n.sensor_ranges[e];
    f += 0.5 * z * z;
  }
  for (std::size_t e = 0; e < n.anchor_ranges.size(); ++e) {
    const double z = std::abs(x[n.anchor_edges[2 * e]] - n.anchors[n.anchor_edges[2 * e + 1]]) - n.anchor_ranges[e];
    f += 0.5 * z * z;
  }
  return f;
}

// 003 Fig. 2's star, ranges chosen so that f has three local minima.
Network star() {
  Network n;
  n.dim = 1;
  n.num_sensors = 1;
  n.anchors = {2.0, 4.0, 5.0};
  n.anchor_edges = {0, 0, 0, 1, 0, 2};
  n.anchor_ranges = {0.7, 1.3, 2.4};
  return n;
}

// Two sensors, one range between them, two anchors each.
Network pair() {
  Network n;
  n.dim = 1;
  n.num_sensors = 2;
  n.anchors = {0.0, 1.0, 3.0};
  n.sensor_edges = {0, 1};
  n.sensor_ranges = {1.4};
  n.anchor_edges = {0, 0, 0, 1, 1, 1, 1, 2};
  n.anchor_ranges = {0.9, 0.3, 0.6, 1.1};
  return n;
}

}  // namespace

TEST(GlobalOptimum1D, StarMatchesDenseGrid) {
  const Network n = star();
  const GlobalOptimum1D g = global_ml_optimum_1d(n);
  EXPECT_EQ(g.patterns, 8u);
  ASSERT_EQ(g.positions.size(), 1u);
  EXPECT_NEAR(g.cost, ml_cost(n, g.positions), 1e-15);
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k <= 2000000; ++k) best = std::min(best, ml_cost(n, {-1.0 + 8.0 * k / 2000000}));
  EXPECT_LE(g.cost, best + 1e-12);
  EXPECT_NEAR(g.cost, best, 1e-9);  // grid step 4e-6, curvature 3: error < 3e-11
}

TEST(GlobalOptimum1D, PairMatchesRefinedGrid) {
  const Network n = pair();
  const GlobalOptimum1D g = global_ml_optimum_1d(n);
  EXPECT_EQ(g.patterns, 32u);
  double best = std::numeric_limits<double>::infinity(), bx = 0, by = 0;
  for (int a = 0; a <= 800; ++a)
    for (int b = 0; b <= 800; ++b) {
      const double x = -2.0 + 7.0 * a / 800, y = -2.0 + 7.0 * b / 800, f = ml_cost(n, {x, y});
      if (f < best) best = f, bx = x, by = y;
    }
  for (double h = 7.0 / 800; h > 1e-7; h /= 2)  // pattern search around the grid's best point
    for (bool moved = true; moved;) {
      moved = false;
      for (const auto& [dx, dy] : {std::pair{h, 0.0}, {-h, 0.0}, {0.0, h}, {0.0, -h}})
        if (const double f = ml_cost(n, {bx + dx, by + dy}); f < best) best = f, bx += dx, by += dy, moved = true;
    }
  EXPECT_LE(g.cost, best + 1e-12);
  EXPECT_NEAR(g.cost, best, 1e-9);
  EXPECT_NEAR(g.positions[0], bx, 1e-4);
  EXPECT_NEAR(g.positions[1], by, 1e-4);
}

TEST(GlobalOptimum1D, Refusals) {
  Network two_d = star();
  two_d.dim = 2;
  two_d.anchors = {2, 0, 4, 0, 5, 0};
  EXPECT_CONTAINS(refusal(two_d), "one-dimensional networks (dim 1), got dim 2");
  GlobalOptimum1DOptions small;
  small.max_terms = 2;
  EXPECT_CONTAINS(refusal(star(), small), "T = 3 measurements, more than the limit 2");
  Network loose = pair();
  loose.anchor_edges = {0, 0, 0, 1};  // sensor 1 only through the range to sensor 0 ...
  loose.anchor_ranges = {0.9, 0.3};
  EXPECT_NO_THROW(global_ml_optimum_1d(loose));
  loose.sensor_edges.clear();  // ... and now not at all
  loose.sensor_ranges.clear();
  EXPECT_CONTAINS(refusal(loose), "every connected component to measure an anchor");
}
