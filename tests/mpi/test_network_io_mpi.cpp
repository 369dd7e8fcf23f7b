// Collective network reading (src/io/network.cpp) on 1, 2 and 3 ranks:
// slabs tile the file, errors are identical on every rank (the first bad row
// of the whole file wins).
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <limits>

#include "io_helpers.hpp"
#include "snl/core/mpi_util.hpp"
#include "snl/io/network.hpp"

using namespace snl;
using snl::test::path_of;

namespace {

const MPI_Comm kWorld = MPI_COMM_WORLD;

/// A deterministic network, the same on every rank.
Network make(GlobalId n, GlobalId E, GlobalId Ea, bool truth) {
  Network net;
  net.dim = 2;
  net.num_sensors = n;
  net.anchors = {0, 0, 1, 0, 0, 1, 1, 1};
  for (GlobalId e = 0; e < E; ++e) {
    const GlobalId i = e % n, j = (e * 7 + 1) % n == i ? (i + 1) % n : (e * 7 + 1) % n;
    net.sensor_edges.insert(net.sensor_edges.end(), {i, j});
    net.sensor_ranges.push_back(0.5 + 0.001 * static_cast<double>(e));
  }
  for (GlobalId e = 0; e < Ea; ++e) {
    net.anchor_edges.insert(net.anchor_edges.end(), {(e * 3) % n, e % 4});
    net.anchor_ranges.push_back(0.25 + 0.002 * static_cast<double>(e));
  }
  net.has_truth = truth;
  if (truth)
    for (GlobalId k = 0; k < 2 * n; ++k) net.truth.push_back(0.01 * static_cast<double>(k));
  if (truth) net.sigma = 0.05;
  if (truth)
    for (GlobalId i = 0; i < n; ++i) net.localizability.push_back(static_cast<std::uint8_t>(i % 3));
  return net;
}

/// Rank 0 writes (serially); everybody waits for the file.
void write_on_root(const std::string& path, const Network& net) {
  std::string err;
  if (comm_rank(kWorld) == 0) {
    try {
      write_network(path, net);
    } catch (const std::exception& e) {
      err = e.what();
    }
  }
  agree(kWorld, err);
}

template <class T>
std::vector<T> rows_of(const std::vector<T>& v, GlobalId width, GlobalId b, GlobalId e) {
  return std::vector<T>(v.begin() + b * width, v.begin() + e * width);
}

std::string collective_error(const std::string& path) {
  try {
    read_network(path, kWorld);
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

void check_tiling(GlobalId n, GlobalId E, GlobalId Ea, bool truth, const std::string& name) {
  const Network whole = make(n, E, Ea, truth);
  const std::string path = path_of(name);
  write_on_root(path, whole);
  const Network s = read_network(path, kWorld);
  const int rank = comm_rank(kWorld), size = comm_size(kWorld);
  EXPECT_EQ(s.dim, 2);
  EXPECT_EQ(s.num_sensors, n);
  EXPECT_EQ(s.anchors, whole.anchors);  // complete on every rank
  EXPECT_EQ(s.total_sensor_edges, E);
  EXPECT_EQ(s.total_anchor_edges, Ea);
  EXPECT_EQ(s.has_truth, truth);
  EXPECT_EQ(s.sigma, whole.sigma);
  GlobalId b, e;
  block_range(E, size, rank, b, e);
  EXPECT_EQ(s.sensor_edge_offset, b);
  EXPECT_EQ(s.sensor_edges, rows_of(whole.sensor_edges, 2, b, e));
  EXPECT_EQ(s.sensor_ranges, rows_of(whole.sensor_ranges, 1, b, e));
  block_range(Ea, size, rank, b, e);
  EXPECT_EQ(s.anchor_edge_offset, b);
  EXPECT_EQ(s.anchor_edges, rows_of(whole.anchor_edges, 2, b, e));
  EXPECT_EQ(s.anchor_ranges, rows_of(whole.anchor_ranges, 1, b, e));
  block_range(n, size, rank, b, e);
  EXPECT_EQ(s.sensor_row_offset, b);
  if (truth) {
    EXPECT_EQ(s.truth, rows_of(whole.truth, 2, b, e));
    EXPECT_EQ(s.localizability, rows_of(whole.localizability, 1, b, e));
  } else {
    EXPECT_TRUE(s.truth.empty());
    EXPECT_TRUE(s.localizability.empty());
  }
  // The slabs add up to the whole file.
  long long sums[3] = {s.local_sensor_edges(), s.local_anchor_edges(),
                       static_cast<long long>(s.truth.size() / 2)};
  MPI_Allreduce(MPI_IN_PLACE, sums, 3, MPI_LONG_LONG, MPI_SUM, kWorld);
  EXPECT_EQ(sums[0], E);
  EXPECT_EQ(sums[1], Ea);
  EXPECT_EQ(sums[2], truth ? n : 0);
}

}  // namespace

TEST(NetworkIoMpi, SlabsTileTheFile) {
  check_tiling(11, 29, 13, true, "tile_a.h5");
  check_tiling(5, 1, 2, false, "tile_b.h5");  // fewer rows than ranks
  check_tiling(4, 0, 0, true, "tile_c.h5");   // E = Ea = 0
  check_tiling(1000, 3000, 400, true, "tile_d.h5");
}

TEST(NetworkIoMpi, SameErrorOnEveryRankFirstRowWins) {
  const int size = comm_size(kWorld);
  const GlobalId E = 30;
  Network net = make(10, E, 12, true);
  // Bad rows near the end of sensor_ranges (the last rank's slab), at the start
  // of a later dataset (rank 0's slab), and a later bad row in the same dataset.
  net.sensor_ranges[E - 2] = -1.0;
  net.sensor_ranges[E - 1] = std::numeric_limits<double>::quiet_NaN();
  net.anchor_ranges[0] = -3.0;
  const std::string path = path_of("bad_last.h5");
  write_on_root(path, net);
  EXPECT_EQ(collective_error(path), path + ": sensor_ranges row 28: range -1 is negative");

  // An earlier dataset beats an earlier row: edges in the last slab vs ranges in the first.
  net = make(10, E, 12, true);
  net.sensor_ranges[0] = -2.0;
  net.sensor_edges[2 * (E - 1)] = 99;
  const std::string path2 = path_of("bad_mixed.h5");
  write_on_root(path2, net);
  EXPECT_EQ(collective_error(path2), path2 + ": sensor_edges row 29: sensor index 99 out of range [0, 10)");

  // Bad rows in the middle and last slab: the middle one (lower row) wins.
  net = make(10, E, 12, true);
  GlobalId b, e;
  block_range(E, size, size > 1 ? 1 : 0, b, e);
  net.sensor_edges[2 * b + 1] = net.sensor_edges[2 * b];  // self-loop at row b
  net.sensor_edges[2 * (E - 1) + 1] = net.sensor_edges[2 * (E - 1)];
  const std::string path3 = path_of("bad_two.h5");
  write_on_root(path3, net);
  const GlobalId i = net.sensor_edges[2 * b];
  EXPECT_EQ(collective_error(path3), path3 + ": sensor_edges row " + std::to_string(b) + ": self-loop (" +
                                         std::to_string(i) + ", " + std::to_string(i) + ")");

  // Truth rows are global sensor ids.
  net = make(10, E, 12, true);
  net.truth[2 * 9 + 1] = std::numeric_limits<double>::infinity();
  const std::string path4 = path_of("bad_truth.h5");
  write_on_root(path4, net);
  EXPECT_EQ(collective_error(path4), path4 + ": truth row 9: coordinate 1 is Inf");
}

TEST(NetworkIoMpi, FileErrorsAgree) {
  const std::string missing = path_of("nope.h5");
  EXPECT_EQ(collective_error(missing), missing + ": no such file");
  const std::string text = path_of("text.h5");
  if (comm_rank(kWorld) == 0) {
    FILE* f = std::fopen(text.c_str(), "w");
    std::fputs("not hdf5", f);
    std::fclose(f);
  }
  MPI_Barrier(kWorld);
  EXPECT_EQ(collective_error(text).rfind(text + ": not a readable HDF5 file", 0), 0u);
}
