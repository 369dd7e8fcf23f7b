// libFuzzer target (issue #5): the in-memory validation and duplicate merging
// of measurement lists (src/io/validate.cpp; no MPI, no HDF5). Bytes decode into a
// small Network with arbitrary integers and doubles (NaN, Inf, negatives,
// out-of-range ids, odd shapes); check_network/validate_network must only ever
// throw snl::Error; on a valid network merge_duplicates must keep its contract.
// Built and run by tests/fuzz/run_fuzz.sh (clang++ -fsanitize=fuzzer,address,undefined).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <utility>
#include <vector>

#include "snl/io/network.hpp"

namespace {

struct Reader {
  const std::uint8_t* p;
  std::size_t n;
  std::uint8_t byte() {
    if (n == 0) return 0;
    --n;
    return *p++;
  }
  std::int64_t id(std::int64_t span) {  // mostly in [-1, span], sometimes anything
    const std::uint8_t k = byte();
    if (k == 255) {
      std::int64_t v = 0;
      for (int i = 0; i < 8; ++i) v = (v << 8) | byte();
      return v;
    }
    return static_cast<std::int64_t>(k % (span + 2)) - 1;
  }
  double real() {
    static const double kSpecial[] = {0.0, -0.0, 1.0, -1.0, 0.5, 1e-300, 1e300, std::numeric_limits<double>::max(),
                                      std::numeric_limits<double>::denorm_min(),
                                      std::numeric_limits<double>::infinity(),
                                      -std::numeric_limits<double>::infinity(),
                                      std::numeric_limits<double>::quiet_NaN()};
    const std::uint8_t k = byte();
    if (k < 12) return kSpecial[k];
    if (k < 200) return (k - 12) / 16.0;  // small ranges, frequent duplicates
    std::uint64_t bits = 0;
    for (int i = 0; i < 8; ++i) bits = (bits << 8) | byte();
    double d;
    std::memcpy(&d, &bits, sizeof d);
    return d;
  }
};

[[noreturn]] void die(const char* what) {
  std::fprintf(stderr, "fuzz_network: invariant violated: %s\n", what);
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Reader in{data, size};
  snl::Network net;
  const std::uint8_t h = in.byte();
  net.dim = (h & 3) == 3 ? static_cast<int>(static_cast<std::int8_t>(in.byte())) : 2 + (h & 1);
  net.num_sensors = static_cast<snl::GlobalId>(in.byte() % 24);
  const int p = net.dim > 0 && net.dim <= 3 ? net.dim : 2;
  const int m = in.byte() % 6;
  net.anchors.resize(static_cast<std::size_t>(m * p) + ((h & 4) ? 1 : 0));  // sometimes a ragged shape
  for (auto& a : net.anchors) a = in.real();
  const int E = in.byte() % 40, Ea = in.byte() % 20;
  for (int e = 0; e < E; ++e) {
    net.sensor_edges.push_back(in.id(net.num_sensors));
    net.sensor_edges.push_back(in.id(net.num_sensors));
    net.sensor_ranges.push_back(in.real());
  }
  for (int e = 0; e < Ea; ++e) {
    net.anchor_edges.push_back(in.id(net.num_sensors));
    net.anchor_edges.push_back(in.id(m));
    net.anchor_ranges.push_back(in.real());
  }
  if (h & 8) net.sensor_ranges.push_back(1.0);  // mismatched lengths
  if (h & 16) {
    net.has_truth = true;
    net.truth.resize(static_cast<std::size_t>(net.num_sensors) * p + ((h & 32) ? 1 : 0));
    for (auto& t : net.truth) t = in.real();
  }
  if (h & 64) net.sigma = in.real();
  if (h & 128) {
    net.localizability.resize(static_cast<std::size_t>(net.num_sensors));
    for (auto& f : net.localizability) f = in.byte();
  }

  bool valid = true;
  try {
    snl::validate_network(net);
  } catch (const snl::Error&) {
    valid = false;
  }
  const snl::NetworkIssue issue = snl::check_network(net, true);
  if (issue.ok() != valid) die("check_network and validate_network disagree");
  if (!valid) return 0;

  // Valid: merge, then check canonical sorted unique pairs, conservation, and
  // that every averaged range lies within [min, max] of its duplicates.
  std::map<std::pair<snl::GlobalId, snl::GlobalId>, std::pair<double, double>> want_s, want_a;
  for (int e = 0; e < E; ++e) {
    auto key = std::minmax(net.sensor_edges[2 * e], net.sensor_edges[2 * e + 1]);
    auto it = want_s.emplace(key, std::make_pair(net.sensor_ranges[e], net.sensor_ranges[e])).first;
    it->second.first = std::min(it->second.first, net.sensor_ranges[e]);
    it->second.second = std::max(it->second.second, net.sensor_ranges[e]);
  }
  for (int e = 0; e < Ea; ++e) {
    auto key = std::make_pair(net.anchor_edges[2 * e], net.anchor_edges[2 * e + 1]);
    auto it = want_a.emplace(key, std::make_pair(net.anchor_ranges[e], net.anchor_ranges[e])).first;
    it->second.first = std::min(it->second.first, net.anchor_ranges[e]);
    it->second.second = std::max(it->second.second, net.anchor_ranges[e]);
  }
  snl::MergeStats st;
  try {
    st = snl::merge_duplicates(net.sensor_edges, net.sensor_ranges, net.anchor_edges, net.anchor_ranges);
  } catch (const snl::Error&) {
    die("merge_duplicates threw on a valid network");
  }
  auto check = [](const std::vector<snl::GlobalId>& ed, const std::vector<double>& r, int rows_in,
                  snl::GlobalId merged, const auto& want, bool canonical) {
    if (ed.size() != 2 * r.size()) die("edges/ranges length mismatch after merge");
    if (static_cast<snl::GlobalId>(r.size()) + merged != rows_in) die("row count not conserved");
    if (r.size() != want.size()) die("number of distinct pairs changed");
    for (std::size_t e = 0; e < r.size(); ++e) {
      const auto key = std::make_pair(ed[2 * e], ed[2 * e + 1]);
      if (canonical && !(key.first < key.second)) die("sensor pair not canonical (i < j)");
      if (e > 0 && !(std::make_pair(ed[2 * e - 2], ed[2 * e - 1]) < key)) die("pairs not sorted and unique");
      const auto it = want.find(key);
      if (it == want.end()) die("merged pair not in the input");
      if (!(r[e] >= it->second.first && r[e] <= it->second.second)) die("averaged range outside [min, max]");
    }
  };
  check(net.sensor_edges, net.sensor_ranges, E, st.merged_sensor_pairs, want_s, true);
  check(net.anchor_edges, net.anchor_ranges, Ea, st.merged_anchor_pairs, want_a, false);
  return 0;
}
