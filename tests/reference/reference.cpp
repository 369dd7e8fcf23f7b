#include "reference/reference.hpp"

#include "snl/core/random.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <queue>

namespace snl::reference {

namespace {
double dist(const double* a, const double* b, int p) {
  double s = 0;
  for (int c = 0; c < p; ++c) s += (a[c] - b[c]) * (a[c] - b[c]);
  return std::sqrt(s);
}
void sphere(double rho, double* v, int p) {
  double s = 0;
  for (int c = 0; c < p; ++c) s += v[c] * v[c];
  s = std::sqrt(s);
  if (s > 0)
    for (int c = 0; c < p; ++c) v[c] = rho * v[c] / s;
  else {
    v[0] = rho;
    for (int c = 1; c < p; ++c) v[c] = 0;
  }
}
std::vector<int> degrees(const Network& net) {
  std::vector<int> d(net.num_sensors, 0);
  for (std::size_t e = 0; e < net.sensor_ranges.size(); ++e) {
    ++d[net.sensor_edges[2 * e]];
    ++d[net.sensor_edges[2 * e + 1]];
  }
  return d;
}
int max_anchor_degree(const Network& net) {
  std::vector<int> d(net.num_sensors, 0);
  for (std::size_t e = 0; e < net.anchor_ranges.size(); ++e) ++d[net.anchor_edges[2 * e]];
  return d.empty() ? 0 : *std::max_element(d.begin(), d.end());
}
}  // namespace

double ml_cost(const Network& net, const std::vector<double>& x) {
  const int p = net.dim;
  double f = 0;
  for (std::size_t e = 0; e < net.sensor_ranges.size(); ++e) {
    const double r = dist(&x[net.sensor_edges[2 * e] * p], &x[net.sensor_edges[2 * e + 1] * p], p) - net.sensor_ranges[e];
    f += 0.5 * r * r;
  }
  for (std::size_t e = 0; e < net.anchor_ranges.size(); ++e) {
    const double r = dist(&x[net.anchor_edges[2 * e] * p], &net.anchors[net.anchor_edges[2 * e + 1] * p], p) -
                     net.anchor_ranges[e];
    f += 0.5 * r * r;
  }
  return f;
}

double relaxed_cost(const Network& net, const std::vector<double>& x) {
  const int p = net.dim;
  double f = 0;
  for (std::size_t e = 0; e < net.sensor_ranges.size(); ++e) {
    const double r = dist(&x[net.sensor_edges[2 * e] * p], &x[net.sensor_edges[2 * e + 1] * p], p) - net.sensor_ranges[e];
    if (r > 0) f += 0.5 * r * r;
  }
  for (std::size_t e = 0; e < net.anchor_ranges.size(); ++e) {
    const double r = dist(&x[net.anchor_edges[2 * e] * p], &net.anchors[net.anchor_edges[2 * e + 1] * p], p) -
                     net.anchor_ranges[e];
    if (r > 0) f += 0.5 * r * r;
  }
  return f;
}

std::vector<double> relaxed_gradient(const Network& net, const std::vector<double>& x) {
  const int p = net.dim;
  std::vector<double> g(x.size(), 0.0);
  for (std::size_t e = 0; e < net.sensor_ranges.size(); ++e) {
    const GlobalId i = net.sensor_edges[2 * e], j = net.sensor_edges[2 * e + 1];
    const double d = dist(&x[i * p], &x[j * p], p);
    if (d <= net.sensor_ranges[e]) continue;
    const double c = 1 - net.sensor_ranges[e] / d;
    for (int k = 0; k < p; ++k) {
      g[i * p + k] += c * (x[i * p + k] - x[j * p + k]);
      g[j * p + k] -= c * (x[i * p + k] - x[j * p + k]);
    }
  }
  for (std::size_t e = 0; e < net.anchor_ranges.size(); ++e) {
    const GlobalId i = net.anchor_edges[2 * e];
    const double* a = &net.anchors[net.anchor_edges[2 * e + 1] * p];
    const double d = dist(&x[i * p], a, p);
    if (d <= net.anchor_ranges[e]) continue;
    const double c = 1 - net.anchor_ranges[e] / d;
    for (int k = 0; k < p; ++k) g[i * p + k] += c * (x[i * p + k] - a[k]);
  }
  return g;
}

double relaxation_lipschitz(const Network& net) {
  const auto d = degrees(net);
  const int dmax = d.empty() ? 0 : *std::max_element(d.begin(), d.end());
  return 2.0 * dmax + max_anchor_degree(net);
}

std::vector<double> nesterov(const Network& net, const std::vector<double>& x0, int iters) {
  const double L = relaxation_lipschitz(net);
  std::vector<double> x = x0, xm = x0, w(x0.size());
  for (int k = 1; k <= iters; ++k) {
    for (std::size_t t = 0; t < x.size(); ++t) w[t] = x[t] + (double(k) - 2) / (double(k) + 1) * (x[t] - xm[t]);
    const auto g = relaxed_gradient(net, w);
    xm = x;
    for (std::size_t t = 0; t < x.size(); ++t) x[t] = w[t] - g[t] / L;
  }
  return x;
}

namespace {
// 000's MM (Algorithm 1) on z = (x, y): y holds p reals per sensor edge,
// oriented i -> j with i < j, then p per anchor edge. The surrogate F (eq. 2),
// y at its best for x (where F = f), and one projected gradient step with
// step 1/L (eqs. 11-13), in place.
struct PlainMM {
  const Network& net;
  int p;
  double L;
  std::size_t E, Ea;
  std::vector<GlobalId> ei, ej;
  explicit PlainMM(const Network& n) : net(n), p(n.dim), E(n.sensor_ranges.size()), Ea(n.anchor_ranges.size()) {
    const auto d = degrees(net);
    L = 2.0 * (d.empty() ? 0 : *std::max_element(d.begin(), d.end())) + max_anchor_degree(net) + 2.0;
    ei.resize(E);
    ej.resize(E);
    for (std::size_t e = 0; e < E; ++e) {
      ei[e] = std::min(net.sensor_edges[2 * e], net.sensor_edges[2 * e + 1]);
      ej[e] = std::max(net.sensor_edges[2 * e], net.sensor_edges[2 * e + 1]);
    }
  }
  // Edge e's difference x_i - x_j (e < E) or x_i - a_k (anchor edge e - E), coordinate c.
  double dz(const std::vector<double>& x, std::size_t e, int c) const {
    if (e < E) return x[ei[e] * p + c] - x[ej[e] * p + c];
    const std::size_t k = e - E;
    return x[net.anchor_edges[2 * k] * p + c] - net.anchors[net.anchor_edges[2 * k + 1] * p + c];
  }
  double range(std::size_t e) const { return e < E ? net.sensor_ranges[e] : net.anchor_ranges[e - E]; }
  std::vector<double> best_y(const std::vector<double>& x) const {
    std::vector<double> y((E + Ea) * p);
    for (std::size_t e = 0; e < E + Ea; ++e) {
      for (int c = 0; c < p; ++c) y[e * p + c] = dz(x, e, c);
      sphere(range(e), &y[e * p], p);
    }
    return y;
  }
  double Phi(const std::vector<double>& x, const std::vector<double>& y) const {
    double s = 0;
    for (std::size_t e = 0; e < E + Ea; ++e)
      for (int c = 0; c < p; ++c) {
        const double r = dz(x, e, c) - y[e * p + c];
        s += 0.5 * r * r;
      }
    return s;
  }
  // Gradient of F with respect to x at z, then the projected steps.
  void step(std::vector<double>& x, std::vector<double>& y) const {
    std::vector<double> gx(x.size(), 0.0), yn = y;
    for (std::size_t e = 0; e < E + Ea; ++e) {
      for (int c = 0; c < p; ++c) {
        const double d = dz(x, e, c), r = d - y[e * p + c];
        if (e < E) {
          gx[ei[e] * p + c] += r;
          gx[ej[e] * p + c] -= r;
        } else {
          gx[net.anchor_edges[2 * (e - E)] * p + c] += r;
        }
        yn[e * p + c] = (L - 1) / L * y[e * p + c] + 1 / L * d;
      }
      sphere(range(e), &yn[e * p], p);
    }
    for (std::size_t t = 0; t < x.size(); ++t) x[t] -= gx[t] / L;
    y.swap(yn);
  }
};

// MM's loop over either model's MM (plain l2 or ModelMMRef): from y at its
// best for x0, `iters` steps; the surrogate Phi before and after each into *phi.
template <class MM>
std::vector<double> plain_mm(const MM& r, const std::vector<double>& x0, int iters, std::vector<double>* phi) {
  std::vector<double> x = x0, y = r.best_y(x0);
  if (phi) phi->assign(1, r.Phi(x, y));
  for (int t = 0; t < iters; ++t) {
    r.step(x, y);
    if (phi) phi->push_back(r.Phi(x, y));
  }
  return x;
}

// mm-accel's loop over either model's MM (plain l2 or ModelMMRef): the MM
// step from the extrapolated point z(k) + t/(t+3) (z(k) - z(k-1)), accepted
// when neither Phi nor the ML cost `cost` rises, else a restart (t = 0, y at
// its best for x(k)). The ML cost after each iteration into *ml, the rejected
// steps into *restarts.
template <class MM, class Cost>
std::vector<double> accelerated_mm(const MM& r, Cost cost, const std::vector<double>& x0, int iters,
                                   std::vector<double>* ml, int* restarts) {
  std::vector<double> x = x0, y = r.best_y(x0), xp = x, yp = y;
  double F = r.Phi(x, y), f = cost(x);
  if (ml) ml->assign(1, f);
  if (restarts) *restarts = 0;
  long t = 0;
  for (int it = 0; it < iters; ++it) {
    const double beta = t == 0 ? 0.0 : double(t) / double(t + 3);
    std::vector<double> v = x, yv = y;
    for (std::size_t q = 0; q < v.size(); ++q) v[q] = x[q] + beta * (x[q] - xp[q]);
    for (std::size_t q = 0; q < yv.size(); ++q) yv[q] = y[q] + beta * (y[q] - yp[q]);
    r.step(v, yv);
    const double Fn = r.Phi(v, yv), fn = cost(v);
    if (beta > 0 && !(Fn <= F && fn <= f)) {  // reject: restart from x with its best y
      t = 0;
      y = r.best_y(x);
      F = r.Phi(x, y);
      if (restarts) ++*restarts;
    } else {
      xp.swap(x);
      x.swap(v);
      yp.swap(y);
      y.swap(yv);
      F = Fn;
      f = fn;
      ++t;
    }
    if (ml) ml->push_back(f);
  }
  return x;
}
}  // namespace

std::vector<double> mm(const Network& net, const std::vector<double>& x0, int iters, std::vector<double>* surrogate) {
  return plain_mm(PlainMM(net), x0, iters, surrogate);
}

std::vector<double> mm_accel(const Network& net, const std::vector<double>& x0, int iters, std::vector<double>* ml,
                             int* restarts) {
  return accelerated_mm(
      PlainMM(net), [&](const std::vector<double>& x) { return ml_cost(net, x); }, x0, iters, ml, restarts);
}

namespace {
struct Adj {
  std::vector<std::vector<std::pair<GlobalId, double>>> nbr;  // (neighbour, range)
  std::vector<std::vector<std::pair<GlobalId, double>>> anc;  // (anchor, range)
};
Adj adjacency(const Network& net) {
  Adj a;
  a.nbr.resize(net.num_sensors);
  a.anc.resize(net.num_sensors);
  for (std::size_t e = 0; e < net.sensor_ranges.size(); ++e) {
    a.nbr[net.sensor_edges[2 * e]].push_back({net.sensor_edges[2 * e + 1], net.sensor_ranges[e]});
    a.nbr[net.sensor_edges[2 * e + 1]].push_back({net.sensor_edges[2 * e], net.sensor_ranges[e]});
  }
  for (std::size_t e = 0; e < net.anchor_ranges.size(); ++e)
    a.anc[net.anchor_edges[2 * e]].push_back({net.anchor_edges[2 * e + 1], net.anchor_ranges[e]});
  for (auto& l : a.nbr) std::sort(l.begin(), l.end());
  for (auto& l : a.anc) std::sort(l.begin(), l.end());
  return a;
}
void project_ball(const double* z, const double* c, double rho, int p, double* acc) {
  const double d = dist(z, c, p);
  const double f = d > rho ? rho / d : 1.0;
  for (int k = 0; k < p; ++k) acc[k] += c[k] + f * (z[k] - c[k]);
}
double local_f(const Network& net, const Adj& a, const std::vector<double>& x, GlobalId i, const double* v,
               double* g) {
  const int p = net.dim;
  double f = 0;
  for (int k = 0; k < p; ++k) g[k] = 0;
  auto term = [&](const double* c, double rho) {
    const double d = dist(v, c, p);
    if (d <= rho) return;
    f += 0.5 * (d - rho) * (d - rho);
    for (int k = 0; k < p; ++k) g[k] += (1 - rho / d) * (v[k] - c[k]);
  };
  for (auto& [j, r] : a.nbr[i]) term(&x[j * p], r);
  for (auto& [k, r] : a.anc[i]) term(&net.anchors[k * p], r);
  return f;
}
}  // namespace

std::vector<int> coloring(const Network& net) {
  const Adj a = adjacency(net);
  const GlobalId n = net.num_sensors;
  std::vector<std::uint64_t> prio(n);
  for (GlobalId v = 0; v < n; ++v) prio[v] = mix64(static_cast<std::uint64_t>(v) ^ 0x5bd1e995ULL);
  // Sequentially in decreasing priority: the same colours as the parallel rounds.
  std::vector<GlobalId> order(n);
  for (GlobalId v = 0; v < n; ++v) order[v] = v;
  std::sort(order.begin(), order.end(), [&](GlobalId x, GlobalId y) { return prio[x] != prio[y] ? prio[x] > prio[y] : x > y; });
  std::vector<int> c(n, -1);
  for (GlobalId v : order) {
    std::vector<char> used(a.nbr[v].size() + 2, 0);
    for (auto& [u, r] : a.nbr[v])
      if (c[u] >= 0 && c[u] < static_cast<int>(used.size())) used[c[u]] = 1;
    int k = 0;
    while (used[k]) ++k;
    c[v] = k;
  }
  return c;
}

std::vector<double> pm(const Network& net, const std::vector<double>& x0, int sweeps) {
  const int p = net.dim;
  const Adj a = adjacency(net);
  const auto col = coloring(net);
  std::vector<GlobalId> order(net.num_sensors);
  for (GlobalId v = 0; v < net.num_sensors; ++v) order[v] = v;
  std::stable_sort(order.begin(), order.end(), [&](GlobalId x, GlobalId y) { return col[x] < col[y]; });
  std::vector<double> x = x0;
  for (int s = 0; s < sweeps; ++s)
    for (GlobalId i : order) {
      const double deg = double(a.nbr[i].size() + a.anc[i].size());
      if (deg == 0) continue;
      double acc[3] = {0, 0, 0};
      for (auto& [j, r] : a.nbr[i]) project_ball(&x[i * p], &x[j * p], r, p, acc);
      for (auto& [k, r] : a.anc[i]) project_ball(&x[i * p], &net.anchors[k * p], r, p, acc);
      for (int k = 0; k < p; ++k) x[i * p + k] = acc[k] / deg;
    }
  return x;
}

std::vector<double> async(const Network& net, const std::vector<double>& x0, long activations, std::uint64_t seed,
                          bool exact, std::vector<double>* fhat) {
  const int p = net.dim;
  const Adj a = adjacency(net);
  const double L = relaxation_lipschitz(net);
  std::vector<double> x = x0;
  if (fhat) fhat->assign(1, relaxed_cost(net, x));
  for (long k = 0; k < activations; ++k) {
    GlobalId i = static_cast<GlobalId>(uniform01(seed, RngStream::kAsyncClock, k) * double(net.num_sensors));
    i = std::min<GlobalId>(i, net.num_sensors - 1);
    double g[3];
    if (!exact) {
      local_f(net, a, x, i, &x[i * p], g);
      for (int c = 0; c < p; ++c) x[i * p + c] -= g[c] / L;
    } else {
      const double Li = double(a.nbr[i].size() + a.anc[i].size());
      if (Li > 0) {
        double z[3], zm[3], w[3];
        for (int c = 0; c < p; ++c) z[c] = zm[c] = x[i * p + c];
        const double f0 = local_f(net, a, x, i, &x[i * p], g);
        for (int l = 1; l <= 500; ++l) {
          double step = 0, nz = 0;
          for (int c = 0; c < p; ++c) w[c] = z[c] + (double(l) - 2) / (double(l) + 1) * (z[c] - zm[c]);
          local_f(net, a, x, i, w, g);
          for (int c = 0; c < p; ++c) {
            zm[c] = z[c];
            z[c] = w[c] - g[c] / Li;
            step += (z[c] - zm[c]) * (z[c] - zm[c]);
            nz += z[c] * z[c];
          }
          if (step <= 1e-24 * (1 + nz)) break;
        }
        if (local_f(net, a, x, i, z, g) <= f0)
          for (int c = 0; c < p; ++c) x[i * p + c] = z[c];
      }
    }
    if (fhat) fhat->push_back(relaxed_cost(net, x));
  }
  return x;
}

}  // namespace snl::reference

