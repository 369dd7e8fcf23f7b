#pragma once
// Small in-memory networks for the tests (brute force, independent of the
// library's generator), and slabs of them as read_network would hand out.
#include <mpi.h>

#include <cmath>
#include <vector>

#include "snl/io/network.hpp"
#include "snl/problem/problem.hpp"
#include "snl/core/random.hpp"

namespace snl::test {

struct NetSpec {
  GlobalId n = 50;
  int dim = 2;
  double radius = 0.3;
  double anchor_radius = 0.3;
  double sigma = 0.01;
  std::uint64_t seed = 7;
  bool duplicates = false;  // add reversed duplicate rows of every 5th edge
};

inline Network make_network(const NetSpec& s) {
  Network net;
  net.dim = s.dim;
  net.num_sensors = s.n;
  const int p = s.dim;
  for (int k = 0; k < (1 << p); ++k)
    for (int c = 0; c < p; ++c) net.anchors.push_back((k >> c) & 1 ? 1.0 : 0.0);
  net.truth.resize(s.n * p);
  for (GlobalId i = 0; i < s.n * p; ++i) net.truth[i] = uniform01(s.seed, RngStream::kSensorPositions, i);
  net.has_truth = true;
  net.sigma = s.sigma;
  auto dist = [&](const double* a, const double* b) {
    double q = 0;
    for (int c = 0; c < p; ++c) q += (a[c] - b[c]) * (a[c] - b[c]);
    return std::sqrt(q);
  };
  std::uint64_t ctr = 0;
  for (GlobalId i = 0; i < s.n; ++i)
    for (GlobalId j = i + 1; j < s.n; ++j) {
      const double d = dist(&net.truth[i * p], &net.truth[j * p]);
      if (d > s.radius) continue;
      const double r = std::abs(d + s.sigma * standard_normal(s.seed, RngStream::kSensorNoise, ctr++));
      net.sensor_edges.push_back(i);
      net.sensor_edges.push_back(j);
      net.sensor_ranges.push_back(r);
      if (s.duplicates && ctr % 5 == 0) {
        net.sensor_edges.push_back(j);
        net.sensor_edges.push_back(i);
        net.sensor_ranges.push_back(r + 0.01);
      }
    }
  for (GlobalId i = 0; i < s.n; ++i)
    for (GlobalId k = 0; k < net.num_anchors(); ++k) {
      const double d = dist(&net.truth[i * p], &net.anchors[k * p]);
      if (d > s.anchor_radius) continue;
      net.anchor_edges.push_back(i);
      net.anchor_edges.push_back(k);
      net.anchor_ranges.push_back(std::abs(d + s.sigma * standard_normal(s.seed, RngStream::kAnchorNoise, ctr++)));
    }
  net.total_sensor_edges = net.local_sensor_edges();
  net.total_anchor_edges = net.local_anchor_edges();
  return net;
}

/// This rank's slab of a whole network, as read_network hands it out.
inline Network slab_of(const Network& w, MPI_Comm comm) { return network_slab(w, comm); }

/// Owned rows (local order) -> the whole [n, p] array in global order, on every rank.
inline std::vector<double> allgather_positions(const LocalizationProblem& prob, const std::vector<double>& owned) {
  GlobalId off = 0;
  std::vector<double> rows = prob.owned_to_file_rows(owned.data(), prob.dim(), &off);
  int size = 1;
  MPI_Comm_size(prob.comm(), &size);
  std::vector<int> counts(size), displs(size);
  int mine = static_cast<int>(rows.size());
  MPI_Allgather(&mine, 1, MPI_INT, counts.data(), 1, MPI_INT, prob.comm());
  for (int r = 1; r < size; ++r) displs[r] = displs[r - 1] + counts[r - 1];
  std::vector<double> all(std::size_t(prob.num_sensors()) * prob.dim());
  MPI_Allgatherv(rows.data(), mine, MPI_DOUBLE, all.data(), counts.data(), displs.data(), MPI_DOUBLE, prob.comm());
  return all;
}

}  // namespace snl::test
