// The relaxation and MM under a measurement model other than unweighted l2
// (weights.hpp): weights 1/sigma^2 and/or the Huber loss. One node at a time
// in CSR order (the scalar path: the SIMD kernels of src/kernels/ serve the
// unweighted l2 model only, which stays bit for bit what it was). Every node
// sums its neighbours in global-id order, then its anchors in id order, so
// iterates are bit-identical for any number of ranks. Derivations:
// docs/quality.md, "Weighted ML".
#include <algorithm>
#include <cmath>

#include "core/dim_dispatch.hpp"
#include "core/exact_sum.hpp"
#include "kernels/kernels.hpp"
#include "snl/problem/metrics.hpp"
#include "solvers/algorithm_util.hpp"
#include "solvers/methods.hpp"
#include "solvers/model_mm.hpp"

namespace snl {

namespace {

using detail::project_sphere;
using detail::with_ghost_rows;

// Weights spread over orders of magnitude (1/d^2 for multiplicative noise), so
// one global step 1/L moves the lightly weighted nodes far too slowly. Both
// methods therefore take per-node steps from a diagonal majorizer D >= the
// Hessian (Gershgorin: D - H is diagonally dominant), a local, parameter-free
// quantity; with D = L I they would be the paper's methods.

// Per owned node: (sum_j w_ij, sum_k w_ik).
std::vector<std::pair<double, double>> node_weight_sums(const LocalizationProblem& prob) {
  const MeasurementModel& mo = prob.model();
  const auto& off = prob.graph().offsets();
  const auto& aoff = prob.anchor_offsets();
  std::vector<std::pair<double, double>> s(prob.num_owned(), {0.0, 0.0});
  for (LocalId v = 0; v < prob.num_owned(); ++v) {
    for (auto e = off[v]; e < off[v + 1]; ++e) s[v].first += mo.edge_weight(e);
    for (auto e = aoff[v]; e < aoff[v + 1]; ++e) s[v].second += mo.anchor_weight(e);
  }
  return s;
}

// Disk relaxation by Nesterov's method (003, Alg. 1) on
//   f_hat(x) = sum_e w_e rho(dist(z_e, B(d_e))),  z_e = x_i - x_j (or x_i - a_k),
// rho = r^2/2 or Huber: convex, with gradient sum_e w_e rho'(t)/t (z - P_B z)
// (relaxed_gradient). Each term is 1-smooth in z_e (Huber too), so the Hessian
// is at most the weighted Laplacian plus the anchor diagonal, which is at most
// D = diag(2 sum_j w_ij + sum_k w_ik) (003 eq. 16 per node): Nesterov's method
// in the D-metric, x(k) = w - D^-1 grad f_hat(w), keeps the O(1/k^2) rate.
class ModelRelaxation final : public Algorithm {
 public:
  explicit ModelRelaxation(LocalizationProblem& prob) : prob_(prob), L_(relaxation_lipschitz(prob)) {}
  std::string name() const override { return algorithm_info(AlgorithmId::kRelaxation).name; }
  double lipschitz() const override { return L_; }
  double reals_per_iteration() const override { return prob_.dim(); }

  void start(const std::vector<double>& x0) override {
    x_ = with_ghost_rows(prob_, x0);
    prev_ = x_;
    w_.assign(x_.size(), 0.0);
    g_.assign(std::size_t(prob_.num_owned()) * prob_.dim(), 0.0);
    dinv_.assign(prob_.num_owned(), 0.0);
    const auto sums = node_weight_sums(prob_);
    for (LocalId v = 0; v < prob_.num_owned(); ++v) {
      const double D = 2.0 * sums[v].first + sums[v].second;
      dinv_[v] = D > 0 ? 1.0 / D : 0.0;  // a node without measurements stays
    }
    k_ = 0;
  }

