// The text tables of snl import (src/io/text_table.cpp): good rows in every
// accepted spelling, and each class of bad row reported with its file and line.
#include <gtest/gtest.h>

#include <string>

#include "io/text_table.hpp"

namespace {

using snl::GlobalId;
using namespace snl::text;

// The message of the snl::Error that f throws ("" if none).
template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const snl::Error& e) {
    return e.what();
  }
  return "";
}

std::string edge_error(const std::string& text, EdgeKind kind = EdgeKind::kSensor, int base = 0) {
  return error_of([&] { parse_edges(text, "e.csv", kind, base); });
}

TEST(TextTable, SplitsCsvWhitespaceCommentsAndHeader) {
  const std::string text = "# comment line\n\ni , j,range  # header\r\n 0,1, 0.5\r\n2\t3   1e-1 # trailing\n\n";
  const auto rows = split_rows(text);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].line, 4);
  ASSERT_EQ(rows[0].fields.size(), 3u);
  EXPECT_EQ(rows[0].fields[0], "0");
  EXPECT_EQ(rows[0].fields[2], "0.5");
  EXPECT_EQ(rows[1].line, 5);
  ASSERT_EQ(rows[1].fields.size(), 3u);
  EXPECT_EQ(rows[1].fields[1], "3");
  EXPECT_EQ(rows[1].fields[2], "1e-1");
}

TEST(TextTable, OnlyTheFirstLineWithoutNumbersIsAHeader) {
  EXPECT_EQ(split_rows("a,b,c\n1,2,3\n").size(), 1u);
  EXPECT_EQ(split_rows("1,2,3\n").size(), 1u);
  // a typo in the first data row is a row (reported later), not a header
  EXPECT_EQ(split_rows("O,1,0.5\n").size(), 1u);
  // a second text line is a row
  EXPECT_EQ(split_rows("a,b,c\nd,e,f\n").size(), 1u);
}

TEST(TextTable, ParsesSensorEdgesWithAndWithoutSigma) {
  EdgeTable t = parse_edges("i,j,range\n0,1,0.5\n+3,2,2\n1 0 0.25\n", "e.csv", EdgeKind::kSensor, 0);
  EXPECT_EQ(t.edges, (std::vector<GlobalId>{0, 1, 3, 2, 1, 0}));
  EXPECT_EQ(t.ranges, (std::vector<double>{0.5, 2.0, 0.25}));
  EXPECT_TRUE(t.sigmas.empty());
  EXPECT_EQ(t.lines, (std::vector<std::int64_t>{2, 3, 4}));
  t = parse_edges("1,2,0.5,0.01\n2,1,0.6,0.02\n", "e.csv", EdgeKind::kSensor, 1);
  EXPECT_EQ(t.edges, (std::vector<GlobalId>{0, 1, 1, 0}));  // index base 1 removed
  EXPECT_EQ(t.sigmas, (std::vector<double>{0.01, 0.02}));
  t = parse_edges("# nothing\n", "e.csv", EdgeKind::kSensor, 0);
  EXPECT_TRUE(t.ranges.empty());
}

TEST(TextTable, BadEdgeRowsNameTheirLine) {
  EXPECT_EQ(edge_error("0,1,0.5\n0,1\n"), "e.csv:2: 2 columns, expected 3 or 4 (i, j, range[, sigma])");
  EXPECT_EQ(edge_error("0,1,0.5\n\n0,1,2,3,4\n"), "e.csv:3: 5 columns, expected 3 or 4 (i, j, range[, sigma])");
  EXPECT_EQ(edge_error("0,1,0.5\n1,2,0.5,0.1\n"),
            "e.csv:2: 4 columns, but line 1 has 3: a sigma column must be on every row or on none");
  EXPECT_EQ(edge_error("0,1,0.5\n0,x,0.5\n"), "e.csv:2: column 2 (sensor): 'x' is not an integer index");
  EXPECT_EQ(edge_error("0,1,0.5\n0,1.0,0.5\n"), "e.csv:2: column 2 (sensor): '1.0' is not an integer index");
  EXPECT_EQ(edge_error("0,1,0.5\n0,,0.5\n"), "e.csv:2: column 2 (sensor) is empty");
  EXPECT_EQ(edge_error("0,1,\n"), "e.csv:1: column 3 (range) is empty");
  EXPECT_EQ(edge_error("0,1,abc\n"), "e.csv:1: column 3 (range): 'abc' is not a number");
  EXPECT_EQ(edge_error("0,1,0.5x\n"), "e.csv:1: column 3 (range): '0.5x' is not a number");
  EXPECT_EQ(edge_error("0,1,0.5\n0 1 -0.5\n"), "e.csv:2: range -0.5 is negative");
  EXPECT_EQ(edge_error("0,1,nan\n"), "e.csv:1: range is NaN");
  EXPECT_EQ(edge_error("0,1,1e999\n"), "e.csv:1: range is Inf");
  EXPECT_EQ(edge_error("h\n0,1,0.5\n7,7,0.5\n"), "e.csv:3: self-loop (7, 7)");
  EXPECT_EQ(edge_error("-1,1,0.5\n"), "e.csv:1: sensor index -1 is below the index base 0");
  EXPECT_EQ(edge_error("1,0,0.5\n", EdgeKind::kSensor, 1),
            "e.csv:1: sensor index 0 is below the index base 1 (--index-base 1)");
  EXPECT_EQ(edge_error("0,1,0.5,0\n"),
            "e.csv:1: sigma 0 is outside [1e-150, 1e150] (weights 1/sigma^2 must be finite and positive)");
  EXPECT_EQ(edge_error("0,1,0.5,-1\n").substr(0, 24), "e.csv:1: sigma -1 is out");
  EXPECT_EQ(edge_error("0,1,0.5,inf\n").substr(0, 25), "e.csv:1: sigma Inf is out");
  EXPECT_EQ(edge_error("0,1,0.5,x\n"), "e.csv:1: column 4 (sigma): 'x' is not a number");
  EXPECT_EQ(edge_error("99999999999999999999,1,0.5\n"),
            "e.csv:1: column 1 (sensor): '99999999999999999999' is not an integer index");
}

