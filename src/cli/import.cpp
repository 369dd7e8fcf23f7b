// snl import: a network file from text tables of measurements and positions
// (docs/formats.md, "Text files"), built on rank 0.
#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <sstream>

#include "cli/cli_util.hpp"
#include "io/text_table.hpp"
#include "snl/cli/commands.hpp"
#include "snl/io/network.hpp"

namespace snl {

namespace {

using detail::is_root;
using detail::read_text_file;


// Sensors that appear in no measurement (an id typo inflates n: worth a line).
GlobalId sensors_without_measurements(const Network& net) {
  std::vector<GlobalId> ids(net.sensor_edges);
  for (std::size_t e = 0; e < net.anchor_edges.size(); e += 2) ids.push_back(net.anchor_edges[e]);
  std::sort(ids.begin(), ids.end());
  const auto distinct = std::unique(ids.begin(), ids.end()) - ids.begin();
  return net.num_sensors - static_cast<GlobalId>(distinct);
}

// Duplicate rows of a pair, which the network reader merges.
MergeStats duplicate_rows(const Network& net) {
  std::vector<GlobalId> se(net.sensor_edges), ae(net.anchor_edges);
  std::vector<double> sr(net.sensor_ranges), ar(net.anchor_ranges);
  return merge_duplicates(se, sr, ae, ar);
}

std::string summary(const ImportCommand& cmd, const Network& net) {
  const MergeStats dup = duplicate_rows(net);
  const GlobalId silent = sensors_without_measurements(net);
  std::ostringstream os;
  os << "imported " << cmd.output << ": n=" << net.num_sensors << " m=" << net.num_anchors() << " p=" << net.dim
     << ", " << net.local_sensor_edges() << " sensor ranges (" << dup.merged_sensor_pairs << " duplicate rows), "
     << net.local_anchor_edges() << " anchor ranges (" << dup.merged_anchor_pairs << " duplicate rows)\n"
     << "per-measurement sigmas: " << (net.sensor_sigmas.empty() ? "no" : "yes") << " (sensor ranges), "
     << (net.anchor_sigmas.empty() ? "no" : "yes") << " (anchor ranges); truth: "
     << (net.has_truth ? "yes" : "no") << "; sigma: " << (net.sigma ? detail::fmt(*net.sigma) : "unknown");
  if (silent > 0) os << "\nwarning: " << silent << " of " << net.num_sensors << " sensors have no measurement";
  return os.str();
}

}  // namespace

void run_import(const ImportCommand& cmd, MPI_Comm comm) {
  text::ImportOptions opt;
  opt.sensors = cmd.sensors;
  opt.index_base = cmd.index_base;
  opt.sigma = cmd.sigma;
  if (const std::string bad = opt.validate(); !bad.empty()) throw UsageError(bad);
  check_output_path(cmd.output, comm, {{"--sensor-edges", cmd.sensor_edges}, {"--anchor-edges", cmd.anchor_edges},
                                      {"--anchors", cmd.anchors}, {"--truth", cmd.truth}});
  std::string text;
  collective_try(comm, [&] {
    if (!is_root(comm)) return;
    text::ImportInput in;
    in.sensor_edges = {cmd.sensor_edges, read_text_file(cmd.sensor_edges)};
    in.anchor_edges = {cmd.anchor_edges, read_text_file(cmd.anchor_edges)};
    in.anchors = {cmd.anchors, read_text_file(cmd.anchors)};
    if (!cmd.truth.empty()) in.truth = text::TextFile{cmd.truth, read_text_file(cmd.truth)};
    const Network net = text::import_network(in, opt);
    validate_network(net);  // the network file's rules, all of them already checked row by row above
    write_network(cmd.output, net);
    text = summary(cmd, net);
  });
  if (is_root(comm) && !cmd.quiet) std::printf("%s\n", text.c_str());
}

}  // namespace snl