  // w = x(k-1) + (k-2)/(k+1) (x(k-1) - x(k-2)); x(k) = w - D^-1 grad f_hat(w).
  void iterate() override {
    const std::size_t m = std::size_t(prob_.num_owned()) * prob_.dim();
    const double beta = static_cast<double>(k_ - 1) / static_cast<double>(k_ + 2);
    for (std::size_t t = 0; t < m; ++t) w_[t] = x_[t] + beta * (x_[t] - prev_[t]);
    prob_.graph().halo().exchange(w_.data(), prob_.dim());
    relaxed_gradient(prob_, w_.data(), g_.data(), 0, prob_.num_owned());
    double d = 0, s = 0, gs = 0;
    for (std::size_t t = 0; t < m; ++t) {
      const double now = w_[t] - g_[t] * dinv_[t / prob_.dim()];
      prev_[t] = x_[t];
      x_[t] = now;
      d += (now - prev_[t]) * (now - prev_[t]);
      s += now * now;
      gs += g_[t] * g_[t];
    }
    diff_sq_ = d;
    x_sq_ = s;
    gsq_ = gs;
    ++k_;
  }

  const std::vector<double>& positions() const override { return x_; }
  double objective() override {
    prob_.graph().halo().exchange(x_.data(), prob_.dim());
    return evaluate_costs(prob_, x_.data()).relaxed;
  }
  void change_norms(double* d, double* s) const override {
    *d = diff_sq_;
    *s = x_sq_;
  }
  double grad_norm_sq() const override { return gsq_; }
  const double* previous_positions() const override { return prev_.data(); }
  const double* gradient_rows() override { return k_ > 0 ? g_.data() : nullptr; }
  std::int64_t memory_bytes() const override {
    return static_cast<std::int64_t>(sizeof(double) * (x_.capacity() + prev_.capacity() + w_.capacity() + g_.capacity()));
  }
  void save(StateWriter& w) const override {
    w.scalar("k", double(k_));
    w.node_rows("x", x_.data(), prob_.dim());
    w.node_rows("x_prev", prev_.data(), prob_.dim());
  }
  void load(const StateReader& r) override {
    k_ = static_cast<std::int64_t>(r.scalar("k"));
    r.node_rows("x", x_.data(), prob_.dim());
    r.node_rows("x_prev", prev_.data(), prob_.dim());
  }

 private:
  LocalizationProblem& prob_;
  double L_;
  std::vector<double> x_, prev_, w_, g_, dinv_;  // dinv_: 1/D per owned node
  std::int64_t k_ = 0;
  double diff_sq_ = 0, x_sq_ = 0, gsq_ = 0;
};

// MM (000, Alg. 1) on Phi(x, y, w) = sum_e w_e rho(|x_i - x_j - y_e|) + anchors
// alike, |y_e| = d_e: min over y of Phi is the (weighted, Huber) ML cost. At
// the current iterate, rho(|u|) <= rho(|u0|) + omega/2 (|u|^2 - |u0|^2) with
// omega = rho'(|u0|)/|u0| = min(1, delta/|u0|) (1 for l2), so one projected
// gradient step on the quadratic Q = 1/2 sum w_e omega_e |x_i - x_j - y_e|^2
// with a diagonal majorizer D of its Hessian decreases Q and hence Phi:
// monotone and parameter-free. The Hessian of an edge's term in (x_i, x_j,
// y_e) is w omega [1 -1 -1; -1 1 1; -1 1 1] (an anchor's in (x_i, w_ik):
// w omega [1 -1; -1 1]); Gershgorin with omega <= 1 gives D_x_i = 3 sum_j w_ij
// + 2 sum_k w_ik, D_y_e = 3 w_e, D_w_ik = 2 w_ik. Each y block is a multiple
// of I, so its step is still the Euclidean projection (000, eqs. 11-13):
//   x_i -= D_x_i^-1 sum_e s_e w_e omega_e (dz_e - y_e),
//   y_e <- P_sphere(y_e + (omega_e / 3) (dz_e - y_e))   (anchors: omega / 2).
class ModelMM final : public Algorithm {
 public:
  explicit ModelMM(LocalizationProblem& prob) : prob_(prob), k_(prob) {}
  std::string name() const override { return algorithm_info(AlgorithmId::kMM).name; }
  double lipschitz() const override { return k_.lipschitz(); }
  double reals_per_iteration() const override { return prob_.dim(); }

  void start(const std::vector<double>& x0) override {
    x_ = with_ghost_rows(prob_, x0);
    xn_ = x_;
    prob_.graph().halo().exchange(x_.data(), prob_.dim());
    y_.assign(prob_.graph().adjacency().size() * prob_.dim(), 0.0);
    aw_.assign(prob_.anchor_ranges().size() * prob_.dim(), 0.0);
    k_.init(x_.data(), y_.data(), aw_.data());
  }

