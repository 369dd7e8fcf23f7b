#pragma once
// A small network built by hand with exact ranges (unit tests of the
// analysis and of the bound on hand-made frameworks).
#include <cmath>
#include <utility>
#include <vector>

#include "snl/io/network.hpp"

namespace snl::test {

struct NetworkBuilder {
  Network net;
  explicit NetworkBuilder(std::vector<double> truth, std::vector<double> anchors, int dim = 2) {
    net.dim = dim;
    net.num_sensors = static_cast<GlobalId>(truth.size()) / dim;
    net.truth = std::move(truth);
    net.has_truth = true;
    net.anchors = std::move(anchors);
  }
  double dist(const double* a, const double* b) const {
    double s = 0;
    for (int d = 0; d < net.dim; ++d) s += (a[d] - b[d]) * (a[d] - b[d]);
    return std::sqrt(s);
  }
  NetworkBuilder& s(GlobalId i, GlobalId j) {  ///< a sensor-sensor measurement
    net.sensor_edges.push_back(i);
    net.sensor_edges.push_back(j);
    net.sensor_ranges.push_back(dist(&net.truth[i * net.dim], &net.truth[j * net.dim]));
    return *this;
  }
  NetworkBuilder& a(GlobalId i, GlobalId k) {  ///< a sensor-anchor measurement
    net.anchor_edges.push_back(i);
    net.anchor_edges.push_back(k);
    net.anchor_ranges.push_back(dist(&net.truth[i * net.dim], &net.anchors[k * net.dim]));
    return *this;
  }
  Network done() {
    net.total_sensor_edges = net.local_sensor_edges();
    net.total_anchor_edges = net.local_anchor_edges();
    return net;
  }
};

/// The unit square's corners as anchors.
inline const std::vector<double> kCorners = {0, 0, 1, 0, 0, 1, 1, 1};

}  // namespace snl::test
