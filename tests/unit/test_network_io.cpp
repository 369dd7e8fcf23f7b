// Network files (src/io/network.cpp): write_network / read_network_serial
// round trips, one test per kind of broken file (each must give a clear
// snl::Error naming the dataset and row), and failed writes.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <map>

#include "io_helpers.hpp"
#include "snl/io/h5file.hpp"
#include "snl/io/network.hpp"

using namespace snl;
using snl::test::read_error;
using snl::test::scratch;

namespace {

Network sample(GlobalId n = 6, int dim = 2) {
  Network net;
  net.dim = dim;
  net.num_sensors = n;
  for (int a = 0; a < 3; ++a)
    for (int c = 0; c < dim; ++c) net.anchors.push_back(a + 0.25 * c);
  for (GlobalId i = 0; i + 1 < n; ++i) {
    net.sensor_edges.insert(net.sensor_edges.end(), {i, i + 1});
    net.sensor_ranges.push_back(0.1 * static_cast<double>(i + 1));
  }
  for (GlobalId i = 0; i < n; ++i) {
    net.anchor_edges.insert(net.anchor_edges.end(), {i, i % 3});
    net.anchor_ranges.push_back(1.0 + 0.01 * static_cast<double>(i));
  }
  net.has_truth = true;
  for (GlobalId i = 0; i < n * dim; ++i) net.truth.push_back(0.001 * static_cast<double>(i));
  net.sigma = 0.02;
  for (GlobalId i = 0; i < n; ++i) net.localizability.push_back(static_cast<std::uint8_t>(i % 8));
  return net;
}

void expect_same(const Network& a, const Network& b) {
  EXPECT_EQ(a.dim, b.dim);
  EXPECT_EQ(a.num_sensors, b.num_sensors);
  EXPECT_EQ(a.anchors, b.anchors);
  EXPECT_EQ(a.sensor_edges, b.sensor_edges);
  EXPECT_EQ(a.sensor_ranges, b.sensor_ranges);
  EXPECT_EQ(a.anchor_edges, b.anchor_edges);
  EXPECT_EQ(a.anchor_ranges, b.anchor_ranges);
  EXPECT_EQ(a.has_truth, b.has_truth);
  EXPECT_EQ(a.truth, b.truth);
  EXPECT_EQ(a.sigma, b.sigma);
  EXPECT_EQ(a.localizability, b.localizability);
  EXPECT_EQ(a.sensor_sigmas, b.sensor_sigmas);
  EXPECT_EQ(a.anchor_sigmas, b.anchor_sigmas);
  EXPECT_EQ(a.sensor_nlos, b.sensor_nlos);
  EXPECT_EQ(a.anchor_nlos, b.anchor_nlos);
}

/// sample() with per-measurement sigmas and NLOS flags.
Network sample_with_extras(GlobalId n = 6) {
  Network net = sample(n);
  for (std::size_t e = 0; e < net.sensor_ranges.size(); ++e) {
    net.sensor_sigmas.push_back(0.01 + 0.001 * static_cast<double>(e));
    net.sensor_nlos.push_back(static_cast<std::uint8_t>(e % 3 == 0));
  }
  for (std::size_t e = 0; e < net.anchor_ranges.size(); ++e) {
    net.anchor_sigmas.push_back(0.02 + 0.001 * static_cast<double>(e));
    net.anchor_nlos.push_back(static_cast<std::uint8_t>(e % 2));
  }
  return net;
}

using Override = std::function<void(H5File&)>;

/// Writes `net` item by item like write_network, except that an item named in
/// `over` is replaced by its function (which may write nothing: a missing item).
void write_raw(const std::string& path, const Network& net, const std::map<std::string, Override>& over) {
  H5File f(path, MPI_COMM_SELF, H5File::Mode::kCreate);
  auto item = [&](const std::string& name, const std::function<void()>& standard) {
    auto it = over.find(name);
    if (it != over.end()) it->second(f);
    else standard();
  };
  const std::uint64_t p = static_cast<std::uint64_t>(net.dim);
  item("format", [&] { f.set_attr("format", std::string("snl-network")); });
  item("version", [&] { f.set_attr("version", std::int64_t{1}); });
  item("dim", [&] { f.set_attr("dim", std::int64_t{net.dim}); });
  item("num_sensors", [&] { f.set_attr("num_sensors", std::int64_t{net.num_sensors}); });
  item("anchors", [&] { f.write_rows("anchors", net.anchors.size() / p, p, 0, net.anchors.data(), net.anchors.size() / p); });
  const std::uint64_t E = net.sensor_ranges.size(), Ea = net.anchor_ranges.size();
  item("sensor_edges", [&] { f.write_rows("sensor_edges", E, 2, 0, net.sensor_edges.data(), E); });
  item("sensor_ranges", [&] { f.write_rows("sensor_ranges", E, 0, 0, net.sensor_ranges.data(), E); });
  item("anchor_edges", [&] { f.write_rows("anchor_edges", Ea, 2, 0, net.anchor_edges.data(), Ea); });
  item("anchor_ranges", [&] { f.write_rows("anchor_ranges", Ea, 0, 0, net.anchor_ranges.data(), Ea); });
  const std::uint64_t n = static_cast<std::uint64_t>(net.num_sensors);
  item("truth", [&] { f.write_rows("truth", n, p, 0, net.truth.data(), n); });
  f.commit();
}

Override nothing() {
  return [](H5File&) {};
}

std::string file_size_text(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 ? std::to_string(st.st_size) : "missing";
}

}  // namespace

