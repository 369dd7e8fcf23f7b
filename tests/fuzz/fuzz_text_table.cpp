// libFuzzer target: the text tables of snl import (src/io/text_table.cpp; no
// MPI, no files). Bytes split at '\x01' into the sensor-edge, anchor-edge,
// anchors and truth texts; the first byte picks the options. import_network
// must only ever throw snl::Error, every message must start "NAME:" of one of
// the inputs or name an option, and a network it returns must pass
// check_network (the network file's rules).
// Built and run by tests/fuzz/run_fuzz_text.sh (clang++ -fsanitize=fuzzer,address,undefined).
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "io/text_table.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  snl::text::ImportOptions opt;
  const std::uint8_t o = data[0];
  opt.index_base = o & 1;
  opt.sensors = (o >> 1) & 7;  // 0: decided from the truth or the ids
  if (o & 16) opt.sigma = 0.5;
  std::vector<std::string> parts(4);
  std::size_t k = 0;
  for (std::size_t i = 1; i < size; ++i) {
    if (data[i] == 1 && k < 3) {
      ++k;
      continue;
    }
    parts[k].push_back(static_cast<char>(data[i]));
  }
  snl::text::ImportInput in;
  in.sensor_edges = {"E", parts[0]};
  in.anchor_edges = {"A", parts[1]};
  in.anchors = {"P", parts[2]};
  if (o & 32) in.truth = snl::text::TextFile{"T", parts[3]};
  try {
    const snl::Network net = snl::text::import_network(in, opt);
    const snl::NetworkIssue issue = snl::check_network(net, true);
    if (!issue.ok()) {
      std::fprintf(stderr, "import_network returned a network check_network rejects: %s\n", issue.message.c_str());
      std::abort();
    }
  } catch (const snl::Error& e) {
    const std::string m = e.what();
    if (m.empty()) std::abort();
    const bool named = m.rfind("E:", 0) == 0 || m.rfind("A:", 0) == 0 || m.rfind("P:", 0) == 0 ||
                       m.rfind("T:", 0) == 0 || m.rfind("no sensor ids in E or A", 0) == 0;
    if (!named) {
      std::fprintf(stderr, "error without its file: %s\n", m.c_str());
      std::abort();
    }
  }
  return 0;
}
