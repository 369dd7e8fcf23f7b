// Fraction of localizable sensors against average degree for the generator's
// default networks (corners + 1% random anchors, constant density beyond 1,000
// sensors): the measurement behind the default degree (docs/generator.md).
//   snl_localizability N DIM SEEDS DEG [DEG ...]   -> one JSON line per draw
// Connectivity, anchoring and measurement counts are exact on the whole
// network. Infinitesimal rigidity is exact (the Fisher information of the whole
// anchored framework) up to snl::kRigidityLimit sensors; beyond, it is decided
// in overlapping windows: each window's core plus a margin of kMarginRadii link
// radii is analysed as a network of its own and only its core sensors are
// counted (flexibility of a random geometric graph is local; the run at
// n = 20,000 with SNL_WINDOWS=1 compares both methods on the same draws).
#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "snl/problem/analysis.hpp"
#include "snl/problem/generate.hpp"

namespace {

using snl::GlobalId;
using snl::Network;

constexpr double kMarginRadii = 6.0;
constexpr double kWindowSensors = 15000;  // core + margin, below kRigidityLimit

// The sensors of `net` (2D) in [x0 - m, x1 + m] x [y0 - m, y1 + m], renumbered,
// with the measurements among them and to the anchors; ids maps back.
Network window(const Network& net, const double box[4], double m, std::vector<GlobalId>& ids) {
  const auto n = static_cast<std::size_t>(net.num_sensors);
  std::vector<GlobalId> local(n, -1);
  ids.clear();
  for (std::size_t i = 0; i < n; ++i) {
    const double x = net.truth[2 * i], y = net.truth[2 * i + 1];
    if (x >= box[0] - m && x <= box[1] + m && y >= box[2] - m && y <= box[3] + m) {
      local[i] = static_cast<GlobalId>(ids.size());
      ids.push_back(static_cast<GlobalId>(i));
    }
  }
  Network w;
  w.dim = 2;
  w.num_sensors = static_cast<GlobalId>(ids.size());
  w.anchors = net.anchors;
  w.has_truth = true;
  for (const GlobalId i : ids) {
    w.truth.push_back(net.truth[2 * i]);
    w.truth.push_back(net.truth[2 * i + 1]);
  }
  for (std::size_t e = 0; e + 1 < net.sensor_edges.size(); e += 2) {
    const GlobalId a = local[net.sensor_edges[e]], b = local[net.sensor_edges[e + 1]];
    if (a < 0 || b < 0) continue;
    w.sensor_edges.push_back(a);
    w.sensor_edges.push_back(b);
    w.sensor_ranges.push_back(net.sensor_ranges[e / 2]);
  }
  for (std::size_t e = 0; e + 1 < net.anchor_edges.size(); e += 2) {
    const GlobalId a = local[net.anchor_edges[e]];
    if (a < 0) continue;
    w.anchor_edges.push_back(a);
    w.anchor_edges.push_back(net.anchor_edges[e + 1]);
    w.anchor_ranges.push_back(net.anchor_ranges[e / 2]);
  }
  w.total_sensor_edges = w.local_sensor_edges();
  w.total_anchor_edges = w.local_anchor_edges();
  return w;
}

// Flexible sensors (kNotRigid) by windows; returns the number of windows.
int windowed_rigidity(const Network& net, double side, double radius, std::vector<std::uint8_t>& flex) {
  const double density = static_cast<double>(net.num_sensors) / (side * side);
  const double m = kMarginRadii * radius;
  const double outer = std::sqrt(kWindowSensors / density);
  const int k = std::max(1, static_cast<int>(std::ceil(side / std::max(outer - 2 * m, 0.25 * outer))));
  const double w = side / k;
  std::vector<GlobalId> ids;
  int windows = 0;
  for (int a = 0; a < k; ++a)
    for (int b = 0; b < k; ++b) {
      const double box[4] = {a * w, (a + 1) * w, b * w, (b + 1) * w};
      const Network sub = window(net, box, m, ids);
      const snl::LocalizabilityReport r = snl::analyze_localizability(sub, true);
      ++windows;
      if (!r.rigidity_checked) {
        std::fprintf(stderr, "window %d,%d: rigidity not checked\n", a, b);
        std::exit(1);
      }
      for (const GlobalId s : r.not_rigid) {
        const GlobalId i = ids[static_cast<std::size_t>(s)];
        const double x = net.truth[2 * i], y = net.truth[2 * i + 1];
        const bool core = x >= box[0] && (x < box[1] || a == k - 1) && y >= box[2] && (y < box[3] || b == k - 1);
        if (core) flex[static_cast<std::size_t>(i)] = 1;
      }
    }
  return windows;
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  if (argc < 5) {
    std::fprintf(stderr, "usage: %s N DIM SEEDS DEG [DEG ...]\n", argv[0]);
    return 2;
  }
  const GlobalId n = std::atoll(argv[1]);
  const int dim = std::atoi(argv[2]), seeds = std::atoi(argv[3]);
  const bool force_windows = std::getenv("SNL_WINDOWS") != nullptr;
  for (int d = 4; d < argc; ++d) {
    for (int seed = 1; seed <= seeds; ++seed) {
      const auto t0 = std::chrono::steady_clock::now();
      snl::GenerateOptions o;
      o.sensors = n;
      o.dim = dim;
      o.avg_degree = std::atof(argv[d]);
      o.seed = static_cast<std::uint64_t>(seed);
      o.localizable = snl::GenerateOptions::Localizable::kNo;
      snl::GenerateReport rep;
      const Network net = snl::generate_network(o, &rep);
      const bool exact = n <= snl::kRigidityLimit && !force_windows;
      snl::LocalizabilityReport r = snl::analyze_localizability(net, exact);
      std::vector<std::uint8_t> flags = r.flags;
      int windows = 0;
      if (!exact && dim == 2) {
        std::vector<std::uint8_t> flex(flags.size(), 0);
        windows = windowed_rigidity(net, rep.side, rep.radius, flex);
        for (std::size_t i = 0; i < flags.size(); ++i)
          if (flex[i]) flags[i] |= snl::kNotRigid;
      }
      std::size_t bad = 0, flexible = 0;
      for (const auto f : flags) {
        bad += f != 0;
        flexible += (f & snl::kNotRigid) != 0;
      }
      const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      std::printf(
          "{\"n\": %lld, \"dim\": %d, \"avg_degree\": %g, \"achieved_degree\": %.4f, \"anchors\": %lld, \"seed\": %d, "
          "\"rigidity\": \"%s\", \"windows\": %d, \"not_localizable\": %zu, \"unanchored\": %zu, "
          "\"few_measurements\": %zu, \"flexible\": %zu, \"localizable_fraction\": %.6f, \"seconds\": %.2f}\n",
          static_cast<long long>(n), dim, o.avg_degree, rep.achieved_avg_degree,
          static_cast<long long>(net.num_anchors()), seed,
          exact ? (r.rigidity_checked ? "exact" : "unchecked") : (dim == 2 ? "windows" : "unchecked"), windows, bad,
          r.unanchored.size(), r.few_measurements.size(), flexible,
          1.0 - static_cast<double>(bad) / static_cast<double>(n), secs);
      std::fflush(stdout);
    }
  }
  MPI_Finalize();
  return 0;
}