// ---- the weighted / Huber model, written from the formulas (edge lists) ----
namespace snl::reference {

namespace {
double huber(double d, double r) { return d > 0 && r > d ? d * r - 0.5 * d * d : 0.5 * r * r; }
double omega(double d, double r) { return d > 0 && r > d ? d / r : 1.0; }
// Per sensor: cs * sum_j w_ij + ca * sum_k w_ik (the diagonal majorizer D).
std::vector<double> diag_majorizer(const Network& net, const Model& m, double cs, double ca) {
  std::vector<double> D(net.num_sensors, 0.0);
  for (std::size_t e = 0; e < net.sensor_ranges.size(); ++e) {
    D[net.sensor_edges[2 * e]] += cs * m.sensor_w[e];
    D[net.sensor_edges[2 * e + 1]] += cs * m.sensor_w[e];
  }
  for (std::size_t e = 0; e < net.anchor_ranges.size(); ++e) D[net.anchor_edges[2 * e]] += ca * m.anchor_w[e];
  return D;
}
}  // namespace

Model model_from_sigmas(const Network& net, double delta) {
  Model m;
  m.delta = delta;
  m.sensor_w.assign(net.sensor_ranges.size(), 1.0);
  m.anchor_w.assign(net.anchor_ranges.size(), 1.0);
  double smin = INFINITY;
  for (double s : net.sensor_sigmas) smin = std::min(smin, s);
  for (double s : net.anchor_sigmas) smin = std::min(smin, s);
  for (std::size_t e = 0; e < net.sensor_sigmas.size(); ++e) m.sensor_w[e] = std::pow(smin / net.sensor_sigmas[e], 2);
  for (std::size_t e = 0; e < net.anchor_sigmas.size(); ++e) m.anchor_w[e] = std::pow(smin / net.anchor_sigmas[e], 2);
  return m;
}

// Calls f(i, c, rho, w, anchor?) for each measurement: c is x_j or a_k.
template <class F>
void each_measurement(const Network& net, const Model& m, const std::vector<double>& x, F&& f) {
  const int p = net.dim;
  for (std::size_t e = 0; e < net.sensor_ranges.size(); ++e)
    f(net.sensor_edges[2 * e], net.sensor_edges[2 * e + 1], &x[net.sensor_edges[2 * e + 1] * p], net.sensor_ranges[e],
      m.sensor_w[e]);
  for (std::size_t e = 0; e < net.anchor_ranges.size(); ++e)
    f(net.anchor_edges[2 * e], GlobalId(-1), &net.anchors[net.anchor_edges[2 * e + 1] * p], net.anchor_ranges[e],
      m.anchor_w[e]);
}

double model_ml_cost(const Network& net, const Model& m, const std::vector<double>& x) {
  double f = 0;
  each_measurement(net, m, x, [&](GlobalId i, GlobalId, const double* c, double rho, double w) {
    f += w * huber(m.delta, std::abs(dist(&x[i * net.dim], c, net.dim) - rho));
  });
  return f;
}

double model_relaxed_cost(const Network& net, const Model& m, const std::vector<double>& x) {
  double f = 0;
  each_measurement(net, m, x, [&](GlobalId i, GlobalId, const double* c, double rho, double w) {
    f += w * huber(m.delta, std::max(0.0, dist(&x[i * net.dim], c, net.dim) - rho));
  });
  return f;
}

std::vector<double> model_relaxed_gradient(const Network& net, const Model& m, const std::vector<double>& x) {
  const int p = net.dim;
  std::vector<double> g(x.size(), 0.0);
  each_measurement(net, m, x, [&](GlobalId i, GlobalId j, const double* c, double rho, double w) {
    const double d = dist(&x[i * p], c, p);
    if (d <= rho) return;
    const double k = w * omega(m.delta, d - rho) * (1 - rho / d);
    for (int q = 0; q < p; ++q) {
      g[i * p + q] += k * (x[i * p + q] - c[q]);
      if (j >= 0) g[j * p + q] -= k * (x[i * p + q] - c[q]);
    }
  });
  return g;
}

std::vector<double> model_nesterov(const Network& net, const Model& m, const std::vector<double>& x0, int iters) {
  const auto D = diag_majorizer(net, m, 2.0, 1.0);
  std::vector<double> x = x0, xm = x0, w(x0.size());
  for (int k = 1; k <= iters; ++k) {
    for (std::size_t t = 0; t < x.size(); ++t) w[t] = x[t] + (double(k) - 2) / (double(k) + 1) * (x[t] - xm[t]);
    const auto g = model_relaxed_gradient(net, m, w);
    xm = x;
    for (std::size_t t = 0; t < x.size(); ++t) x[t] = w[t] - g[t] / D[t / net.dim];
  }
  return x;
}

namespace {
// MM on the model (000 Algorithm 1 with Huber majorizer weights and per-node
// steps): every measurement as (i, j or -1 - k, range, weight), j > i for
// sensor pairs, with one edge variable y each.
struct ModelMMRef {
  const Network& net;
  const Model& m;
  int p;
  std::vector<double> D;
  std::vector<GlobalId> ei, ej;
  std::vector<double> rho, wt;