TEST(TextTable, AnchorEdgesAllowEqualIdsAndNameTheAnchorColumn) {
  const EdgeTable t = parse_edges("3,3,0.5\n", "a.txt", EdgeKind::kAnchor, 0);
  EXPECT_EQ(t.edges, (std::vector<GlobalId>{3, 3}));
  EXPECT_EQ(edge_error("0 y 0.5\n", EdgeKind::kAnchor), "e.csv:1: column 2 (anchor): 'y' is not an integer index");
  EXPECT_EQ(edge_error("0 1\n", EdgeKind::kAnchor), "e.csv:1: 2 columns, expected 3 or 4 (i, anchor, range[, sigma])");
}

TEST(TextTable, PointsHaveOneDimension) {
  const PointTable t = parse_points("x,y\n0,0\n1, 0.5\n", "p.csv");
  EXPECT_EQ(t.dim, 2);
  EXPECT_EQ(t.coords, (std::vector<double>{0, 0, 1, 0.5}));
  EXPECT_EQ(t.rows(), 2);
  EXPECT_EQ(parse_points("1 2 3\n", "p.csv").dim, 3);
  const auto err = [](const std::string& text) { return error_of([&] { parse_points(text, "p.csv"); }); };
  EXPECT_EQ(err("0,0\n1,2,3\n"),
            "p.csv:2: 3 columns, but line 1 has 2: every row must have the same number of coordinates (the dimension p)");
  EXPECT_EQ(err("1,2,3,4\n"), "p.csv:1: 4 columns, expected 1, 2 or 3 coordinates (the dimension p)");
  EXPECT_EQ(err("0,0\n1\n"),
            "p.csv:2: 1 columns, but line 1 has 2: every row must have the same number of coordinates (the dimension p)");
  EXPECT_EQ(parse_points("3\n-1.5\n", "p.csv").dim, 1);  // p = 1: points on a line
  EXPECT_EQ(err("0,0\n1,inf\n"), "p.csv:2: coordinate y is Inf");
  EXPECT_EQ(err("0,0\n1,z\n"), "p.csv:2: column 2 (y): 'z' is not a number");
}

// A small valid input: 3 sensors, 2 anchors in the plane.
ImportInput small_input() {
  ImportInput in;
  in.sensor_edges = {"e.csv", "i,j,range\n0,1,0.5\n1,2,0.5\n2,1,0.75\n"};
  in.anchor_edges = {"a.txt", "0 0 0.1\n2 1 0.2\n"};
  in.anchors = {"anc.csv", "0,0\n1,1\n"};
  return in;
}

std::string import_error(const ImportInput& in, const ImportOptions& opt = {}) {
  return error_of([&] { import_network(in, opt); });
}

TEST(TextTable, ImportsAWholeValidNetwork) {
  ImportInput in = small_input();
  snl::Network net = import_network(in, {});
  EXPECT_EQ(net.num_sensors, 3);  // largest id + 1
  EXPECT_EQ(net.dim, 2);
  EXPECT_EQ(net.num_anchors(), 2);
  EXPECT_EQ(net.sensor_edges, (std::vector<GlobalId>{0, 1, 1, 2, 2, 1}));  // duplicates kept, file order
  EXPECT_EQ(net.anchor_edges, (std::vector<GlobalId>{0, 0, 2, 1}));
  EXPECT_FALSE(net.has_truth);
  EXPECT_FALSE(net.sigma.has_value());
  EXPECT_TRUE(snl::check_network(net, true).ok());

  ImportOptions opt;
  opt.sensors = 5;
  opt.sigma = 0.01;
  net = import_network(in, opt);
  EXPECT_EQ(net.num_sensors, 5);
  ASSERT_TRUE(net.sigma.has_value());
  EXPECT_EQ(*net.sigma, 0.01);

  in.truth = TextFile{"t.csv", "x,y\n0,0\n1,0\n0,1\n0.5,0.5\n"};  // n = truth rows
  net = import_network(in, {});
  EXPECT_EQ(net.num_sensors, 4);
  EXPECT_TRUE(net.has_truth);
  EXPECT_EQ(net.truth.size(), 8u);
  EXPECT_TRUE(snl::check_network(net, true).ok());

  in = small_input();  // 1-based ids: the same network
  in.sensor_edges.text = "1,2,0.5\n2,3,0.5\n3,2,0.75\n";
  in.anchor_edges.text = "1 1 0.1\n3 2 0.2\n";
  opt = {};
  opt.index_base = 1;
  net = import_network(in, opt);
  EXPECT_EQ(net.num_sensors, 3);
  EXPECT_EQ(net.sensor_edges, (std::vector<GlobalId>{0, 1, 1, 2, 2, 1}));
  EXPECT_EQ(net.anchor_edges, (std::vector<GlobalId>{0, 0, 2, 1}));
}