// ---------------------------------------------------------------- round trips

TEST(NetworkIo, RoundTripFull) {
  const std::string path = scratch("full.h5");
  const Network net = sample();
  write_network(path, net);
  const Network back = read_network_serial(path);
  expect_same(net, back);
  EXPECT_EQ(back.total_sensor_edges, net.local_sensor_edges());
  EXPECT_EQ(back.total_anchor_edges, net.local_anchor_edges());
  EXPECT_EQ(back.sensor_edge_offset, 0);
  EXPECT_EQ(back.anchor_edge_offset, 0);
  EXPECT_EQ(back.sensor_row_offset, 0);
  EXPECT_NO_THROW(validate_network(back));
}

TEST(NetworkIo, RoundTripPerMeasurementSigmasAndFlags) {
  const std::string path = scratch("extras.h5");
  const Network net = sample_with_extras();
  write_network(path, net);
  const Network back = read_network_serial(path);
  expect_same(net, back);
  EXPECT_FALSE(back.sensor_sigmas.empty());
  EXPECT_FALSE(back.anchor_nlos.empty());
  // Each rank's slab carries the rows of its edges.
  const Network slab = network_slab(net, MPI_COMM_SELF);
  EXPECT_EQ(slab.sensor_sigmas, net.sensor_sigmas);
  EXPECT_EQ(slab.anchor_nlos, net.anchor_nlos);
}

TEST(NetworkIoBroken, PerMeasurementSigmaNotPositive) {
  const std::string path = scratch("badsigmas.h5");
  Network net = sample_with_extras();
  net.anchor_sigmas[2] = 0.0;
  write_network(path, net);
  EXPECT_CONTAINS(read_error(path), "anchor_sigmas row 2: sigma 0 is outside");
  net.anchor_sigmas[2] = 0.5;
  net.sensor_sigmas[1] = std::numeric_limits<double>::quiet_NaN();
  write_network(path, net);
  EXPECT_CONTAINS(read_error(path), "sensor_sigmas row 1: sigma NaN");
}

TEST(NetworkIoBroken, PerMeasurementDatasetsWrongShapeOrValue) {
  const std::string path = scratch("badextras.h5");
  Network net = sample_with_extras();
  net.sensor_sigmas.pop_back();
  write_network(path, net);
  EXPECT_CONTAINS(read_error(path), "dataset 'sensor_sigmas' has shape");
  net = sample_with_extras();
  net.anchor_nlos[0] = 2;
  write_network(path, net);
  EXPECT_CONTAINS(read_error(path), "anchor_nlos row 0: flag 2 is not 0 or 1");
}

TEST(NetworkIo, RoundTripMinimal3D) {
  const std::string path = scratch("minimal.h5");
  Network net = sample(5, 3);
  net.has_truth = false;
  net.truth.clear();
  net.sigma.reset();
  net.localizability.clear();
  write_network(path, net);
  const Network back = read_network_serial(path);
  expect_same(net, back);
  EXPECT_FALSE(back.sigma.has_value());
  EXPECT_FALSE(back.has_truth);
  EXPECT_TRUE(back.localizability.empty());
}

TEST(NetworkIo, RoundTripNoEdges) {
  const std::string path = scratch("noedges.h5");
  Network net = sample(3);
  net.sensor_edges.clear();
  net.sensor_ranges.clear();
  net.anchor_edges.clear();
  net.anchor_ranges.clear();
  net.anchors.clear();  // m == 0 is readable (the solver refuses it later)
  write_network(path, net);
  const Network back = read_network_serial(path);
  expect_same(net, back);
  EXPECT_EQ(back.total_sensor_edges, 0);
  EXPECT_EQ(back.num_anchors(), 0);
}

