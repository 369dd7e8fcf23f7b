// snl export: a result's positions as CSV (docs/formats.md, "Text files"),
// written on rank 0; with the network, each sensor's localizability flags. A
// consensus result (snl consensus solve) gives its x per node instead.
#include <cstdio>
#include <sstream>

#include "cli/cli_util.hpp"
#include "core/json.hpp"
#include "snl/cli/commands.hpp"
#include "snl/io/network.hpp"
#include "snl/io/result_io.hpp"
#include "snl/problem/analysis.hpp"

namespace snl {

namespace {

using detail::is_root;

// The network's stored flags (snl generate writes them), else those of the
// analysis snl info runs: rigidity at the truth, or without truth at the
// result's positions (a generic point), when n <= kRigidityLimit.
std::vector<std::uint8_t> sensor_flags(const ExportCommand& cmd, const ResultFile& r, std::string& source) {
  Network net = read_network_serial(cmd.network);
  if (net.num_sensors != r.num_sensors || net.dim != r.dim)
    throw Error(cmd.result + ": " + std::to_string(r.num_sensors) + " positions in dimension " +
                std::to_string(r.dim) + ", but " + cmd.network + " has n = " + std::to_string(net.num_sensors) +
                ", p = " + std::to_string(net.dim));
  if (!net.localizability.empty()) {
    source = "stored in " + cmd.network;
    return net.localizability;
  }
  merge_duplicates(net.sensor_edges, net.sensor_ranges, {&net.sensor_sigmas, &net.sensor_nlos}, net.anchor_edges,
                   net.anchor_ranges, {&net.anchor_sigmas, &net.anchor_nlos});
  net.total_sensor_edges = net.local_sensor_edges();
  net.total_anchor_edges = net.local_anchor_edges();
  const bool rig = net.num_sensors <= kRigidityLimit;
  LocalizabilityReport lr = analyze_localizability(net, rig, net.has_truth ? nullptr : &r.positions);
  source = std::string("computed; rigidity ") +
           (!lr.rigidity_checked ? "not checked" : net.has_truth ? "at the truth" : "at the result's positions");
  return std::move(lr.flags);
}

std::string csv_text(const ResultFile& r, const std::vector<std::uint8_t>& flags, int base) {
  static const char* const kAxis[] = {"x", "y", "z"};
  std::string out = "sensor";
  for (int c = 0; c < r.dim; ++c) out += std::string(",") + (c < 3 ? kAxis[c] : "?");
  if (!flags.empty()) out += ",flags,localizable";
  out += '\n';
  char buf[64];
  for (GlobalId i = 0; i < r.num_sensors; ++i) {
    out += std::to_string(i + base);
    for (int c = 0; c < r.dim; ++c) {
      std::snprintf(buf, sizeof buf, ",%.17g", r.positions[static_cast<std::size_t>(i) * r.dim + c]);
      out += buf;
    }
    if (!flags.empty()) {
      const unsigned f = flags[static_cast<std::size_t>(i)];
      out += "," + std::to_string(f) + (f == 0 ? ",1" : ",0");
    }
    out += '\n';
  }
  return out;
}

}  // namespace

void run_export(const ExportCommand& cmd, MPI_Comm comm) {
  if (cmd.index_base != 0 && cmd.index_base != 1)
    throw UsageError("--index-base must be 0 or 1, got " + std::to_string(cmd.index_base));
  check_output_path(cmd.output, comm, {{"the result", cmd.result}, {"--network", cmd.network}});
  std::string text;
  collective_try(comm, [&] {
    if (!is_root(comm)) return;
    if (detail::hdf5_format(cmd.result) == "snl-consensus-result") {  // x of every node (docs/consensus.md)
      if (!cmd.network.empty())
        throw Error(cmd.result + ": a consensus result has no sensors: --network applies to localization results only");
      std::int64_t n = 0, q = 0;
      write_text_atomic(cmd.output, detail::consensus_x_csv(cmd.result, cmd.index_base, &n, &q));
      text = "exported " + cmd.output + ": x of " + std::to_string(n) + " nodes, q=" + std::to_string(q) +
             " (consensus result)";
      return;
    }
    const ResultFile r = read_result_serial(cmd.result);
    std::vector<std::uint8_t> flags;
    std::string source;
    if (!cmd.network.empty()) flags = sensor_flags(cmd, r, source);
    write_text_atomic(cmd.output, csv_text(r, flags, cmd.index_base));
    std::ostringstream os;
    os << "exported " << cmd.output << ": " << r.num_sensors << " sensors, p=" << r.dim << " (" << r.algorithm
       << ", " << r.iterations << " iterations)";
    if (!flags.empty()) {
      GlobalId bad = 0;
      for (auto f : flags) bad += f != 0;
      os << "; localizability flags " << source << ": " << bad << " sensors not localizable";
    }
    text = os.str();
  });
  if (is_root(comm) && !cmd.quiet) std::printf("%s\n", text.c_str());
}

}  // namespace snl