  void iterate() override {
    prob_.graph().halo().exchange(x_.data(), prob_.dim());
    k_.step(x_.data(), xn_.data(), y_.data(), aw_.data(), &diff_sq_, &x_sq_);
    std::swap(x_, xn_);  // xn_ keeps x(t) for previous_positions()
  }

  const std::vector<double>& positions() const override { return x_; }
  // Phi(x, y, w), each edge once; exact sums.
  double objective() override {
    prob_.graph().halo().exchange(x_.data(), prob_.dim());
    detail::ExactSum F;
    k_.terms(x_.data(), y_.data(), aw_.data(), 0, prob_.num_owned(), &F, nullptr);
    detail::allreduce_exact(&F, 1, prob_.comm());
    return F.value();
  }
  const double* previous_positions() const override { return xn_.data(); }
  void change_norms(double* d, double* s) const override {
    *d = diff_sq_;
    *s = x_sq_;
  }
  std::int64_t memory_bytes() const override {
    return static_cast<std::int64_t>(sizeof(double) * (x_.capacity() + xn_.capacity() + y_.capacity() + aw_.capacity())) +
           k_.bytes();
  }
  void save(StateWriter& w) const override {
    const int p = prob_.dim();
    w.node_rows("x", x_.data(), p);
    w.edge_rows("y", p, [&](LocalId, std::int64_t e, int c) { return y_[std::size_t(e) * p + c]; });
    w.anchor_rows("w", aw_.data(), p);
  }
  void load(const StateReader& r) override {
    const int p = prob_.dim();
    r.node_rows("x", x_.data(), p);
    r.edge_rows("y", p, [&](LocalId, std::int64_t e, int c, double y) { y_[std::size_t(e) * p + c] = y; });
    r.anchor_rows("w", aw_.data(), p);
  }