TEST(NetworkIo, OverwriteIsAtomicAndLeavesNoTemporary) {
  const std::string path = scratch("over.h5");
  write_network(path, sample(4));
  write_network(path, sample(7));
  EXPECT_EQ(read_network_serial(path).num_sensors, 7);
  // No temporary left next to it.
  const std::string dir = test::scratch_dir(MPI_COMM_SELF);
  const std::string cmd = "ls '" + dir + "' | grep -c 'over.h5.tmp' > /dev/null";
  EXPECT_NE(std::system(cmd.c_str()), 0) << "temporary file left in " << dir;
}

TEST(NetworkIo, IntegerTypesAndIntegerRangesAccepted) {
  // Users' writers may store edges as int32 and ranges/anchors as integers.
  const std::string path = scratch("ints.h5");
  const Network net = sample(4);
  std::vector<std::int64_t> ranges_int = {1, 2, 3};
  write_raw(path, net, {{"sensor_ranges", [&](H5File& f) { f.write_rows("sensor_ranges", 3, 0, 0, ranges_int.data(), 3); }}});
  const Network back = read_network_serial(path);
  EXPECT_EQ(back.sensor_ranges, (std::vector<double>{1, 2, 3}));
}

// ---------------------------------------------------------------- broken files

TEST(NetworkIoBroken, NaNRange) {
  const std::string path = scratch("nan.h5");
  Network net = sample();
  net.sensor_ranges[3] = std::numeric_limits<double>::quiet_NaN();
  write_network(path, net);
  const std::string e = read_error(path);
  EXPECT_CONTAINS(e, path);
  EXPECT_CONTAINS(e, "sensor_ranges row 3: range is NaN");
}

TEST(NetworkIoBroken, InfAnchor) {
  const std::string path = scratch("infanchor.h5");
  Network net = sample();
  net.anchors[3] = std::numeric_limits<double>::infinity();
  write_network(path, net);
  EXPECT_CONTAINS(read_error(path), "anchors row 1: coordinate 1 is Inf");
}

TEST(NetworkIoBroken, NaNTruth) {
  const std::string path = scratch("nantruth.h5");
  Network net = sample();
  net.truth[9] = std::numeric_limits<double>::quiet_NaN();
  write_network(path, net);
  EXPECT_CONTAINS(read_error(path), "truth row 4: coordinate 1 is NaN");
}

TEST(NetworkIoBroken, NegativeRange) {
  const std::string path = scratch("neg.h5");
  Network net = sample();
  net.anchor_ranges[5] = -0.25;
  write_network(path, net);
  EXPECT_CONTAINS(read_error(path), "anchor_ranges row 5: range -0.25 is negative");
}

TEST(NetworkIoBroken, SelfLoop) {
  const std::string path = scratch("loop.h5");
  Network net = sample();
  net.sensor_edges[2 * 2 + 1] = 2;
  write_network(path, net);
  EXPECT_CONTAINS(read_error(path), "sensor_edges row 2: self-loop (2, 2)");
}

TEST(NetworkIoBroken, SensorIndexOutOfRange) {
  const std::string path = scratch("sidx.h5");
  Network net = sample();
  net.sensor_edges[2 * 4] = 12;
  write_network(path, net);
  EXPECT_CONTAINS(read_error(path), "sensor_edges row 4: sensor index 12 out of range [0, 6)");
}

TEST(NetworkIoBroken, AnchorIndexOutOfRange) {
  const std::string path = scratch("aidx.h5");
  Network net = sample();
  net.anchor_edges[2 * 1 + 1] = 3;
  write_network(path, net);
  EXPECT_CONTAINS(read_error(path), "anchor_edges row 1: anchor index 3 out of range [0, 3)");
}

TEST(NetworkIoBroken, NegativeSigma) {
  const std::string path = scratch("sigma.h5");
  Network net = sample();
  net.sigma = -1.0;
  write_network(path, net);
  EXPECT_CONTAINS(read_error(path), "sigma -1 is negative");
}

TEST(NetworkIoBroken, MissingDatasets) {
  for (const char* name : {"anchors", "sensor_edges", "sensor_ranges", "anchor_edges", "anchor_ranges"}) {
    const std::string path = scratch(std::string("missing_") + name + ".h5");
    write_raw(path, sample(), {{name, nothing()}});
    const std::string e = read_error(path);
    EXPECT_CONTAINS(e, path);
    EXPECT_CONTAINS(e, std::string("required dataset '") + name + "' is missing");
  }
}

