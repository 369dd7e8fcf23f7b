// Result files (src/io/result_io.cpp), serially: round trip, and the checks
// of read_positions.
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "io_helpers.hpp"
#include "snl/io/h5file.hpp"
#include "snl/io/result_io.hpp"

using namespace snl;
using snl::test::read_error;
using snl::test::scratch;

TEST(ResultIo, SerialRoundTrip) {
  const std::string path = scratch("result.h5");
  ResultFile r;
  r.algorithm = "mm";
  r.iterations = 17;
  r.converged = true;
  r.dim = 3;
  r.num_sensors = 4;
  for (int k = 0; k < 12; ++k) r.positions.push_back(k * 0.125);
  r.history = {{"iteration", {0, 1, 2}}, {"cost", {3, 2, 1}}, {"communications", {1, 2, 3}}};
  r.double_attrs = {{"tol", 1e-6}};
  r.string_attrs = {{"network", "net.h5"}};
  write_result(path, MPI_COMM_SELF, r);
  const ResultFile b = read_result_serial(path);
  EXPECT_EQ(b.algorithm, "mm");
  EXPECT_EQ(b.iterations, 17);
  EXPECT_TRUE(b.converged);
  EXPECT_EQ(b.dim, 3);
  EXPECT_EQ(b.num_sensors, 4);
  EXPECT_EQ(b.positions, r.positions);
  ASSERT_EQ(b.history.size(), 3u);  // sorted by name
  EXPECT_EQ(b.history[0].first, "communications");
  EXPECT_EQ(b.history[1].first, "cost");
  EXPECT_EQ(b.history[1].second, (std::vector<double>{3, 2, 1}));
  EXPECT_EQ(b.double_attrs, r.double_attrs);
  EXPECT_EQ(b.string_attrs, r.string_attrs);
  // Reading the result as a network fails clearly.
  EXPECT_CONTAINS(read_error(path), "attribute 'format' is 'snl-result', expected 'snl-network'");
}

TEST(ResultIo, ReadPositionsChecks) {
  const std::string path = scratch("pos.h5");
  ResultFile r;
  r.algorithm = "x";
  r.dim = 2;
  r.num_sensors = 3;
  r.positions = {0, 1, 2, 3, 4, std::numeric_limits<double>::quiet_NaN()};
  write_result(path, MPI_COMM_SELF, r);
  EXPECT_EQ(read_positions(path, MPI_COMM_SELF, 3, 2, 0, 2), (std::vector<double>{0, 1, 2, 3}));
  try {
    read_positions(path, MPI_COMM_SELF, 3, 2, 0, 3);
    FAIL();
  } catch (const Error& e) {
    EXPECT_CONTAINS(e.what(), "positions row 2 is not finite");
  }
  try {
    read_positions(path, MPI_COMM_SELF, 4, 2, 0, 4);
    FAIL();
  } catch (const Error& e) {
    EXPECT_CONTAINS(e.what(), "dataset 'positions' has shape [3, 2], expected [4, 2]");
  }
  EXPECT_THROW(read_positions(scratch("nothere.h5"), MPI_COMM_SELF, 3, 2, 0, 3), Error);
}
