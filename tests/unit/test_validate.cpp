// validate_network / check_network / merge_duplicates on in-memory networks.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <set>

#include "snl/io/network.hpp"

using namespace snl;

namespace {

/// 4 sensors in 2-D, 2 anchors, 3 sensor edges, 2 anchor edges, truth, sigma.
Network small() {
  Network n;
  n.dim = 2;
  n.num_sensors = 4;
  n.anchors = {0, 0, 1, 1};
  n.sensor_edges = {0, 1, 1, 2, 2, 3};
  n.sensor_ranges = {0.5, 0.6, 0.7};
  n.anchor_edges = {0, 0, 3, 1};
  n.anchor_ranges = {0.1, 0.2};
  n.has_truth = true;
  n.truth = {0.1, 0.1, 0.2, 0.2, 0.3, 0.3, 0.4, 0.4};
  n.sigma = 0.01;
  return n;
}

std::string error_of(const Network& n) {
  try {
    validate_network(n);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

#define EXPECT_INVALID(net, fragment)                                                          \
  do {                                                                                         \
    const std::string msg_ = error_of(net);                                                    \
    EXPECT_NE(msg_.find(fragment), std::string::npos) << "message: '" << msg_ << "'";          \
  } while (0)

const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

}  // namespace

TEST(Validate, ValidNetworkPasses) {
  EXPECT_NO_THROW(validate_network(small()));
  Network n = small();
  n.has_truth = false;
  n.truth.clear();
  n.sigma.reset();
  n.sensor_edges.clear();
  n.sensor_ranges.clear();
  EXPECT_NO_THROW(validate_network(n));
  n.dim = 3;
  n.anchors = {0, 0, 0};
  n.anchor_edges = {0, 0};
  n.anchor_ranges = {1.0};
  EXPECT_NO_THROW(validate_network(n));
}

TEST(Validate, Dim) {
  Network n = small();
  n.dim = 4;
  n.anchors = {0, 0, 0, 0};
  EXPECT_INVALID(n, "dim must be 1, 2 or 3, got 4");
  n.dim = 0;
  EXPECT_INVALID(n, "dim must be 1, 2 or 3, got 0");
}

TEST(Validate, NumSensors) {
  Network n = small();
  n.num_sensors = 0;
  EXPECT_INVALID(n, "num_sensors must be >= 1, got 0");
}

TEST(Validate, AnchorsShape) {
  Network n = small();
  n.anchors.push_back(3.0);
  EXPECT_INVALID(n, "anchors: 5 values, not a multiple of dim = 2");
}

TEST(Validate, AnchorsNonFinite) {
  Network n = small();
  n.anchors[3] = kNaN;
  EXPECT_INVALID(n, "anchors row 1: coordinate 1 is NaN");
  n.anchors[3] = -kInf;
  EXPECT_INVALID(n, "anchors row 1: coordinate 1 is -Inf");
}

TEST(Validate, SensorEdgesShape) {
  Network n = small();
  n.sensor_edges.push_back(0);
  EXPECT_INVALID(n, "sensor_edges: 7 values, expected 2 per row for 3 rows of sensor_ranges");
  n = small();
  n.sensor_ranges.pop_back();
  EXPECT_INVALID(n, "sensor_edges: 6 values, expected 2 per row for 2 rows");
}

TEST(Validate, SensorIndexOutOfRange) {
  Network n = small();
  n.sensor_edges[3] = 12;
  EXPECT_INVALID(n, "sensor_edges row 1: sensor index 12 out of range [0, 4)");
  n = small();
  n.sensor_edges[4] = -1;
  EXPECT_INVALID(n, "sensor_edges row 2: sensor index -1 out of range [0, 4)");
}

TEST(Validate, SelfLoop) {
  Network n = small();
  n.sensor_edges[5] = 2;
  EXPECT_INVALID(n, "sensor_edges row 2: self-loop (2, 2)");
}

TEST(Validate, SensorRangeNonFinite) {
  Network n = small();
  n.sensor_ranges[1] = kNaN;
  EXPECT_INVALID(n, "sensor_ranges row 1: range is NaN");
  n.sensor_ranges[1] = kInf;
  EXPECT_INVALID(n, "sensor_ranges row 1: range is Inf");
}

TEST(Validate, SensorRangeNegative) {
  Network n = small();
  n.sensor_ranges[2] = -0.5;
  EXPECT_INVALID(n, "sensor_ranges row 2: range -0.5 is negative");
  n.sensor_ranges[2] = 0.0;  // zero is a valid range
  EXPECT_NO_THROW(validate_network(n));
}

TEST(Validate, AnchorEdgesShape) {
  Network n = small();
  n.anchor_edges.pop_back();
  EXPECT_INVALID(n, "anchor_edges: 3 values, expected 2 per row for 2 rows of anchor_ranges");
}

TEST(Validate, AnchorEdgeSensorIndex) {
  Network n = small();
  n.anchor_edges[2] = 4;
  EXPECT_INVALID(n, "anchor_edges row 1: sensor index 4 out of range [0, 4)");
}

TEST(Validate, AnchorEdgeAnchorIndex) {
  Network n = small();
  n.anchor_edges[1] = 2;
  EXPECT_INVALID(n, "anchor_edges row 0: anchor index 2 out of range [0, 2)");
  n.anchors.clear();  // m == 0: every anchor edge is out of range
  n.anchor_edges[1] = 0;
  EXPECT_INVALID(n, "anchor_edges row 0: anchor index 0 out of range [0, 0)");
}

TEST(Validate, AnchorRange) {
  Network n = small();
  n.anchor_ranges[1] = kNaN;
  EXPECT_INVALID(n, "anchor_ranges row 1: range is NaN");
  n.anchor_ranges[1] = -1;
  EXPECT_INVALID(n, "anchor_ranges row 1: range -1 is negative");
}

TEST(Validate, TruthShape) {
  Network n = small();
  n.truth.resize(6);
  EXPECT_INVALID(n, "truth: 3 rows, expected num_sensors = 4");
  n.truth.resize(7);
  EXPECT_INVALID(n, "truth: 7 values, not a multiple of dim = 2");
}

TEST(Validate, TruthNonFinite) {
  Network n = small();
  n.truth[6] = kNaN;
  EXPECT_INVALID(n, "truth row 3: coordinate 0 is NaN");
}

TEST(Validate, Sigma) {
  Network n = small();
  n.sigma = kNaN;
  EXPECT_INVALID(n, "sigma is NaN");
  n.sigma = -0.1;
  EXPECT_INVALID(n, "sigma -0.10000000000000001 is negative");
}

TEST(Validate, LocalizabilityShape) {
  Network n = small();
  n.localizability = {0, 1, 2};
  EXPECT_INVALID(n, "localizability/flags: 3 values, expected num_sensors = 4");
  n.localizability.push_back(0);
  EXPECT_NO_THROW(validate_network(n));
}

TEST(Validate, RowsAreGlobalInSlabs) {
  // A slab: rows of the file start at the offsets; messages name global rows.
  Network n = small();
  n.sensor_edge_offset = 100;
  n.total_sensor_edges = 200;
  n.sensor_edges[3] = 9;
  EXPECT_INVALID(n, "sensor_edges row 101: sensor index 9 out of range [0, 4)");
  n = small();
  n.anchor_edge_offset = 50;
  n.total_anchor_edges = 60;
  n.anchor_ranges[1] = -2;
  EXPECT_INVALID(n, "anchor_ranges row 51: range -2 is negative");
  n = small();
  n.sensor_row_offset = 2;
  n.truth = {1, 1, kInf, 0};  // rows 2 and 3 of the whole truth
  EXPECT_INVALID(n, "truth row 3: coordinate 0 is Inf");
}

TEST(Validate, SlabTruthRowsMayBeFewer) {
  Network n = small();
  n.truth.resize(4);  // rows 0 and 1 of 4 only
  EXPECT_FALSE(check_network(n, /*whole=*/true).ok());
  EXPECT_TRUE(check_network(n, /*whole=*/false).ok());
  n.sensor_row_offset = 3;  // rows 3 and 4: beyond n
  EXPECT_FALSE(check_network(n, false).ok());
}

TEST(Validate, FirstViolationAndKeyOrder) {
  // Two problems: the one in the earlier dataset (sensor_edges) is reported, and
  // within a dataset the earlier row.
  Network n = small();
  n.sensor_ranges[0] = -1;
  n.sensor_edges[5] = 2;  // self-loop in row 2
  n.sensor_edges[3] = 2;  // row 1 becomes (1, 2)... make it a self-loop too
  n.sensor_edges[2] = 2;
  const NetworkIssue a = check_network(n, true);
  EXPECT_EQ(a.message, "sensor_edges row 1: self-loop (2, 2)");
  // Keys order rows within a dataset and datasets among themselves.
  Network r1 = small(), r2 = small(), r3 = small();
  r1.sensor_edges[1] = 0;  // row 0
  r2.sensor_edges[5] = 2;  // row 2
  r3.sensor_ranges[0] = -1;  // later dataset, row 0
  const auto k1 = check_network(r1, true).key, k2 = check_network(r2, true).key, k3 = check_network(r3, true).key;
  EXPECT_LT(k1, k2);
  EXPECT_LT(k2, k3);
}

TEST(Merge, CanonicalSortedAndAveraged) {
  std::vector<GlobalId> se = {3, 1, 0, 2, 1, 3, 2, 0, 1, 3};
  std::vector<double> sr = {1.0, 2.0, 3.0, 4.0, 5.0};
  std::vector<GlobalId> ae = {2, 1, 0, 0, 2, 1};
  std::vector<double> ar = {0.5, 0.25, 1.5};
  const MergeStats st = merge_duplicates(se, sr, ae, ar);
  // (3,1)=1, (0,2)=2, (1,3)=3, (2,0)=4, (1,3)=5 -> (0,2): mean(2,4), (1,3): mean(1,3,5)
  EXPECT_EQ(st.merged_sensor_pairs, 3);
  EXPECT_EQ(st.merged_anchor_pairs, 1);
  EXPECT_EQ(se, (std::vector<GlobalId>{0, 2, 1, 3}));
  EXPECT_EQ(sr, (std::vector<double>{3.0, 3.0}));
  EXPECT_EQ(ae, (std::vector<GlobalId>{0, 0, 2, 1}));
  EXPECT_EQ(ar, (std::vector<double>{0.25, 1.0}));
}

TEST(Merge, NoDuplicatesUnchangedExceptOrder) {
  std::vector<GlobalId> se = {0, 1, 1, 2, 2, 3};
  std::vector<double> sr = {1, 2, 3};
  std::vector<GlobalId> ae;
  std::vector<double> ar;
  const MergeStats st = merge_duplicates(se, sr, ae, ar);
  EXPECT_EQ(st.merged_sensor_pairs, 0);
  EXPECT_EQ(st.merged_anchor_pairs, 0);
  EXPECT_EQ(se, (std::vector<GlobalId>{0, 1, 1, 2, 2, 3}));
  EXPECT_EQ(sr, (std::vector<double>{1, 2, 3}));
  EXPECT_TRUE(ae.empty());
  EXPECT_TRUE(ar.empty());
}

TEST(Merge, OrderIndependentBitForBit) {
  // Many duplicates with ranges whose floating-point sum depends on order.
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<int> node(0, 9);
  std::uniform_real_distribution<double> val(0.0, 1.0);
  std::vector<GlobalId> se0, ae0;
  std::vector<double> sr0, ar0;
  for (int e = 0; e < 400; ++e) {
    int i = node(rng), j = node(rng);
    if (i == j) j = (j + 1) % 10;
    se0.insert(se0.end(), {i, j});
    sr0.push_back(val(rng) * std::pow(10.0, node(rng) - 5));
    ae0.insert(ae0.end(), {node(rng), node(rng) % 3});
    ar0.push_back(val(rng) * std::pow(10.0, node(rng) - 5));
  }
  auto se = se0, ae = ae0;
  auto sr = sr0, ar = ar0;
  const MergeStats ref = merge_duplicates(se, sr, ae, ar);
  EXPECT_GT(ref.merged_sensor_pairs, 0);
  EXPECT_GT(ref.merged_anchor_pairs, 0);
  EXPECT_EQ(static_cast<GlobalId>(sr.size()) + ref.merged_sensor_pairs, 400);
  for (std::size_t e = 0; e < sr.size(); ++e) EXPECT_LT(se[2 * e], se[2 * e + 1]);
  for (int trial = 0; trial < 5; ++trial) {
    std::vector<std::size_t> perm(400);
    std::iota(perm.begin(), perm.end(), 0);
    std::shuffle(perm.begin(), perm.end(), rng);
    std::vector<GlobalId> se2, ae2;
    std::vector<double> sr2, ar2;
    for (std::size_t k : perm) {
      // Also flip the orientation of half of the sensor pairs.
      if (k % 2) se2.insert(se2.end(), {se0[2 * k + 1], se0[2 * k]});
      else se2.insert(se2.end(), {se0[2 * k], se0[2 * k + 1]});
      sr2.push_back(sr0[k]);
      ae2.insert(ae2.end(), {ae0[2 * k], ae0[2 * k + 1]});
      ar2.push_back(ar0[k]);
    }
    const MergeStats st = merge_duplicates(se2, sr2, ae2, ar2);
    EXPECT_EQ(st.merged_sensor_pairs, ref.merged_sensor_pairs);
    EXPECT_EQ(st.merged_anchor_pairs, ref.merged_anchor_pairs);
    EXPECT_EQ(se2, se);
    EXPECT_EQ(ae2, ae);
    // Bit for bit, not approximately.
    ASSERT_EQ(sr2.size(), sr.size());
    for (std::size_t e = 0; e < sr.size(); ++e) EXPECT_EQ(sr2[e], sr[e]) << e;
    for (std::size_t e = 0; e < ar.size(); ++e) EXPECT_EQ(ar2[e], ar[e]) << e;
  }
}

// Rows that arrive as a few ascending runs (each rank's sorted slab, gathered)
// are merged run by run instead of sorted; the result must be the sort's, bit
// for bit, with duplicates across runs, for run counts on both sides of the
// limit (64) where one sort takes over.
TEST(Merge, SortedRunsGiveTheSortsResult) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> val(0.0, 1.0);
  for (int runs : {2, 3, 5, 64, 65, 70}) {
    std::vector<GlobalId> se_runs;
    std::vector<double> sr_runs;
    std::vector<std::pair<GlobalId, GlobalId>> all_pairs;
    std::vector<double> all_ranges;
    for (int r = 0; r < runs; ++r) {
      std::set<std::pair<GlobalId, GlobalId>> pairs;  // distinct and ascending within a run
      std::uniform_int_distribution<int> node(0, 19);
      while (pairs.size() < 40) {
        const int i = node(rng), j = node(rng);
        if (i != j) pairs.insert({std::min(i, j), std::max(i, j)});
      }
      for (const auto& pr : pairs) {
        const double range = val(rng);
        if (rng() % 2) se_runs.insert(se_runs.end(), {pr.second, pr.first});  // either orientation
        else se_runs.insert(se_runs.end(), {pr.first, pr.second});
        sr_runs.push_back(range);
        all_pairs.push_back(pr);
        all_ranges.push_back(range);
      }
    }
    // The reference: the same rows in random order (far more than 64 runs: one sort).
    std::vector<std::size_t> perm(all_ranges.size());
    std::iota(perm.begin(), perm.end(), 0);
    std::shuffle(perm.begin(), perm.end(), rng);
    std::vector<GlobalId> se_ref, ae, ae_ref;
    std::vector<double> sr_ref, ar, ar_ref;
    for (std::size_t k : perm) {
      se_ref.insert(se_ref.end(), {all_pairs[k].first, all_pairs[k].second});
      sr_ref.push_back(all_ranges[k]);
    }
    const MergeStats ref = merge_duplicates(se_ref, sr_ref, ae_ref, ar_ref);
    const MergeStats st = merge_duplicates(se_runs, sr_runs, ae, ar);
    EXPECT_GT(ref.merged_sensor_pairs, 0) << runs << " runs: the case needs duplicates across runs";
    EXPECT_EQ(st.merged_sensor_pairs, ref.merged_sensor_pairs) << runs << " runs";
    EXPECT_EQ(se_runs, se_ref) << runs << " runs";
    ASSERT_EQ(sr_runs.size(), sr_ref.size()) << runs << " runs";
    for (std::size_t e = 0; e < sr_ref.size(); ++e) EXPECT_EQ(sr_runs[e], sr_ref[e]) << runs << " runs, row " << e;
  }
}

TEST(Merge, AverageOfThree) {
  std::vector<GlobalId> se = {5, 4, 4, 5, 4, 5};
  std::vector<double> sr = {3.0, 1.0, 2.0};
  std::vector<GlobalId> ae;
  std::vector<double> ar;
  EXPECT_EQ(merge_duplicates(se, sr, ae, ar).merged_sensor_pairs, 2);
  EXPECT_EQ(se, (std::vector<GlobalId>{4, 5}));
  EXPECT_EQ(sr, (std::vector<double>{2.0}));
}

TEST(Merge, SigmasInverseVarianceAndFlagsOred) {
  // (1,2) read twice: range 1 with sigma 1, range 2 with sigma 0.5 (weight 4):
  // weighted mean (1 + 8) / 5 = 1.8, sigma (1 + 4)^(-1/2).
  std::vector<GlobalId> se = {2, 1, 0, 1, 1, 2};
  std::vector<double> sr = {1.0, 7.0, 2.0};
  std::vector<double> ss = {1.0, 0.3, 0.5};
  std::vector<std::uint8_t> sf = {0, 0, 1};
  std::vector<GlobalId> ae = {0, 0, 0, 0};
  std::vector<double> ar = {3.0, 5.0};
  std::vector<double> as;  // absent: plain mean
  std::vector<std::uint8_t> af = {1, 0};
  const MergeStats st = merge_duplicates(se, sr, {&ss, &sf}, ae, ar, {&as, &af});
  EXPECT_EQ(st.merged_sensor_pairs, 1);
  EXPECT_EQ(st.merged_anchor_pairs, 1);
  EXPECT_EQ(se, (std::vector<GlobalId>{0, 1, 1, 2}));
  ASSERT_EQ(sr.size(), 2u);
  EXPECT_EQ(sr[0], 7.0);
  EXPECT_NEAR(sr[1], 1.8, 1e-15);
  ASSERT_EQ(ss.size(), 2u);
  EXPECT_EQ(ss[0], 0.3);
  EXPECT_NEAR(ss[1], 1.0 / std::sqrt(5.0), 1e-15);
  EXPECT_EQ(sf, (std::vector<std::uint8_t>{0, 1}));
  EXPECT_EQ(ar, (std::vector<double>{4.0}));
  EXPECT_TRUE(as.empty());
  EXPECT_EQ(af, (std::vector<std::uint8_t>{1}));
}

TEST(Merge, ExtrasOfWrongLengthRefused) {
  std::vector<GlobalId> se = {0, 1, 1, 0};
  std::vector<double> sr = {1.0, 2.0};
  std::vector<double> ss = {1.0};
  std::vector<GlobalId> ae;
  std::vector<double> ar;
  EXPECT_THROW(merge_duplicates(se, sr, {&ss, nullptr}, ae, ar, {}), Error);
}