TEST(NetworkIoBroken, MissingAttributes) {
  for (const char* name : {"version", "dim", "num_sensors"}) {
    const std::string path = scratch(std::string("noattr_") + name + ".h5");
    write_raw(path, sample(), {{name, nothing()}});
    EXPECT_CONTAINS(read_error(path), std::string("root attribute '") + name + "' is missing");
  }
  const std::string path = scratch("noformat.h5");
  write_raw(path, sample(), {{"format", nothing()}});
  EXPECT_CONTAINS(read_error(path), "not an snl network file");
}

TEST(NetworkIoBroken, WrongFormat) {
  const std::string path = scratch("format.h5");
  write_raw(path, sample(), {{"format", [](H5File& f) { f.set_attr("format", std::string("snl-result")); }}});
  EXPECT_CONTAINS(read_error(path), "attribute 'format' is 'snl-result', expected 'snl-network'");
}

TEST(NetworkIo, FixedLengthStringAttributesAccepted) {
  // MATLAB and other writers store fixed-length strings, NUL- or space-padded.
  for (bool space : {false, true}) {
    const std::string path = scratch("fixedstr.h5");
    write_raw(path, sample(), {{"format", [&](H5File& f) { f.set_attr_fixed_string("format", "snl-network", space); }}});
    EXPECT_EQ(read_error(path), "(no error)") << "space padded: " << space;
    H5File f(path, MPI_COMM_SELF, H5File::Mode::kRead);
    EXPECT_EQ(f.attr_string("format"), "snl-network");
  }
}

TEST(NetworkIoBroken, FormatNotAString) {
  const std::string path = scratch("format_int.h5");
  write_raw(path, sample(), {{"format", [](H5File& f) { f.set_attr("format", std::int64_t{1}); }}});
  EXPECT_CONTAINS(read_error(path), "attribute 'format' has type integer, expected a string");
}

TEST(NetworkIoBroken, WrongVersion) {
  const std::string path = scratch("version.h5");
  write_raw(path, sample(), {{"version", [](H5File& f) { f.set_attr("version", std::int64_t{2}); }}});
  EXPECT_CONTAINS(read_error(path), "unsupported network format version 2");
}

TEST(NetworkIoBroken, VersionNotAnInteger) {
  const std::string path = scratch("version_str.h5");
  write_raw(path, sample(), {{"version", [](H5File& f) { f.set_attr("version", std::string("1")); }}});
  EXPECT_CONTAINS(read_error(path), "attribute 'version' has type string, expected a number");
  write_raw(path, sample(), {{"version", [](H5File& f) { f.set_attr("version", 1.5); }}});
  EXPECT_CONTAINS(read_error(path), "attribute 'version' = 1.5");
  // An integral float (MATLAB writes numbers as double) is accepted.
  write_raw(path, sample(), {{"version", [](H5File& f) { f.set_attr("version", 1.0); }}});
  EXPECT_EQ(read_error(path), "(no error)");
}

TEST(NetworkIoBroken, BadDim) {
  const std::string path = scratch("dim.h5");
  write_raw(path, sample(), {{"dim", [](H5File& f) { f.set_attr("dim", std::int64_t{4}); }}});
  EXPECT_CONTAINS(read_error(path), "attribute 'dim' must be 1, 2 or 3, got 4");
}

TEST(NetworkIoBroken, AnchorsWrongShape) {
  const std::string path = scratch("anchors_shape.h5");
  const std::vector<double> a(9, 0.0);
  write_raw(path, sample(), {{"anchors", [&](H5File& f) { f.write_rows("anchors", 3, 3, 0, a.data(), 3); }}});
  EXPECT_CONTAINS(read_error(path), "dataset 'anchors' has shape [3, 3], expected [m, 2]");
}

TEST(NetworkIoBroken, EdgesWrongShape) {
  const std::string path = scratch("edges_shape.h5");
  const std::vector<std::int64_t> e(15, 0);
  write_raw(path, sample(), {{"sensor_edges", [&](H5File& f) { f.write_rows("sensor_edges", 5, 3, 0, e.data(), 5); }}});
  EXPECT_CONTAINS(read_error(path), "dataset 'sensor_edges' has shape [5, 3], expected [E, 2]");
  write_raw(path, sample(), {{"anchor_edges", [&](H5File& f) { f.write_rows("anchor_edges", 10, 0, 0, e.data(), 10); }}});
  EXPECT_CONTAINS(read_error(path), "dataset 'anchor_edges' has shape [10], expected [Ea, 2]");
}

