// Collective result files (src/io/result_io.cpp) on 1, 2 and 3 ranks: slabs
// written by one distribution read back by another, rank-local errors that
// become the same error everywhere, failed writes that leave the old file intact.
#include <gtest/gtest.h>
#include <mpi.h>
#include <sys/stat.h>

#include <cstdlib>
#include <string>
#include <vector>

#include "io_helpers.hpp"
#include "snl/core/mpi_util.hpp"
#include "snl/io/h5file.hpp"
#include "snl/io/network.hpp"
#include "snl/io/result_io.hpp"

using namespace snl;
using snl::test::path_of;

namespace {

const MPI_Comm kWorld = MPI_COMM_WORLD;

}  // namespace

TEST(ResultIoMpi, WriteSlabsReadOtherSlabs) {
  const int rank = comm_rank(kWorld), size = comm_size(kWorld);
  const GlobalId n = 17;
  ResultFile r;
  r.algorithm = "relaxation";
  r.iterations = 5;
  r.converged = false;
  r.dim = 3;
  r.num_sensors = n;
  GlobalId b, e;
  block_range(n, size, rank, b, e);
  r.row_offset = b;
  for (GlobalId k = 3 * b; k < 3 * e; ++k) r.positions.push_back(static_cast<double>(k) + 0.5);
  r.history = {{"iteration", {0, 1}}, {"cost", {2.0, 1.0}}, {"communications", {4, 8}}, {"rmse", {0.1, 0.05}}};
  r.double_attrs = {{"wall_seconds", 1.25}};
  r.string_attrs = {{"network", "net.h5"}};
  const std::string path = path_of("result.h5");
  write_result(path, kWorld, r);

  // Read back with a different distribution: rank r takes the block of rank size-1-r.
  block_range(n, size, size - 1 - rank, b, e);
  const std::vector<double> got = read_positions(path, kWorld, n, 3, b, e - b);
  ASSERT_EQ(got.size(), static_cast<std::size_t>(3 * (e - b)));
  for (GlobalId k = 0; k < 3 * (e - b); ++k) EXPECT_EQ(got[k], static_cast<double>(3 * b + k) + 0.5);

  if (rank == 0) {
    const ResultFile whole = read_result_serial(path);
    EXPECT_EQ(whole.algorithm, "relaxation");
    EXPECT_EQ(whole.iterations, 5);
    EXPECT_FALSE(whole.converged);
    EXPECT_EQ(whole.positions.size(), static_cast<std::size_t>(3 * n));
    for (GlobalId k = 0; k < 3 * n; ++k) EXPECT_EQ(whole.positions[k], static_cast<double>(k) + 0.5);
    EXPECT_EQ(whole.history.size(), 4u);
    EXPECT_EQ(whole.double_attrs, r.double_attrs);
    EXPECT_EQ(whole.string_attrs, r.string_attrs);
  }
  MPI_Barrier(kWorld);

  // A rank-local bad request becomes the same error everywhere.
  try {
    read_positions(path, kWorld, n, 3, rank == size - 1 ? n : 0, rank == size - 1 ? 1 : 0);
    ADD_FAILURE() << "no error";
  } catch (const Error& ex) {
    EXPECT_NE(std::string(ex.what()).find("requested outside [0, 17)"), std::string::npos) << ex.what();
  }
  // Wrong expected shape.
  EXPECT_THROW(read_positions(path, kWorld, n, 2, 0, 0), Error);
}

TEST(ResultIoMpi, FailedWriteLeavesExistingFileIntact) {
  const int rank = comm_rank(kWorld), size = comm_size(kWorld);
  const std::string path = path_of("keep_result.h5");
  ResultFile r;
  r.algorithm = "mm";
  r.dim = 2;
  r.num_sensors = 6;
  GlobalId b, e;
  block_range(6, size, rank, b, e);
  r.row_offset = b;
  for (GlobalId k = 2 * b; k < 2 * e; ++k) r.positions.push_back(static_cast<double>(k));
  write_result(path, kWorld, r);

  struct stat st0 {};
  ASSERT_EQ(::stat(path.c_str(), &st0), 0);

  // 1. Inconsistent input (rows do not add up to n): refused before writing.
  ResultFile bad = r;
  bad.num_sensors = 7;
  bad.algorithm = "broken";
  EXPECT_THROW(write_result(path, kWorld, bad), Error);

  // 2. A failure in the middle of writing, raised on one rank only.
  try {
    H5File f(path, kWorld, H5File::Mode::kCreate);
    f.set_attr("format", std::string("snl-result"));
    const std::vector<double> v(4, 1.0);
    // Rank 0 asks for rows outside the dataset: a rank-local error.
    f.write_rows("positions", 2, 2, rank == 0 ? 1 : 0, rank == 0 ? v.data() : nullptr, rank == 0 ? 2 : 0);
    f.commit();
    ADD_FAILURE() << "no error";
  } catch (const Error& ex) {
    EXPECT_NE(std::string(ex.what()).find("lie outside [0, 2)"), std::string::npos) << ex.what();
  }
  MPI_Barrier(kWorld);

  struct stat st1 {};
  ASSERT_EQ(::stat(path.c_str(), &st1), 0);
  EXPECT_EQ(st1.st_size, st0.st_size);
  EXPECT_EQ(st1.st_mtime, st0.st_mtime);
  if (rank == 0) {
    const ResultFile back = read_result_serial(path);
    EXPECT_EQ(back.algorithm, "mm");
    EXPECT_EQ(back.num_sensors, 6);
  }
  // No temporary left behind.
  std::string leftovers;
  const std::string dir = test::scratch_dir(kWorld);  // collective: outside the rank-0 branch
  if (rank == 0) {
    const std::string cmd = "ls '" + dir + "' | grep -q 'keep_result.h5.tmp'";
    if (std::system(cmd.c_str()) == 0) leftovers = "temporary file left behind";
  }
  EXPECT_NO_THROW(agree(kWorld, leftovers));
}