 private:
  LocalizationProblem& prob_;
  detail::ModelMMKernel k_;
  std::vector<double> x_, xn_, y_, aw_;  // y_: P per CSR slot; aw_: P per anchor measurement
  double diff_sq_ = 0, x_sq_ = 0;
};

}  // namespace

namespace detail {

ModelMMKernel::ModelMMKernel(const LocalizationProblem& prob)
    : prob_(prob), L_(2.0 * prob.model().max_weight_sum + prob.model().max_anchor_weight_sum + 2.0) {
  dinv_.assign(prob.num_owned(), 0.0);
  const auto sums = node_weight_sums(prob);
  for (LocalId v = 0; v < prob.num_owned(); ++v) {
    const double D = 3.0 * sums[v].first + 2.0 * sums[v].second;
    dinv_[v] = D > 0 ? 1.0 / D : 0.0;
  }
}

void ModelMMKernel::init(const double* x, double* y, double* aw) const {
  with_dim(prob_.dim(), [&](auto P) { init_p<decltype(P)::value>(x, y, aw); });
}
void ModelMMKernel::step(const double* x, double* xn, double* y, double* aw, double* d, double* s) const {
  with_dim(prob_.dim(), [&](auto P) { step_p<decltype(P)::value>(x, xn, y, aw, d, s); });
}
void ModelMMKernel::terms(const double* x, const double* y, const double* aw, LocalId v0, LocalId v1, ExactSum* F,
                          ExactSum* f) const {
  with_dim(prob_.dim(), [&](auto P) { terms_p<decltype(P)::value>(x, y, aw, v0, v1, F, f); });
}

namespace {

// dz = x_i - x_j of the edge {v, u} in its orientation i < j (global ids); returns +1 if v = i.
template <int P>
double oriented_diff(const LocalizationProblem& prob, const double* x, LocalId v, LocalId u, double* dz) {
  const bool fwd = prob.graph().global_id(v) < prob.graph().global_id(u);
  const double* xi = &x[std::size_t(fwd ? v : u) * P];
  const double* xj = &x[std::size_t(fwd ? u : v) * P];
  for (int c = 0; c < P; ++c) dz[c] = xi[c] - xj[c];
  return fwd ? 1.0 : -1.0;
}

// One edge variable: acc += sgn omega w (dz - y), y <- P_sphere(y + (omega / Dy)(dz - y)).
template <int P>
void edge_update(double delta, const double* dz, double sgn, double weight, double Dy, double rho, double* y,
                 double* acc) {
  double r[P], s = 0;
  for (int c = 0; c < P; ++c) {
    r[c] = dz[c] - y[c];
    s += r[c] * r[c];
  }
  const double om = huber_factor(delta, std::sqrt(s));
  const double a = weight * om;
  for (int c = 0; c < P; ++c) acc[c] += sgn * a * r[c];
  const double step = om / Dy;
  for (int c = 0; c < P; ++c) y[c] += step * r[c];
  project_sphere<P>(rho, y);
}

}  // namespace

template <int P>
void ModelMMKernel::init_p(const double* x, double* y, double* aw) const {
  best_edge_variables<P>(prob_, x, [&](LocalId, std::int64_t e, int c) { return &y[std::size_t(e) * P + c]; }, aw);
}

template <int P>
void ModelMMKernel::step_p(const double* x, double* xn, double* y, double* aw, double* dsq, double* ssq) const {
  const auto& gr = prob_.graph();
  const auto& off = gr.offsets();
  const auto& aoff = prob_.anchor_offsets();
  const MeasurementModel& mo = prob_.model();
  double d = 0, s = 0;
  for (LocalId v = 0; v < gr.num_owned(); ++v) {
    double acc[P] = {}, dz[P];
    for (auto e = off[v]; e < off[v + 1]; ++e) {
      const double sgn = oriented_diff<P>(prob_, x, v, gr.adjacency()[e], dz);
      edge_update<P>(mo.huber_delta, dz, sgn, mo.edge_weight(e), 3.0, gr.edge_value(e), &y[std::size_t(e) * P], acc);
    }
    for (auto e = aoff[v]; e < aoff[v + 1]; ++e) {
      const double* a = &prob_.anchors()[std::size_t(prob_.anchor_ids()[e]) * P];
      for (int c = 0; c < P; ++c) dz[c] = x[std::size_t(v) * P + c] - a[c];
      edge_update<P>(mo.huber_delta, dz, 1.0, mo.anchor_weight(e), 2.0, prob_.anchor_ranges()[e],
                     &aw[std::size_t(e) * P], acc);
    }
    for (int c = 0; c < P; ++c) {
      const std::size_t t = std::size_t(v) * P + c;
      xn[t] = x[t] - acc[c] * dinv_[v];
      d += (xn[t] - x[t]) * (xn[t] - x[t]);
      s += xn[t] * xn[t];
    }
  }
  if (dsq) *dsq = d;
  if (ssq) *ssq = s;
}

template <int P>
void ModelMMKernel::terms_p(const double* x, const double* y, const double* aw, LocalId v0, LocalId v1, ExactSum* F,
                            ExactSum* f) const {
  const auto& gr = prob_.graph();
  const auto& off = gr.offsets();
  const auto& aoff = prob_.anchor_offsets();
  const MeasurementModel& mo = prob_.model();
  auto term = [&](const double* dz, const double* ye, double weight, double rho) {
    double s = 0, z2 = 0;
    for (int c = 0; c < P; ++c) {
      s += (dz[c] - ye[c]) * (dz[c] - ye[c]);
      z2 += dz[c] * dz[c];
    }
    F->add(weight * loss_value(mo.huber_delta, std::sqrt(s)));
    if (f) f->add(weight * loss_value(mo.huber_delta, std::abs(std::sqrt(z2) - rho)));
  };
  for (LocalId v = v0; v < v1; ++v) {
    double dz[P];
    for (auto e = off[v]; e < off[v + 1]; ++e) {
      if (oriented_diff<P>(prob_, x, v, gr.adjacency()[e], dz) < 0) continue;
      term(dz, &y[std::size_t(e) * P], mo.edge_weight(e), gr.edge_value(e));
    }
    for (auto e = aoff[v]; e < aoff[v + 1]; ++e) {
      const double* a = &prob_.anchors()[std::size_t(prob_.anchor_ids()[e]) * P];
      for (int c = 0; c < P; ++c) dz[c] = x[std::size_t(v) * P + c] - a[c];
      term(dz, &aw[std::size_t(e) * P], mo.anchor_weight(e), prob_.anchor_ranges()[e]);
    }
  }
}

std::unique_ptr<Algorithm> make_model_relaxation(LocalizationProblem& prob) {
  return std::make_unique<ModelRelaxation>(prob);
}
std::unique_ptr<Algorithm> make_model_mm(LocalizationProblem& prob) { return std::make_unique<ModelMM>(prob); }

}  // namespace detail

}  // namespace snl