TEST(NetworkIoBroken, RangesCountMismatch) {
  const std::string path = scratch("ranges_count.h5");
  const std::vector<double> r(4, 1.0);
  write_raw(path, sample(), {{"sensor_ranges", [&](H5File& f) { f.write_rows("sensor_ranges", 4, 0, 0, r.data(), 4); }}});
  EXPECT_CONTAINS(read_error(path), "dataset 'sensor_ranges' has shape [4], expected [5]");
  write_raw(path, sample(), {{"anchor_ranges", [&](H5File& f) { f.write_rows("anchor_ranges", 2, 2, 0, r.data(), 2); }}});
  EXPECT_CONTAINS(read_error(path), "dataset 'anchor_ranges' has shape [2, 2], expected [6]");
}

TEST(NetworkIoBroken, TruthWrongShape) {
  const std::string path = scratch("truth_shape.h5");
  const std::vector<double> t(10, 0.0);
  write_raw(path, sample(), {{"truth", [&](H5File& f) { f.write_rows("truth", 5, 2, 0, t.data(), 5); }}});
  EXPECT_CONTAINS(read_error(path), "dataset 'truth' has shape [5, 2], expected [6, 2]");
}

TEST(NetworkIoBroken, EdgesAsFloats) {
  const std::string path = scratch("edges_float.h5");
  const std::vector<double> e(10, 0.0);
  write_raw(path, sample(), {{"sensor_edges", [&](H5File& f) { f.write_rows("sensor_edges", 5, 2, 0, e.data(), 5); }}});
  EXPECT_CONTAINS(read_error(path), "dataset 'sensor_edges' has type floating point, expected integer");
}

TEST(NetworkIoBroken, NotHdf5) {
  const std::string path = scratch("text.h5");
  std::ofstream(path) << "this is not an HDF5 file\n";
  const std::string e = read_error(path);
  EXPECT_CONTAINS(e, path + ": not a readable HDF5 file");
}

TEST(NetworkIoBroken, EmptyFile) {
  const std::string path = scratch("empty.h5");
  std::ofstream(path).close();
  EXPECT_CONTAINS(read_error(path), path + ": not a readable HDF5 file");
}

TEST(NetworkIoBroken, Truncated) {
  const std::string path = scratch("trunc.h5");
  write_network(path, sample(200));
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  ASSERT_EQ(::truncate(path.c_str(), st.st_size / 2), 0);
  EXPECT_CONTAINS(read_error(path), path + ": not a readable HDF5 file");
}

TEST(NetworkIoBroken, MissingFile) {
  const std::string path = scratch("does_not_exist.h5");
  EXPECT_EQ(read_error(path), path + ": no such file");
}

TEST(NetworkIoBroken, DirectoryInsteadOfFile) {
  const std::string path = test::scratch_dir(MPI_COMM_SELF);
  EXPECT_CONTAINS(read_error(path), "is a directory");
}

// ---------------------------------------------------------------- writing errors

TEST(NetworkIoWrite, OutputDirectoryMissing) {
  const std::string path = scratch("no/such/dir/net.h5");
  try {
    write_network(path, sample());
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_CONTAINS(e.what(), "cannot write " + path + ": directory " + scratch("no/such/dir") + " does not exist");
  }
}

TEST(NetworkIoWrite, OutputIsADirectory) {
  const std::string dir = scratch("adir");
  ::mkdir(dir.c_str(), 0755);
  EXPECT_THROW(write_network(dir, sample()), Error);
}

TEST(NetworkIoWrite, FailedWriteKeepsExistingFile) {
  const std::string path = scratch("keep.h5");
  write_network(path, sample(4));
  const std::string before = file_size_text(path);
  // A failure in the middle of writing (a dataset of inconsistent shape).
  try {
    H5File f(path, MPI_COMM_SELF, H5File::Mode::kCreate);
    f.set_attr("format", std::string("snl-network"));
    const std::vector<double> v(4, 1.0);
    f.write_rows("x", 2, 2, 0, v.data(), 2);
    f.write_rows("x", 3, 2, 0, v.data(), 2);  // exists with another shape: throws
    f.commit();
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_CONTAINS(e.what(), "'x' exists with another shape");
  }
  EXPECT_EQ(file_size_text(path), before);
  EXPECT_EQ(read_network_serial(path).num_sensors, 4);
  const std::string cmd = "ls '" + test::scratch_dir(MPI_COMM_SELF) + "' | grep -q 'keep.h5.tmp'";
  EXPECT_NE(std::system(cmd.c_str()), 0) << "temporary file left behind";
}
