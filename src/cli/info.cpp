// snl info: summary and validation of a network file (on rank 0), or of a
// consensus problem or result (src/cli/consensus_files.cpp).
#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include "cli/cli_util.hpp"
#include "core/json.hpp"
#include "snl/cli/commands.hpp"
#include "snl/io/network.hpp"
#include "snl/problem/analysis.hpp"

namespace snl {

using detail::fmt;
using detail::is_root;

namespace {

// Median of the measured sensor-sensor ranges (anchor ranges if there are none);
// NaN when the network has no range at all.
double median_range(const Network& net) {
  std::vector<double> r = net.sensor_ranges.empty() ? net.anchor_ranges : net.sensor_ranges;
  if (r.empty()) return std::nan("");
  const auto mid = r.begin() + static_cast<std::ptrdiff_t>(r.size() / 2);
  std::nth_element(r.begin(), mid, r.end());
  return *mid;
}

// "sigma S, median range R: sigma / median range Q", with n/a and the reason for what is missing.
std::string noise_regime(const Network& net, double med) {
  std::ostringstream os;
  os << "sigma " << (net.sigma ? fmt(*net.sigma) : std::string("unknown")) << ", median range "
     << (std::isfinite(med) ? fmt(med, 4) : std::string("n/a (no ranges)")) << ", sigma / median range ";
  if (net.sigma && std::isfinite(med) && med > 0)
    os << fmt(*net.sigma / med, 3);
  else
    os << "n/a (" << (!net.sigma ? "sigma unknown" : "no positive range") << ")";
  return os.str();
}

}  // namespace

void run_info(const InfoCommand& cmd, MPI_Comm comm) {
  std::string text, json;
  bool unlocalizable = false;
  collective_try(comm, [&] {
    if (!is_root(comm)) return;
    // A consensus problem or result (docs/consensus.md) has a summary of its own.
    if (const std::string format = detail::hdf5_format(cmd.network);
        format == "snl-consensus" || format == "snl-consensus-result") {
      text = detail::consensus_info(cmd.network, format, &json);
      if (!cmd.json.empty()) write_text_atomic(cmd.json, json);
      return;
    }
    Network net = read_network_serial(cmd.network);
    const MergeStats ms = merge_duplicates(net.sensor_edges, net.sensor_ranges, net.anchor_edges, net.anchor_ranges);
    net.total_sensor_edges = net.local_sensor_edges();
    net.total_anchor_edges = net.local_anchor_edges();
    const DegreeStats ds = degree_stats(net);
    const bool rig = net.has_truth && net.num_sensors <= kRigidityLimit;
    const LocalizabilityReport lr = analyze_localizability(net, rig);
    const double med = median_range(net);
    const double nan = std::nan("");
    const double sigma = net.sigma ? *net.sigma : nan;
    std::ostringstream os;
    os << cmd.network << ": valid snl-network v1\n"
       << "  sensors n = " << net.num_sensors << ", anchors m = " << net.num_anchors() << ", dimension p = " << net.dim
       << "\n"
       << "  sensor pairs = " << net.local_sensor_edges() << " (" << ms.merged_sensor_pairs
       << " duplicate rows merged), anchor pairs = " << net.local_anchor_edges() << " (" << ms.merged_anchor_pairs
       << " merged)\n"
       << "  sensor degree: mean " << fmt(ds.mean, 4) << ", min " << ds.min << ", max " << ds.max
       << "; anchor measurements per sensor: mean " << fmt(ds.mean_anchor, 4) << ", max " << ds.max_anchor << "\n"
       << "  truth: " << (net.has_truth ? "present" : "absent") << "; " << noise_regime(net, med) << "\n"
       << "  " << lr.summary();
    if (!rig) os << "\n  (rigidity not checked: " << (net.has_truth ? "n > 20000" : "no truth positions") << ")";
    if (net.num_anchors() == 0) os << "\n  warning: no anchors; snl solve needs at least one";
    text = os.str();
    unlocalizable = !lr.localizable();
    JsonObject j;
    j.add("network", cmd.network)
        .add("num_sensors", static_cast<std::int64_t>(net.num_sensors))
        .add("num_anchors", static_cast<std::int64_t>(net.num_anchors()))
        .add("dim", net.dim)
        .add("sensor_pairs", static_cast<std::int64_t>(net.local_sensor_edges()))
        .add("anchor_pairs", static_cast<std::int64_t>(net.local_anchor_edges()))
        .add("merged_sensor_rows", static_cast<std::int64_t>(ms.merged_sensor_pairs))
        .add("merged_anchor_rows", static_cast<std::int64_t>(ms.merged_anchor_pairs))
        .add("mean_degree", ds.mean)
        .add("min_degree", ds.min)
        .add("max_degree", ds.max)
        .add("components", static_cast<std::int64_t>(lr.components))
        .add("unanchored_sensors", static_cast<std::int64_t>(lr.unanchored.size()))
        .add("few_measurement_sensors", static_cast<std::int64_t>(lr.few_measurements.size()))
        .add_bool("rigidity_checked", lr.rigidity_checked)
        .add_bool("rigid", lr.rigid)
        .add_bool("localizable", lr.localizable())
        .add_bool("has_truth", net.has_truth)
        .add("sigma", sigma)  // null when unknown
        .add("median_range", med)
        .add("sigma_over_median_range", std::isfinite(sigma) && med > 0 ? sigma / med : nan);
    json = j.str();
    if (!cmd.json.empty()) write_text_atomic(cmd.json, json);
  });
  if (is_root(comm)) std::printf("%s\n", text.c_str());
  int bad = unlocalizable ? 1 : 0;
  MPI_Bcast(&bad, 1, MPI_INT, 0, comm);
  if (cmd.strict && bad) throw Error(cmd.network + ": some sensors cannot be localized (--strict)");
}

}  // namespace snl