  ModelMMRef(const Network& n, const Model& mo) : net(n), m(mo), p(n.dim), D(diag_majorizer(n, mo, 3.0, 2.0)) {
    const std::size_t E = net.sensor_ranges.size(), Ea = net.anchor_ranges.size();
    ei.resize(E + Ea);
    ej.resize(E + Ea);
    rho.resize(E + Ea);
    wt.resize(E + Ea);
    for (std::size_t e = 0; e < E; ++e) {
      ei[e] = std::min(net.sensor_edges[2 * e], net.sensor_edges[2 * e + 1]);
      ej[e] = std::max(net.sensor_edges[2 * e], net.sensor_edges[2 * e + 1]);
      rho[e] = net.sensor_ranges[e];
      wt[e] = m.sensor_w[e];
    }
    for (std::size_t e = 0; e < Ea; ++e) {
      ei[E + e] = net.anchor_edges[2 * e];
      ej[E + e] = -1 - net.anchor_edges[2 * e + 1];  // anchor k as -1 - k
      rho[E + e] = net.anchor_ranges[e];
      wt[E + e] = m.anchor_w[e];
    }
  }
  std::size_t size() const { return rho.size(); }
  void dz(const std::vector<double>& x, std::size_t e, double* out) const {
    const double* c = ej[e] >= 0 ? &x[ej[e] * p] : &net.anchors[(-1 - ej[e]) * p];
    for (int q = 0; q < p; ++q) out[q] = x[ei[e] * p + q] - c[q];
  }
  // y at its best value for x: Phi(x, y) = f(x).
  std::vector<double> best_y(const std::vector<double>& x) const {
    std::vector<double> y(size() * p);
    for (std::size_t e = 0; e < size(); ++e) {
      dz(x, e, &y[e * p]);
      sphere(rho[e], &y[e * p], p);
    }
    return y;
  }
  double Phi(const std::vector<double>& x, const std::vector<double>& y) const {
    double s = 0, z[3];
    for (std::size_t e = 0; e < size(); ++e) {
      dz(x, e, z);
      double r2 = 0;
      for (int q = 0; q < p; ++q) r2 += (z[q] - y[e * p + q]) * (z[q] - y[e * p + q]);
      s += wt[e] * huber(m.delta, std::sqrt(r2));
    }
    return s;
  }
  // One step from (x, y) in place.
  void step(std::vector<double>& x, std::vector<double>& y) const {
    std::vector<double> gx(x.size(), 0.0), yn = y;
    for (std::size_t e = 0; e < size(); ++e) {
      double z[3], r[3], r2 = 0;
      dz(x, e, z);
      for (int q = 0; q < p; ++q) {
        r[q] = z[q] - y[e * p + q];
        r2 += r[q] * r[q];
      }
      const double a = wt[e] * omega(m.delta, std::sqrt(r2));
      for (int q = 0; q < p; ++q) {
        gx[ei[e] * p + q] += a * r[q];
        if (ej[e] >= 0) gx[ej[e] * p + q] -= a * r[q];
        yn[e * p + q] = y[e * p + q] + omega(m.delta, std::sqrt(r2)) / (ej[e] >= 0 ? 3.0 : 2.0) * r[q];
      }
      sphere(rho[e], &yn[e * p], p);
    }
    for (std::size_t q = 0; q < x.size(); ++q) x[q] -= gx[q] / D[q / p];
    y.swap(yn);
  }
};
}  // namespace

std::vector<double> model_mm(const Network& net, const Model& m, const std::vector<double>& x0, int iters,
                             std::vector<double>* phi) {
  return plain_mm(ModelMMRef(net, m), x0, iters, phi);
}

std::vector<double> model_mm_accel(const Network& net, const Model& m, const std::vector<double>& x0, int iters,
                                   std::vector<double>* ml, int* restarts) {
  return accelerated_mm(
      ModelMMRef(net, m), [&](const std::vector<double>& x) { return model_ml_cost(net, m, x); }, x0, iters, ml,
      restarts);
}

namespace {
// Each sensor's measurements as (sensor j, or -1 - k for anchor k; range; weight).
struct Term {
  GlobalId other;
  double rho, w;
};
std::vector<std::vector<Term>> node_terms(const Network& net, const Model& m) {
  std::vector<std::vector<Term>> t(net.num_sensors);
  for (std::size_t e = 0; e < net.sensor_ranges.size(); ++e) {
    const GlobalId i = net.sensor_edges[2 * e], j = net.sensor_edges[2 * e + 1];
    t[i].push_back({j, net.sensor_ranges[e], m.sensor_w[e]});
    t[j].push_back({i, net.sensor_ranges[e], m.sensor_w[e]});
  }
  for (std::size_t e = 0; e < net.anchor_ranges.size(); ++e)
    t[net.anchor_edges[2 * e]].push_back({-1 - net.anchor_edges[2 * e + 1], net.anchor_ranges[e], m.anchor_w[e]});
  return t;
}
const double* other_row(const Network& net, const std::vector<double>& x, GlobalId other) {
  return other >= 0 ? &x[other * net.dim] : &net.anchors[(-1 - other) * net.dim];
}
// Node i's weighted / Huber relaxed cost at v and its gradient g.
double model_local_f(const Network& net, const Model& m, const std::vector<Term>& terms, const std::vector<double>& x,
                     const double* v, double* g) {
  const int p = net.dim;
  double f = 0;
  for (int k = 0; k < p; ++k) g[k] = 0;
  for (const Term& t : terms) {
    const double* c = other_row(net, x, t.other);
    const double d = dist(v, c, p);
    if (d <= t.rho) continue;
    f += t.w * huber(m.delta, d - t.rho);
    const double a = t.w * omega(m.delta, d - t.rho) * (1 - t.rho / d);
    for (int k = 0; k < p; ++k) g[k] += a * (v[k] - c[k]);
  }
  return f;
}
}  // namespace

std::vector<double> model_pm(const Network& net, const Model& m, const std::vector<double>& x0, int sweeps) {
  const int p = net.dim;
  const auto terms = node_terms(net, m);
  const auto col = coloring(net);
  std::vector<GlobalId> order(net.num_sensors);
  for (GlobalId v = 0; v < net.num_sensors; ++v) order[v] = v;
  std::stable_sort(order.begin(), order.end(), [&](GlobalId a, GlobalId b) { return col[a] < col[b]; });
  std::vector<double> x = x0;
  for (int s = 0; s < sweeps; ++s)
    for (GlobalId i : order) {
      if (terms[i].empty()) continue;
      double acc[3] = {0, 0, 0}, wsum = 0;
      const double* xi = &x[i * p];
      for (const Term& t : terms[i]) {
        const double* c = other_row(net, x, t.other);
        const double d = dist(xi, c, p);
        const double f = d > t.rho ? t.rho / d : 1.0;
        const double a = t.w * omega(m.delta, d > t.rho ? d - t.rho : 0.0);
        for (int k = 0; k < p; ++k) acc[k] += a * (c[k] + f * (xi[k] - c[k]));
        wsum += a;
      }
      for (int k = 0; k < p; ++k) x[i * p + k] = acc[k] / wsum;
    }
  return x;
}

std::vector<double> model_async(const Network& net, const Model& m, const std::vector<double>& x0, long activations,
                                std::uint64_t seed, bool exact) {
  const int p = net.dim;
  const auto terms = node_terms(net, m);
  std::vector<double> Li(net.num_sensors, 0.0);
  double ws = 0, wa = 0;
  for (GlobalId i = 0; i < net.num_sensors; ++i) {
    double s = 0, a = 0;
    for (const Term& t : terms[i]) (t.other >= 0 ? s : a) += t.w;
    Li[i] = s + a;
    ws = std::max(ws, s);
    wa = std::max(wa, a);
  }
  const double L = 2 * ws + wa;
  std::vector<double> x = x0;
  for (long k = 0; k < activations; ++k) {
    GlobalId i = static_cast<GlobalId>(uniform01(seed, RngStream::kAsyncClock, k) * double(net.num_sensors));
    i = std::min<GlobalId>(i, net.num_sensors - 1);
    double g[3];
    if (!exact) {
      model_local_f(net, m, terms[i], x, &x[i * p], g);
      for (int c = 0; c < p; ++c) x[i * p + c] -= g[c] / L;
      continue;
    }
    if (Li[i] == 0) continue;
    double z[3], zm[3], w[3];
    for (int c = 0; c < p; ++c) z[c] = zm[c] = x[i * p + c];
    const double f0 = model_local_f(net, m, terms[i], x, &x[i * p], g);
    for (int l = 1; l <= 500; ++l) {
      double step = 0, nz = 0;
      for (int c = 0; c < p; ++c) w[c] = z[c] + (double(l) - 2) / (double(l) + 1) * (z[c] - zm[c]);
      model_local_f(net, m, terms[i], x, w, g);
      for (int c = 0; c < p; ++c) {
        zm[c] = z[c];
        z[c] = w[c] - g[c] / Li[i];
        step += (z[c] - zm[c]) * (z[c] - zm[c]);
        nz += z[c] * z[c];
      }
      if (step <= 1e-24 * (1 + nz)) break;
    }
    if (model_local_f(net, m, terms[i], x, z, g) <= f0)
      for (int c = 0; c < p; ++c) x[i * p + c] = z[c];
  }
  return x;
}

}  // namespace snl::reference

