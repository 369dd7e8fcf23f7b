// Validation and duplicate merging of networks held in memory. No MPI, no
// HDF5: these run on any slab and are fuzz targets.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <tuple>

#include "snl/io/network.hpp"

namespace snl {

namespace {

// Dataset order of NetworkIssue keys: the key is (order << 40) + 1 + row, so a
// shape problem of a dataset (row -1) comes before its first bad row.
enum Order : std::int64_t {
  kHeader = 0, kAnchors, kSensorEdges, kSensorRanges, kAnchorEdges, kAnchorRanges, kTruth, kSigma, kFlags,
  kSensorSigmas, kAnchorSigmas, kSensorNlos, kAnchorNlos
};

NetworkIssue issue(Order o, GlobalId row, std::string msg) {
  return NetworkIssue{(static_cast<std::int64_t>(o) << 40) + 1 + row, std::move(msg)};
}

std::string num(double v) {
  if (std::isnan(v)) return "NaN";
  if (std::isinf(v)) return v > 0 ? "Inf" : "-Inf";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

std::string s(GlobalId v) { return std::to_string(v); }

std::string range_text(GlobalId lo, GlobalId hi) { return "[" + s(lo) + ", " + s(hi) + ")"; }

/// Non-finite coordinate check of a row-major [rows, dim] block.
NetworkIssue check_coords(Order o, const char* name, const std::vector<double>& v, int dim, GlobalId offset) {
  for (std::size_t k = 0; k < v.size(); ++k) {
    if (!std::isfinite(v[k])) {
      const GlobalId row = offset + static_cast<GlobalId>(k / static_cast<std::size_t>(dim));
      return issue(o, row, std::string(name) + " row " + s(row) + ": coordinate " + s(static_cast<GlobalId>(k % dim)) +
                               " is " + num(v[k]));
    }
  }
  return {};
}

NetworkIssue check_ranges(Order o, const char* name, const std::vector<double>& r, GlobalId offset) {
  for (std::size_t e = 0; e < r.size(); ++e) {
    const double d = r[e];
    const GlobalId row = offset + static_cast<GlobalId>(e);
    if (!std::isfinite(d)) return issue(o, row, std::string(name) + " row " + s(row) + ": range is " + num(d));
    if (d < 0) return issue(o, row, std::string(name) + " row " + s(row) + ": range " + num(d) + " is negative");
  }
  return {};
}

constexpr double kMinSigma = 1e-150, kMaxSigma = 1e150;

/// Optional per-row sigmas: absent, or one finite positive value per range.
NetworkIssue check_sigmas(Order o, const char* name, const std::vector<double>& sg, std::size_t rows,
                          GlobalId offset) {
  if (sg.empty()) return {};
  if (sg.size() != rows)
    return issue(o, -1, std::string(name) + ": " + s(static_cast<GlobalId>(sg.size())) + " values, expected one per range (" +
                            s(static_cast<GlobalId>(rows)) + ")");
  for (std::size_t e = 0; e < sg.size(); ++e)
    if (!(sg[e] >= kMinSigma && sg[e] <= kMaxSigma)) {  // weights 1/sigma^2 must be finite and non-zero
      const GlobalId row = offset + static_cast<GlobalId>(e);
      return issue(o, row, std::string(name) + " row " + s(row) + ": sigma " + num(sg[e]) +
                               " is outside [1e-150, 1e150] (weights 1/sigma^2 must be finite and positive)");
    }
  return {};
}

/// Optional per-row NLOS flags: absent, or one 0/1 value per range.
NetworkIssue check_flags01(Order o, const char* name, const std::vector<std::uint8_t>& f, std::size_t rows,
                           GlobalId offset) {
  if (f.empty()) return {};
  if (f.size() != rows)
    return issue(o, -1, std::string(name) + ": " + s(static_cast<GlobalId>(f.size())) + " values, expected one per range (" +
                            s(static_cast<GlobalId>(rows)) + ")");
  for (std::size_t e = 0; e < f.size(); ++e)
    if (f[e] > 1) {
      const GlobalId row = offset + static_cast<GlobalId>(e);
      return issue(o, row, std::string(name) + " row " + s(row) + ": flag " + s(f[e]) + " is not 0 or 1");
    }
  return {};
}

}  // namespace

NetworkIssue check_network(const Network& net, bool whole) {
  const int p = net.dim;
  const GlobalId n = net.num_sensors;
  if (p < 1 || p > 3) return {0, "dim must be 1, 2 or 3, got " + s(p)};
  if (n < 1) return {0, "num_sensors must be >= 1, got " + s(n)};

  // anchors
  if (net.anchors.size() % static_cast<std::size_t>(p) != 0)
    return issue(kAnchors, -1, "anchors: " + s(static_cast<GlobalId>(net.anchors.size())) +
                                   " values, not a multiple of dim = " + s(p));
  const GlobalId m = net.num_anchors();
  if (auto i = check_coords(kAnchors, "anchors", net.anchors, p, 0); !i.ok()) return i;

  // sensor_edges, sensor_ranges
  const GlobalId E = static_cast<GlobalId>(net.sensor_ranges.size());
  if (net.sensor_edges.size() != 2 * net.sensor_ranges.size())
    return issue(kSensorEdges, -1,
                 "sensor_edges: " + s(static_cast<GlobalId>(net.sensor_edges.size())) + " values, expected 2 per row for " +
                     s(E) + " rows of sensor_ranges");
  for (GlobalId e = 0; e < E; ++e) {
    const GlobalId i = net.sensor_edges[2 * e], j = net.sensor_edges[2 * e + 1];
    const GlobalId row = net.sensor_edge_offset + e;
    for (GlobalId v : {i, j})
      if (v < 0 || v >= n)
        return issue(kSensorEdges, row,
                     "sensor_edges row " + s(row) + ": sensor index " + s(v) + " out of range " + range_text(0, n));
    if (i == j) return issue(kSensorEdges, row, "sensor_edges row " + s(row) + ": self-loop (" + s(i) + ", " + s(j) + ")");
  }
  if (auto i = check_ranges(kSensorRanges, "sensor_ranges", net.sensor_ranges, net.sensor_edge_offset); !i.ok())
    return i;

  // anchor_edges, anchor_ranges
  const GlobalId Ea = static_cast<GlobalId>(net.anchor_ranges.size());
  if (net.anchor_edges.size() != 2 * net.anchor_ranges.size())
    return issue(kAnchorEdges, -1,
                 "anchor_edges: " + s(static_cast<GlobalId>(net.anchor_edges.size())) + " values, expected 2 per row for " +
                     s(Ea) + " rows of anchor_ranges");
  for (GlobalId e = 0; e < Ea; ++e) {
    const GlobalId i = net.anchor_edges[2 * e], k = net.anchor_edges[2 * e + 1];
    const GlobalId row = net.anchor_edge_offset + e;
    if (i < 0 || i >= n)
      return issue(kAnchorEdges, row,
                   "anchor_edges row " + s(row) + ": sensor index " + s(i) + " out of range " + range_text(0, n));
    if (k < 0 || k >= m)
      return issue(kAnchorEdges, row,
                   "anchor_edges row " + s(row) + ": anchor index " + s(k) + " out of range " + range_text(0, m));
  }
  if (auto i = check_ranges(kAnchorRanges, "anchor_ranges", net.anchor_ranges, net.anchor_edge_offset); !i.ok())
    return i;

  // truth
  if (net.has_truth) {
    if (net.truth.size() % static_cast<std::size_t>(p) != 0)
      return issue(kTruth, -1, "truth: " + s(static_cast<GlobalId>(net.truth.size())) +
                                   " values, not a multiple of dim = " + s(p));
    const GlobalId rows = static_cast<GlobalId>(net.truth.size()) / p;
    if (whole ? rows != n : net.sensor_row_offset + rows > n)
      return issue(kTruth, -1,
                   "truth: " + s(rows) + " rows" + (whole ? "" : " from row " + s(net.sensor_row_offset)) +
                       ", expected num_sensors = " + s(n));
    if (auto i = check_coords(kTruth, "truth", net.truth, p, net.sensor_row_offset); !i.ok()) return i;
  }

  if (net.sigma) {
    const double sg = *net.sigma;
    if (!std::isfinite(sg)) return issue(kSigma, 0, "sigma is " + num(sg));
    if (sg < 0) return issue(kSigma, 0, "sigma " + num(sg) + " is negative");
  }

  if (!net.localizability.empty()) {
    const GlobalId rows = static_cast<GlobalId>(net.localizability.size());
    if (whole ? rows != n : net.sensor_row_offset + rows > n)
      return issue(kFlags, -1, "localizability/flags: " + s(rows) + " values, expected num_sensors = " + s(n));
  }
  if (auto i = check_sigmas(kSensorSigmas, "sensor_sigmas", net.sensor_sigmas, net.sensor_ranges.size(),
                            net.sensor_edge_offset); !i.ok())
    return i;
  if (auto i = check_sigmas(kAnchorSigmas, "anchor_sigmas", net.anchor_sigmas, net.anchor_ranges.size(),
                            net.anchor_edge_offset); !i.ok())
    return i;
  if (auto i = check_flags01(kSensorNlos, "sensor_nlos", net.sensor_nlos, net.sensor_ranges.size(),
                             net.sensor_edge_offset); !i.ok())
    return i;
  if (auto i = check_flags01(kAnchorNlos, "anchor_nlos", net.anchor_nlos, net.anchor_ranges.size(),
                             net.anchor_edge_offset); !i.ok())
    return i;
  return {};
}

void validate_network(const Network& net) {
  const bool whole = net.sensor_edge_offset == 0 && net.anchor_edge_offset == 0 && net.sensor_row_offset == 0 &&
                     (net.total_sensor_edges == 0 || net.total_sensor_edges == net.local_sensor_edges()) &&
                     (net.total_anchor_edges == 0 || net.total_anchor_edges == net.local_anchor_edges());
  const NetworkIssue i = check_network(net, whole);
  if (!i.ok()) throw Error(i.message);
}

namespace {

/// Sorts rows (a, b, r) by (a, b, r) and merges the rows of equal (a, b): the
/// mean of their ranges, or with sigmas the inverse-variance weighted mean and
/// the combined sigma; NLOS flags are or-ed. Returns the number of rows removed.
constexpr std::size_t kMaxRuns = 64;  // beyond this many ascending runs, one sort

GlobalId merge_rows(std::vector<GlobalId>& edges, std::vector<double>& ranges, MeasurementExtras x) {
  const std::size_t E = ranges.size();
  if (edges.size() != 2 * E) throw Error("merge_duplicates: edges and ranges disagree in length");
  std::vector<double>* sg = x.sigmas && !x.sigmas->empty() ? x.sigmas : nullptr;
  std::vector<std::uint8_t>* fl = x.nlos && !x.nlos->empty() ? x.nlos : nullptr;
  if ((sg && sg->size() != E) || (fl && fl->size() != E))
    throw Error("merge_duplicates: per-row sigmas or flags disagree in length with the ranges");
  // Fast path: already sorted with distinct pairs (e.g. generator output).
  // Else the starts of the ascending runs: rows gathered from P ranks' sorted
  // slabs come in P runs, which are merged instead of sorted.
  std::vector<std::size_t> runs{0};
  for (std::size_t e = 1; e < E && runs.size() <= kMaxRuns; ++e)
    if (std::tie(edges[2 * e - 2], edges[2 * e - 1]) >= std::tie(edges[2 * e], edges[2 * e + 1])) runs.push_back(e);
  if (runs.size() == 1) return 0;

  struct Row {
    GlobalId a, b;
    double r, sigma;
    std::uint8_t flag;
  };
  std::vector<Row> rows(E);
  for (std::size_t e = 0; e < E; ++e)
    rows[e] = {edges[2 * e], edges[2 * e + 1], ranges[e], sg ? (*sg)[e] : 1.0, fl ? (*fl)[e] : std::uint8_t{0}};
  // Ranges (then sigmas) are part of the key, so equal pairs meet in a fixed
  // order and the merged value does not depend on the order of the input rows.
  auto less = [](const Row& p, const Row& q) {
    return std::tie(p.a, p.b, p.r, p.sigma, p.flag) < std::tie(q.a, q.b, q.r, q.sigma, q.flag);
  };
  if (runs.size() > kMaxRuns) {
    std::sort(rows.begin(), rows.end(), less);
  } else {
    // A run is ascending in (a, b) with distinct pairs: in the full key too.
    // Adjacent runs are merged pairwise until one is left (log2 of the runs
    // passes over the rows).
    runs.push_back(E);
    while (runs.size() > 2) {
      std::vector<std::size_t> next{0};
      for (std::size_t k = 0; k + 1 < runs.size(); k += 2) {
        const std::size_t end = k + 2 < runs.size() ? runs[k + 2] : runs[k + 1];
        if (k + 2 < runs.size())
          std::inplace_merge(rows.begin() + runs[k], rows.begin() + runs[k + 1], rows.begin() + end, less);
        next.push_back(end);
      }
      runs.swap(next);
    }
  }
  std::size_t out = 0;
  std::vector<double> rs, ss;  // one pair's readings
  for (std::size_t e = 0; e < E;) {
    std::size_t f = e;
    while (f < E && rows[f].a == rows[e].a && rows[f].b == rows[e].b) ++f;
    std::uint8_t flag = 0;
    for (std::size_t t = e; t < f; ++t) flag |= rows[t].flag;
    double sigma = rows[e].sigma, range = rows[e].r;
    if (f - e > 1) {
      rs.clear();
      ss.clear();
      for (std::size_t t = e; t < f; ++t) {
        rs.push_back(rows[t].r);
        ss.push_back(rows[t].sigma);
      }
      range = merge_readings(rs.data(), sg ? ss.data() : nullptr, f - e, 1, &sigma);
    }
    edges[2 * out] = rows[e].a;
    edges[2 * out + 1] = rows[e].b;
    ranges[out] = range;
    if (sg) (*sg)[out] = sigma;
    if (fl) (*fl)[out] = flag;
    ++out;
    e = f;
  }
  edges.resize(2 * out);
  ranges.resize(out);
  if (sg) sg->resize(out);
  if (fl) fl->resize(out);
  return static_cast<GlobalId>(E - out);
}

}  // namespace

double merge_readings(const double* ranges, const double* sigmas, std::size_t count, std::size_t stride,
                      double* sigma) {
  if (count == 1) {
    if (sigmas) *sigma = sigmas[0];
    return ranges[0];
  }
  double sum = 0.0, wsum = 0.0;
  for (std::size_t t = 0; t < count; ++t) {
    const double w = sigmas ? 1.0 / (sigmas[t * stride] * sigmas[t * stride]) : 1.0;
    sum += w * ranges[t * stride];
    wsum += w;
  }
  double avg = sum / wsum;
  if (!std::isfinite(avg)) {  // the sum of huge ranges overflowed: average scaled terms
    avg = 0.0;
    for (std::size_t t = 0; t < count; ++t)
      avg += sigmas ? ranges[t * stride] * (1.0 / (sigmas[t * stride] * sigmas[t * stride]) / wsum)
                    : ranges[t * stride] / static_cast<double>(count);
  }
  if (sigmas) *sigma = 1.0 / std::sqrt(wsum);
  // Rounding must not take the mean outside [min, max] (the readings are ascending).
  return std::min(std::max(avg, ranges[0]), ranges[(count - 1) * stride]);
}

MergeStats merge_duplicates(std::vector<GlobalId>& sensor_edges, std::vector<double>& sensor_ranges,
                            std::vector<GlobalId>& anchor_edges, std::vector<double>& anchor_ranges) {
  for (std::size_t e = 0; e + 1 < sensor_edges.size(); e += 2)
    if (sensor_edges[e] > sensor_edges[e + 1]) std::swap(sensor_edges[e], sensor_edges[e + 1]);
  MergeStats st;
  st.merged_sensor_pairs = merge_rows(sensor_edges, sensor_ranges, {});
  st.merged_anchor_pairs = merge_rows(anchor_edges, anchor_ranges, {});
  return st;
}

MergeStats merge_duplicates(std::vector<GlobalId>& sensor_edges, std::vector<double>& sensor_ranges,
                            MeasurementExtras sensor_extras, std::vector<GlobalId>& anchor_edges,
                            std::vector<double>& anchor_ranges, MeasurementExtras anchor_extras) {
  for (std::size_t e = 0; e + 1 < sensor_edges.size(); e += 2)
    if (sensor_edges[e] > sensor_edges[e + 1]) std::swap(sensor_edges[e], sensor_edges[e + 1]);
  MergeStats st;
  st.merged_sensor_pairs = merge_rows(sensor_edges, sensor_ranges, sensor_extras);
  st.merged_anchor_pairs = merge_rows(anchor_edges, anchor_ranges, anchor_extras);
  return st;
}

}  // namespace snl
