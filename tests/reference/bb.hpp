#pragma once
// Reference twin of the Barzilai-Borwein baseline (algorithms.md, "Baselines":
// Calafiore, Carlone, Wei 2010): gradient descent on the ML cost f with the
// step alpha = (s's)/(s'y), s = x(k) - x(k-1), y = grad f(x(k)) - grad f(x(k-1)),
// where both inner products are replaced by each node's estimate after T
// rounds of average consensus with Metropolis weights
// W_ij = 1 / (1 + max(delta_i, delta_j)), W_ii = 1 - sum_j W_ij.
// Written on the whole edge list, independently of src/solvers/bb.cpp, with
// the conventions that file states:
//  - x(-1) = 0 and grad f(x(-1)) = 0, and the first iteration steps 1/L
//    (L = 2 delta_max + max |A_i|, the relaxation's constant);
//  - a node whose estimate s's/s'y is not finite and positive steps 1/L;
//  - the ML gradient term (1 - r/|z|) z is zero where |z| = 0.
// model_bb is the same method on the weighted / Huber ML cost (Model in
// reference.hpp): each term w_e omega(|r_e|) (1 - d_e/|z|) z, the first step
// 1/L with L = 2 max_i sum_j w_ij + max_i sum_k w_ik.
// Header-only: tests include it directly.
#include <algorithm>
#include <cmath>
#include <tuple>
#include <vector>

#include "reference/reference.hpp"
#include "snl/io/network.hpp"

namespace snl::reference {

/// `iters` BB iterations with T consensus rounds from x0 on the model m
/// (whole network, duplicates merged, global order).
inline std::vector<double> model_bb(const Network& net, const Model& m, const std::vector<double>& x0, int iters,
                                    int T) {
  const int p = net.dim;
  const GlobalId n = net.num_sensors;
  // Neighbour lists sorted by global id: the sum order the distributed code promises.
  std::vector<std::vector<GlobalId>> nb(n);
  std::vector<std::vector<double>> nr(n), nw(n);
  {
    std::vector<std::vector<std::tuple<GlobalId, double, double>>> t(n);
    for (std::size_t e = 0; e < net.sensor_ranges.size(); ++e) {
      const GlobalId i = net.sensor_edges[2 * e], j = net.sensor_edges[2 * e + 1];
      t[i].push_back({j, net.sensor_ranges[e], m.sensor_w[e]});
      t[j].push_back({i, net.sensor_ranges[e], m.sensor_w[e]});
    }
    for (GlobalId i = 0; i < n; ++i) {
      std::sort(t[i].begin(), t[i].end());
      for (auto& [j, r, w] : t[i]) {
        nb[i].push_back(j);
        nr[i].push_back(r);
        nw[i].push_back(w);
      }
    }
  }
  std::vector<std::vector<std::tuple<GlobalId, double, double>>> an(n);  // (anchor, range, weight), by anchor id
  for (std::size_t e = 0; e < net.anchor_ranges.size(); ++e)
    an[net.anchor_edges[2 * e]].push_back({net.anchor_edges[2 * e + 1], net.anchor_ranges[e], m.anchor_w[e]});
  double wmax = 0, amax = 0;
  for (GlobalId i = 0; i < n; ++i) {
    std::sort(an[i].begin(), an[i].end());
    double ws = 0, wa = 0;
    for (double w : nw[i]) ws += w;
    for (auto& [a, r, w] : an[i]) wa += w;
    wmax = std::max(wmax, ws);
    amax = std::max(amax, wa);
  }
  const double alpha0 = 1.0 / (2.0 * wmax + amax);

  auto grad = [&](const std::vector<double>& x) {
    std::vector<double> g(x.size(), 0.0);
    auto term = [&](const double* xi, const double* y, double r, double w, double* gi) {
      double z[3], s = 0;
      for (int c = 0; c < p; ++c) {
        z[c] = xi[c] - y[c];
        s += z[c] * z[c];
      }
      s = std::sqrt(s);
      if (s == 0) return;
      const double res = std::abs(s - r);
      const double omega = m.delta > 0 && res > m.delta ? m.delta / res : 1.0;
      const double a = w * omega * (1 - r / s);
      for (int c = 0; c < p; ++c) gi[c] += a * z[c];
    };
    for (GlobalId i = 0; i < n; ++i) {
      for (std::size_t k = 0; k < nb[i].size(); ++k) term(&x[i * p], &x[nb[i][k] * p], nr[i][k], nw[i][k], &g[i * p]);
      for (auto& [a, r, w] : an[i]) term(&x[i * p], &net.anchors[a * p], r, w, &g[i * p]);
    }
    return g;
  };

  std::vector<double> x = x0, x_old(x.size(), 0.0), g_old(x.size(), 0.0);
  std::vector<double> ss(n), sy(n), ss2(n), sy2(n);
  for (int k = 1; k <= iters; ++k) {
    const std::vector<double> g = grad(x);
    for (GlobalId i = 0; i < n; ++i) {
      ss[i] = sy[i] = 0;
      for (int c = 0; c < p; ++c) {
        const double s = x[i * p + c] - x_old[i * p + c], y = g[i * p + c] - g_old[i * p + c];
        ss[i] += s * s;
        sy[i] += s * y;
      }
    }
    for (int r = 0; r < T; ++r) {  // Metropolis averaging, all nodes at once
      for (GlobalId i = 0; i < n; ++i) {
        auto w = [&](GlobalId j) { return 1.0 / (1.0 + double(std::max(nb[i].size(), nb[j].size()))); };
        double self = 1;
        for (GlobalId j : nb[i]) self -= w(j);
        double a = self * ss[i], b = self * sy[i];
        for (GlobalId j : nb[i]) {
          a += w(j) * ss[j];
          b += w(j) * sy[j];
        }
        ss2[i] = a;
        sy2[i] = b;
      }
      ss.swap(ss2);
      sy.swap(sy2);
    }
    for (GlobalId i = 0; i < n; ++i) {
      double alpha = alpha0;
      if (k > 1) {
        const double a = ss[i] / sy[i];
        if (std::isfinite(a) && a > 0) alpha = a;
      }
      for (int c = 0; c < p; ++c) {
        x_old[i * p + c] = x[i * p + c];
        g_old[i * p + c] = g[i * p + c];
        x[i * p + c] -= alpha * g[i * p + c];
      }
    }
  }
  return x;
}

/// The unweighted method: every weight 1, l2.
inline std::vector<double> bb(const Network& net, const std::vector<double>& x0, int iters, int T) {
  Model m;
  m.sensor_w.assign(net.sensor_ranges.size(), 1.0);
  m.anchor_w.assign(net.anchor_ranges.size(), 1.0);
  return model_bb(net, m, x0, iters, T);
}

}  // namespace snl::reference