TEST(TextTable, ImportCarriesSigmasOfEachFile) {
  ImportInput in = small_input();
  in.anchor_edges.text = "0 0 0.1 0.5\n2 1 0.2 0.25\n";
  const snl::Network net = import_network(in, {});
  EXPECT_TRUE(net.sensor_sigmas.empty());
  EXPECT_EQ(net.anchor_sigmas, (std::vector<double>{0.5, 0.25}));
  EXPECT_TRUE(snl::check_network(net, true).ok());
  in.sensor_edges.text = "0,1,0.5,0.125\n1,2,0.5,0.0625\n";
  in.anchor_edges.text = "0 0 0.1\n2 1 0.2\n";
  const snl::Network net2 = import_network(in, {});
  EXPECT_EQ(net2.sensor_sigmas, (std::vector<double>{0.125, 0.0625}));
  EXPECT_TRUE(net2.anchor_sigmas.empty());
}

TEST(TextTable, ImportChecksIdsAndShapesAtTheirLines) {
  ImportInput in = small_input();
  ImportOptions opt;
  opt.sensors = 2;
  EXPECT_EQ(import_error(in, opt), "e.csv:3: sensor index 2 out of range [0, 2) (n = 2 from --sensors)");
  in.sensor_edges.text = "0,1,0.5\n";
  EXPECT_EQ(import_error(in, opt), "a.txt:2: sensor index 2 out of range [0, 2) (n = 2 from --sensors)");
  in = small_input();
  in.anchor_edges.text = "0 0 0.1\n\n2 2 0.2\n";
  EXPECT_EQ(import_error(in), "a.txt:3: anchor index 2 out of range [0, 2) (2 rows in anc.csv)");
  opt = {};
  opt.index_base = 1;
  in.sensor_edges.text = "1,2,0.5\n";
  in.anchor_edges.text = "1 3 0.1\n";
  EXPECT_EQ(import_error(in, opt), "a.txt:1: anchor index 3 out of range [1, 3) (2 rows in anc.csv)");

  in = small_input();
  in.truth = TextFile{"t.csv", "0,0\n1,1\n"};
  EXPECT_EQ(import_error(in), "e.csv:3: sensor index 2 out of range [0, 2) (n = 2 rows in t.csv)");
  opt = {};
  opt.sensors = 3;
  EXPECT_EQ(import_error(in, opt), "t.csv: 2 rows, expected one per sensor (n = 3 from --sensors)");
  in.truth = TextFile{"t.csv", "x,y\n"};
  EXPECT_EQ(import_error(in), "t.csv: no rows (one true position per sensor expected)");
  in.truth = TextFile{"t.csv", "# 3D\n0,0,0\n1,1,1\n2,2,2\n"};
  EXPECT_EQ(import_error(in), "t.csv:2: 3 coordinates, but anc.csv has 2 (the dimension p)");

  in = small_input();
  in.anchors.text = "x,y\n";
  EXPECT_EQ(import_error(in),
            "anc.csv: no anchor rows (at least one anchor is needed; its columns give the dimension p)");
  in = small_input();
  in.sensor_edges.text = "";
  in.anchor_edges.text = "# none\n";
  EXPECT_EQ(import_error(in), "no sensor ids in e.csv or a.txt: give the number of sensors (--sensors N) or a truth file");
  opt = {};
  opt.sensors = 4;
  EXPECT_EQ(import_network(in, opt).num_sensors, 4);  // a network without measurements is still a network
}

TEST(TextTable, OptionsAreValidated) {
  ImportOptions opt;
  EXPECT_EQ(opt.validate(), "");
  opt.index_base = 2;
  EXPECT_EQ(opt.validate(), "--index-base must be 0 or 1, got 2");
  opt = {};
  opt.sensors = -3;
  EXPECT_EQ(opt.validate(), "--sensors must be positive, got -3");
  opt = {};
  opt.sigma = std::numeric_limits<double>::infinity();
  EXPECT_EQ(opt.validate(), "--sigma must be finite and >= 0");
  EXPECT_EQ(import_error(small_input(), opt), "--sigma must be finite and >= 0");
}

}  // namespace
