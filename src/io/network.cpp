// Network files (shared spec: network-format.md): collective slab reader and
// serial atomic writer.
#include <string>
#include <type_traits>

#include "snl/io/h5file.hpp"
#include "snl/core/mpi_util.hpp"
#include "snl/io/network.hpp"

namespace snl {

namespace {

std::string shape_text(const std::vector<std::uint64_t>& s) {
  std::string t = "[";
  for (std::size_t k = 0; k < s.size(); ++k) t += (k ? ", " : "") + std::to_string(s[k]);
  return t + "]";
}

/// Shape of a required dataset, with a clear message when it is missing.
std::vector<std::uint64_t> required_shape(const H5File& f, const std::string& name) {
  if (!f.has_dataset(name)) throw Error(f.path() + ": required dataset '" + name + "' is missing");
  return f.shape(name);
}

void expect_shape(const H5File& f, const std::string& name, const std::vector<std::uint64_t>& got,
                  const std::vector<std::uint64_t>& want, const std::string& why) {
  if (got != want)
    throw Error(f.path() + ": dataset '" + name + "' has shape " + shape_text(got) + ", expected " +
                shape_text(want) + why);
}

/// Reads and checks the root attributes and dataset shapes. Every step is
/// collective and sees the same metadata on every rank, so all ranks throw alike.
NetworkHeader read_header(const H5File& f) {
  const std::string& path = f.path();
  if (!f.has_attr("format"))
    throw Error(path + ": not an snl network file (root attribute 'format' is missing)");
  const std::string format = f.attr_string("format");
  if (format != "snl-network")
    throw Error(path + ": attribute 'format' is '" + format + "', expected 'snl-network'");
  if (!f.has_attr("version")) throw Error(path + ": root attribute 'version' is missing");
  const std::int64_t version = f.attr_int("version");
  if (version != 1)
    throw Error(path + ": unsupported network format version " + std::to_string(version) +
                " (this snl reads version 1)");
  NetworkHeader h;
  if (!f.has_attr("dim")) throw Error(path + ": root attribute 'dim' is missing");
  const std::int64_t dim = f.attr_int("dim");
  if (dim < 1 || dim > 3) throw Error(path + ": attribute 'dim' must be 1, 2 or 3, got " + std::to_string(dim));
  h.dim = static_cast<int>(dim);
  if (!f.has_attr("num_sensors")) throw Error(path + ": root attribute 'num_sensors' is missing");
  h.num_sensors = f.attr_int("num_sensors");
  if (h.num_sensors < 1)
    throw Error(path + ": attribute 'num_sensors' must be >= 1, got " + std::to_string(h.num_sensors));
  const auto n = static_cast<std::uint64_t>(h.num_sensors), p = static_cast<std::uint64_t>(h.dim);

  const auto a = required_shape(f, "anchors");
  if (a.size() != 2 || a[1] != p)
    throw Error(path + ": dataset 'anchors' has shape " + shape_text(a) + ", expected [m, " + std::to_string(p) + "]");
  h.num_anchors = static_cast<GlobalId>(a[0]);

  const auto se = required_shape(f, "sensor_edges");
  if (se.size() != 2 || se[1] != 2)
    throw Error(path + ": dataset 'sensor_edges' has shape " + shape_text(se) + ", expected [E, 2]");
  const auto sr = required_shape(f, "sensor_ranges");
  expect_shape(f, "sensor_ranges", sr, {se[0]}, " (one range per row of sensor_edges)");
  h.num_sensor_edges = static_cast<GlobalId>(se[0]);

  const auto ae = required_shape(f, "anchor_edges");
  if (ae.size() != 2 || ae[1] != 2)
    throw Error(path + ": dataset 'anchor_edges' has shape " + shape_text(ae) + ", expected [Ea, 2]");
  const auto ar = required_shape(f, "anchor_ranges");
  expect_shape(f, "anchor_ranges", ar, {ae[0]}, " (one range per row of anchor_edges)");
  h.num_anchor_edges = static_cast<GlobalId>(ae[0]);

  h.has_truth = f.has_dataset("truth");
  if (h.has_truth) expect_shape(f, "truth", f.shape("truth"), {n, p}, " ([num_sensors, dim])");
  if (f.has_dataset("sigma")) h.sigma = f.read_scalar("sigma");
  h.has_localizability = f.has_dataset("localizability/flags");
  if (h.has_localizability)
    expect_shape(f, "localizability/flags", f.shape("localizability/flags"), {n}, " ([num_sensors])");
  const auto optional_rows = [&](const char* name, std::uint64_t rows, const char* why) {
    if (!f.has_dataset(name)) return false;
    expect_shape(f, name, f.shape(name), {rows}, why);
    return true;
  };
  h.has_sensor_sigmas = optional_rows("sensor_sigmas", se[0], " (one sigma per row of sensor_edges)");
  h.has_anchor_sigmas = optional_rows("anchor_sigmas", ae[0], " (one sigma per row of anchor_edges)");
  h.has_sensor_nlos = optional_rows("sensor_nlos", se[0], " (one flag per row of sensor_edges)");
  h.has_anchor_nlos = optional_rows("anchor_nlos", ae[0], " (one flag per row of anchor_edges)");
  return h;
}

}  // namespace

Network read_network(const std::string& path, MPI_Comm comm) {
  const int rank = comm_rank(comm), size = comm_size(comm);
  H5File f(path, comm, H5File::Mode::kRead);
  NetworkHeader h;
  collective_try(comm, [&] { h = read_header(f); });

  Network net;
  net.dim = h.dim;
  net.num_sensors = h.num_sensors;
  net.sigma = h.sigma;
  net.has_truth = h.has_truth;
  net.total_sensor_edges = h.num_sensor_edges;
  net.total_anchor_edges = h.num_anchor_edges;

  const auto u = [](GlobalId v) { return static_cast<std::uint64_t>(v); };
  net.anchors = f.read_rows_double("anchors", 0, u(h.num_anchors));

  GlobalId b = 0, e = 0;
  block_range(h.num_sensor_edges, size, rank, b, e);
  net.sensor_edge_offset = b;
  net.sensor_edges = f.read_rows_int("sensor_edges", u(b), u(e - b));
  net.sensor_ranges = f.read_rows_double("sensor_ranges", u(b), u(e - b));
  if (h.has_sensor_sigmas) net.sensor_sigmas = f.read_rows_double("sensor_sigmas", u(b), u(e - b));
  if (h.has_sensor_nlos) net.sensor_nlos = f.read_rows_u8("sensor_nlos", u(b), u(e - b));

  block_range(h.num_anchor_edges, size, rank, b, e);
  net.anchor_edge_offset = b;
  net.anchor_edges = f.read_rows_int("anchor_edges", u(b), u(e - b));
  net.anchor_ranges = f.read_rows_double("anchor_ranges", u(b), u(e - b));
  if (h.has_anchor_sigmas) net.anchor_sigmas = f.read_rows_double("anchor_sigmas", u(b), u(e - b));
  if (h.has_anchor_nlos) net.anchor_nlos = f.read_rows_u8("anchor_nlos", u(b), u(e - b));

  block_range(h.num_sensors, size, rank, b, e);
  net.sensor_row_offset = b;
  if (h.has_truth) net.truth = f.read_rows_double("truth", u(b), u(e - b));
  if (h.has_localizability) net.localizability = f.read_rows_u8("localizability/flags", u(b), u(e - b));
  f.commit();

  // Each rank checks its slab; the globally first violation wins on all ranks.
  NetworkIssue issue;
  try {
    test_fail_point("read");  // fault-injection tests: a failure on one rank's slab
    issue = check_network(net, false);
  } catch (const std::bad_alloc&) {
    issue = {0, "out of memory while checking the network"};
  } catch (const std::exception& ex) {
    issue = {0, ex.what()};
  }
  agree_first(comm, issue.key, issue.ok() ? std::string() : path + ": " + issue.message);
  return net;
}

Network read_network_serial(const std::string& path) { return read_network(path, MPI_COMM_SELF); }

void write_network(const std::string& path, const Network& net) {
  // Only what is needed to write without reading out of bounds is checked
  // here; content is the reader's business (tests write broken files this way).
  const int p = net.dim;
  if (p < 1) throw Error("cannot write " + path + ": dim must be positive");
  if (net.anchors.size() % static_cast<std::size_t>(p) != 0)
    throw Error("cannot write " + path + ": anchors size is not a multiple of dim");
  if (net.sensor_edges.size() % 2 != 0 || net.anchor_edges.size() % 2 != 0)
    throw Error("cannot write " + path + ": edge arrays must hold pairs");
  if (net.has_truth && net.truth.size() % static_cast<std::size_t>(p) != 0)
    throw Error("cannot write " + path + ": truth size is not a multiple of dim");

  H5File f(path, MPI_COMM_SELF, H5File::Mode::kCreate);
  f.set_attr("format", std::string("snl-network"));
  f.set_attr("version", std::int64_t{1});
  f.set_attr("dim", std::int64_t{p});
  f.set_attr("num_sensors", std::int64_t{net.num_sensors});
  const std::uint64_t m = net.anchors.size() / p;
  f.write_rows("anchors", m, p, 0, net.anchors.data(), m);
  const std::uint64_t E = net.sensor_edges.size() / 2, Er = net.sensor_ranges.size();
  f.write_rows("sensor_edges", E, 2, 0, net.sensor_edges.data(), E);
  f.write_rows("sensor_ranges", Er, 0, 0, net.sensor_ranges.data(), Er);
  const std::uint64_t Ea = net.anchor_edges.size() / 2, Ear = net.anchor_ranges.size();
  f.write_rows("anchor_edges", Ea, 2, 0, net.anchor_edges.data(), Ea);
  f.write_rows("anchor_ranges", Ear, 0, 0, net.anchor_ranges.data(), Ear);
  if (net.has_truth) {
    const std::uint64_t rows = net.truth.size() / p;
    f.write_rows("truth", rows, p, 0, net.truth.data(), rows);
  }
  if (net.sigma) f.write_scalar("sigma", *net.sigma);
  const auto write_optional = [&](const char* name, const auto& v) {
    if (!v.empty()) f.write_rows(name, v.size(), 0, 0, v.data(), v.size());
  };
  write_optional("sensor_sigmas", net.sensor_sigmas);
  write_optional("anchor_sigmas", net.anchor_sigmas);
  write_optional("sensor_nlos", net.sensor_nlos);
  write_optional("anchor_nlos", net.anchor_nlos);
  if (!net.localizability.empty()) {
    const std::uint64_t n = net.localizability.size();
    f.write_rows("localizability/flags", n, 0, 0, net.localizability.data(), n);
  }
  f.commit();
}

Network network_slab(const Network& w, MPI_Comm comm) {
  int size = 1, rank = 0;
  MPI_Comm_size(comm, &size);
  MPI_Comm_rank(comm, &rank);
  Network s;
  s.dim = w.dim;
  s.num_sensors = w.num_sensors;
  s.anchors = w.anchors;
  s.sigma = w.sigma;
  s.has_truth = w.has_truth;
  const int p = w.dim;
  GlobalId b, e;
  block_range(w.local_sensor_edges(), size, rank, b, e);
  s.sensor_edges.assign(w.sensor_edges.begin() + 2 * b, w.sensor_edges.begin() + 2 * e);
  s.sensor_ranges.assign(w.sensor_ranges.begin() + b, w.sensor_ranges.begin() + e);
  const auto slice = [](const auto& v, GlobalId lo, GlobalId hi) {
    using V = std::decay_t<decltype(v)>;
    return v.empty() ? V() : V(v.begin() + lo, v.begin() + hi);
  };
  s.sensor_sigmas = slice(w.sensor_sigmas, b, e);
  s.sensor_nlos = slice(w.sensor_nlos, b, e);
  s.sensor_edge_offset = b;
  block_range(w.local_anchor_edges(), size, rank, b, e);
  s.anchor_edges.assign(w.anchor_edges.begin() + 2 * b, w.anchor_edges.begin() + 2 * e);
  s.anchor_ranges.assign(w.anchor_ranges.begin() + b, w.anchor_ranges.begin() + e);
  s.anchor_sigmas = slice(w.anchor_sigmas, b, e);
  s.anchor_nlos = slice(w.anchor_nlos, b, e);
  s.anchor_edge_offset = b;
  block_range(w.num_sensors, size, rank, b, e);
  if (w.has_truth) s.truth.assign(w.truth.begin() + b * p, w.truth.begin() + e * p);
  if (!w.localizability.empty()) s.localizability.assign(w.localizability.begin() + b, w.localizability.begin() + e);
  s.sensor_row_offset = b;
  s.total_sensor_edges = w.local_sensor_edges();
  s.total_anchor_edges = w.local_anchor_edges();
  return s;
}

}  // namespace snl