namespace snl::reference {

std::vector<std::vector<std::pair<double, int>>> nearest_anchor_paths(const Network& net, int k) {
  const GlobalId n = net.num_sensors;
  std::vector<std::vector<std::pair<GlobalId, double>>> adj(n);
  for (std::size_t e = 0; e < net.sensor_ranges.size(); ++e) {
    adj[net.sensor_edges[2 * e]].push_back({net.sensor_edges[2 * e + 1], net.sensor_ranges[e]});
    adj[net.sensor_edges[2 * e + 1]].push_back({net.sensor_edges[2 * e], net.sensor_ranges[e]});
  }
  std::vector<std::vector<std::pair<double, int>>> all(n);
  for (GlobalId a = 0; a < net.num_anchors(); ++a) {
    // Dijkstra from anchor a: its measured sensors at their ranges.
    std::vector<double> d(n, INFINITY);
    using Item = std::pair<double, GlobalId>;
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> q;
    for (std::size_t e = 0; e < net.anchor_ranges.size(); ++e)
      if (net.anchor_edges[2 * e + 1] == a && net.anchor_ranges[e] < d[net.anchor_edges[2 * e]]) {
        d[net.anchor_edges[2 * e]] = net.anchor_ranges[e];
        q.push({net.anchor_ranges[e], net.anchor_edges[2 * e]});
      }
    while (!q.empty()) {
      const auto [du, u] = q.top();
      q.pop();
      if (du > d[u]) continue;
      for (const auto& [v, w] : adj[u])
        if (du + w < d[v]) {
          d[v] = du + w;
          q.push({d[v], v});
        }
    }
    for (GlobalId i = 0; i < n; ++i)
      if (std::isfinite(d[i])) all[i].push_back({d[i], int(a)});
  }
  for (auto& l : all) {
    std::sort(l.begin(), l.end());
    if (int(l.size()) > k) l.resize(k);
  }
  return all;
}

double path_correction(const Network& net, const std::vector<std::vector<std::pair<double, int>>>& lists) {
  std::map<std::pair<int, int>, double> best;
  for (std::size_t e = 0; e < net.anchor_ranges.size(); ++e) {
    const GlobalId i = net.anchor_edges[2 * e];
    const int a = int(net.anchor_edges[2 * e + 1]);
    for (const auto& [D, b] : lists[i]) {
      if (b == a) continue;
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      const double path = net.anchor_ranges[e] + D;
      auto it = best.find(key);
      if (it == best.end() || path < it->second) best[key] = path;
    }
  }
  long double straight = 0, path = 0;
  for (const auto& [key, len] : best) {
    straight += dist(&net.anchors[key.first * net.dim], &net.anchors[key.second * net.dim], net.dim);
    path += len;
  }
  return path > 0 ? double(straight / path) : 1.0;
}

std::vector<double> dv_start(const Network& net, int k, const std::vector<double>& fallback) {
  const int p = net.dim;
  const auto lists = nearest_anchor_paths(net, k);
  const double c = path_correction(net, lists);
  std::vector<double> x = fallback;
  for (GlobalId i = 0; i < net.num_sensors; ++i) {
    const auto& l = lists[i];
    if (l.empty()) continue;
    std::vector<double> r, w;
    double rmin = INFINITY, wsum = 0;
    std::vector<double> xi(p, 0.0);
    for (const auto& [D, a] : l) {
      r.push_back(c * D);
      w.push_back(1.0 / std::max(r.back() * r.back(), 1e-300));
      rmin = std::min(rmin, r.back());
      wsum += w.back();
      for (int q = 0; q < p; ++q) xi[q] += w.back() * net.anchors[a * p + q];
    }
    for (int q = 0; q < p; ++q) xi[q] /= wsum;
    for (int it = 0; it < 20; ++it) {
      std::vector<double> H(p * p, 0.0), g(p, 0.0);
      for (std::size_t t = 0; t < l.size(); ++t) {
        const double* a = &net.anchors[l[t].second * p];
        const double nz = dist(xi.data(), a, p);
        if (!(nz > 0)) continue;
        for (int u = 0; u < p; ++u) {
          g[u] += w[t] * (nz - r[t]) * (xi[u] - a[u]) / nz;
          for (int v = 0; v < p; ++v) H[u * p + v] += w[t] * (xi[u] - a[u]) / nz * ((xi[v] - a[v]) / nz);
        }
      }
      double tr = 0;
      for (int u = 0; u < p; ++u) tr += H[u * p + u];
      if (!(tr > 0)) break;
      for (int u = 0; u < p; ++u) H[u * p + u] += 0.1 * tr;
      // Gauss-Jordan on the p x p system (independent of the solver's elimination).
      std::vector<double> s = g;
      for (int col = 0; col < p; ++col) {
        int piv = col;
        for (int row = col + 1; row < p; ++row)
          if (std::fabs(H[row * p + col]) > std::fabs(H[piv * p + col])) piv = row;
        for (int j = 0; j < p; ++j) std::swap(H[col * p + j], H[piv * p + j]);
        std::swap(s[col], s[piv]);
        for (int row = 0; row < p; ++row) {
          if (row == col) continue;
          const double f = H[row * p + col] / H[col * p + col];
          for (int j = 0; j < p; ++j) H[row * p + j] -= f * H[col * p + j];
          s[row] -= f * s[col];
        }
      }
      double ns = 0;
      for (int u = 0; u < p; ++u) {
        s[u] /= H[u * p + u];
        ns += s[u] * s[u];
      }
      ns = std::sqrt(ns);
      const double scale = ns > 0.5 * rmin ? 0.5 * rmin / ns : 1.0;
      for (int u = 0; u < p; ++u) xi[u] -= scale * s[u];
    }
    for (int q = 0; q < p; ++q) x[i * p + q] = xi[q];
  }
  return x;
}

std::vector<double> ml_agd(const Network& net, const std::vector<double>& x0, int iters) {
  const int p = net.dim;
  auto grad = [&](const std::vector<double>& x) {
    std::vector<double> g(x.size(), 0.0);
    for (std::size_t e = 0; e < net.sensor_ranges.size(); ++e) {
      const GlobalId i = net.sensor_edges[2 * e], j = net.sensor_edges[2 * e + 1];
      const double nz = dist(&x[i * p], &x[j * p], p);
      if (!(nz > 0)) continue;
      for (int c = 0; c < p; ++c) {
        const double t = (1 - net.sensor_ranges[e] / nz) * (x[i * p + c] - x[j * p + c]);
        g[i * p + c] += t;
        g[j * p + c] -= t;
      }
    }
    for (std::size_t e = 0; e < net.anchor_ranges.size(); ++e) {
      const GlobalId i = net.anchor_edges[2 * e];
      const double* a = &net.anchors[net.anchor_edges[2 * e + 1] * p];
      const double nz = dist(&x[i * p], a, p);
      if (!(nz > 0)) continue;
      for (int c = 0; c < p; ++c) g[i * p + c] += (1 - net.anchor_ranges[e] / nz) * (x[i * p + c] - a[c]);
    }
    return g;
  };
  std::vector<double> dinv(net.num_sensors, 0.0);  // 1 / (2 delta_i + |A_i|)
  {
    const auto deg = degrees(net);
    std::vector<int> an(net.num_sensors, 0);
    for (std::size_t e = 0; e < net.anchor_ranges.size(); ++e) ++an[net.anchor_edges[2 * e]];
    for (GlobalId i = 0; i < net.num_sensors; ++i) {
      const double d = 2.0 * deg[i] + an[i];
      dinv[i] = d > 0 ? 1.0 / d : 0.0;
    }
  }
  std::vector<double> x = x0, prev = x0;
  std::int64_t k = 0;  // the momentum's iteration count since the last restart
  for (int it = 0; it < iters; ++it) {
    ++k;
    const double beta = double(k - 2) / double(k + 1);  // w(k) = x(k-1) + (k-2)/(k+1) (x(k-1) - x(k-2))
    std::vector<double> w(x.size());
    for (std::size_t t = 0; t < x.size(); ++t) w[t] = x[t] + (k == 1 ? 0.0 : beta) * (x[t] - prev[t]);
    const auto g = grad(w);
    std::vector<double> xn(x.size());
    double gd = 0;  // grad f(w) . (x(k) - x(k-1)), with grad f(w)_i = D_i (w - x(k))_i
    for (GlobalId i = 0; i < net.num_sensors; ++i) {
      double t = 0;
      for (int c = 0; c < p; ++c) {
        const std::size_t q = std::size_t(i) * p + c;
        xn[q] = w[q] - g[q] * dinv[i];
        t += (w[q] - xn[q]) * (xn[q] - x[q]);
      }
      if (dinv[i] > 0) gd += t / dinv[i];
    }
    prev = x;
    x = xn;
    if (gd > 0) k = 1;  // restart: the next w is x(k) itself, then the momentum of a second iteration
  }
  return x;
}

}  // namespace snl::reference
