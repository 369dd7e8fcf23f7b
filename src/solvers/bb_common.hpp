#pragma once
// What the two distributed Barzilai-Borwein methods share (bb.cpp on the ML
// cost, bb_calafiore.cpp on the squared-distance discrepancy, as in
// Calafiore, Carlone, Wei 2010): the step alpha_i = s's / s'y of each node,
// with both inner products estimated by T rounds of average consensus with
// Metropolis weights W_ij = 1 / (1 + max(deg_i, deg_j)), W_ii = 1 - sum_j W_ij.
// A method supplies its gradient, its objective and its first step.
// Every node sums its neighbours in global-id order: bit-identical iterates on
// any number of ranks.
#include <algorithm>
#include <cmath>
#include <vector>

#include "solvers/algorithm_util.hpp"
#include "solvers/methods.hpp"

namespace snl::detail {

class BarzilaiBorweinBase : public Algorithm {
 public:
  BarzilaiBorweinBase(LocalizationProblem& prob, int rounds) : prob_(prob), T_(rounds) {}
  double messages_per_iteration() const override { return 1.0 + T_; }
  double reals_per_iteration() const override { return prob_.dim() + 2.0 * T_; }

  void start(const std::vector<double>& x0) override {
    const int p = prob_.dim();
    const auto& gr = prob_.graph();
    x_ = with_ghost_rows(prob_, x0);
    const std::size_t mo = std::size_t(prob_.num_owned()) * p;
    x_old_.assign(mo, 0.0);
    g_.assign(mo, 0.0);
    g_old_.assign(mo, 0.0);
    c_.assign(std::size_t(prob_.num_local()) * 2, 0.0);
    cn_.assign(std::size_t(prob_.num_owned()) * 2, 0.0);
    // Metropolis weights from the neighbours' degrees.
    std::vector<double> deg(std::size_t(prob_.num_local()), 0.0);
    for (LocalId v = 0; v < gr.num_owned(); ++v) deg[v] = gr.degree(v);
    prob_.graph().halo().exchange(deg.data(), 1);
    wt_.resize(gr.adjacency().size());
    self_.assign(gr.num_owned(), 1.0);
    for (LocalId v = 0; v < gr.num_owned(); ++v)
      for (auto e = gr.offsets()[v]; e < gr.offsets()[v + 1]; ++e) {
        wt_[e] = 1.0 / (1.0 + std::max(deg[v], deg[gr.adjacency()[e]]));
        self_[v] -= wt_[e];
      }
    alpha0_ = first_step();
    k_ = 0;
  }

  // Halo begin -> interior gradient -> halo end -> boundary gradient, then the
  // T consensus rounds on (s's, s'y) and each node's step.
  void iterate() override {
    ++k_;
    auto& gr = prob_.graph();
    HaloPlan& halo = gr.halo();
    const LocalId n_owned = gr.num_owned(), n_int = gr.num_interior();
    halo.begin(x_.data(), prob_.dim());
    gradient(0, n_int);
    halo.end(x_.data(), prob_.dim());
    gradient(n_int, n_owned);
    local_products();
    for (int r = 0; r < T_; ++r) consensus_round();
    step();
  }

  const std::vector<double>& positions() const override { return x_; }
  std::int64_t memory_bytes() const override {
    return static_cast<std::int64_t>(sizeof(double) * (x_.capacity() + x_old_.capacity() + g_.capacity() +
                                                       g_old_.capacity() + c_.capacity() + cn_.capacity() +
                                                       wt_.capacity() + self_.capacity()));
  }
  void change_norms(double* d, double* s) const override {
    *d = diff_sq_;
    *s = x_sq_;
  }
  double grad_norm_sq() const override { return gsq_; }
  const double* previous_positions() const override { return x_old_.data(); }
  const double* gradient_rows() override { return g_.data(); }
  void save(StateWriter& w) const override {
    w.scalar("k", double(k_));
    w.node_rows("x", x_.data(), prob_.dim());
    w.node_rows("x_old", x_old_.data(), prob_.dim());
    w.node_rows("g_old", g_old_.data(), prob_.dim());
  }
  void load(const StateReader& r) override {
    k_ = static_cast<std::int64_t>(r.scalar("k"));
    r.node_rows("x", x_.data(), prob_.dim());
    r.node_rows("x_old", x_old_.data(), prob_.dim());
    r.node_rows("g_old", g_old_.data(), prob_.dim());
  }

 protected:
  /// The method's gradient into g_ for owned nodes [b, e) (x_'s ghost rows are current).
  virtual void gradient(LocalId b, LocalId e) = 0;
  /// The step before any s, y exist (and the fallback of the safeguard); called by start().
  virtual double first_step() const = 0;

  LocalizationProblem& prob_;
  std::vector<double> x_, g_;  ///< positions (owned + ghost rows), gradient (owned rows)
  double alpha0_ = 0;

 private:
  // Each node's s_i's_i and s_i'y_i, the consensus' starting values.
  void local_products() {
    const int p = prob_.dim();
    for (LocalId v = 0; v < prob_.num_owned(); ++v) {
      double ss = 0, sy = 0;
      for (int c = 0; c < p; ++c) {
        const std::size_t t = std::size_t(v) * p + c;
        const double s = x_[t] - x_old_[t], y = g_[t] - g_old_[t];
        ss += s * s;
        sy += s * y;
      }
      c_[2 * std::size_t(v)] = ss;
      c_[2 * std::size_t(v) + 1] = sy;
    }
  }
  void consensus_round() {
    auto& gr = prob_.graph();
    gr.halo().exchange(c_.data(), 2);
    for (LocalId v = 0; v < gr.num_owned(); ++v) {
      double a = self_[v] * c_[2 * std::size_t(v)], b = self_[v] * c_[2 * std::size_t(v) + 1];
      for (auto e = gr.offsets()[v]; e < gr.offsets()[v + 1]; ++e) {
        const LocalId u = gr.adjacency()[e];
        a += wt_[e] * c_[2 * std::size_t(u)];
        b += wt_[e] * c_[2 * std::size_t(u) + 1];
      }
      cn_[2 * std::size_t(v)] = a;
      cn_[2 * std::size_t(v) + 1] = b;
    }
    std::copy(cn_.begin(), cn_.end(), c_.begin());
  }
  void step() {
    const int p = prob_.dim();
    double dd = 0, xs = 0, gs = 0;
    for (LocalId v = 0; v < prob_.num_owned(); ++v) {
      double alpha = alpha0_;
      if (k_ > 1) {
        const double a = c_[2 * std::size_t(v)] / c_[2 * std::size_t(v) + 1];
        if (std::isfinite(a) && a > 0) alpha = a;  // safeguard: the first step again
      }
      for (int c = 0; c < p; ++c) {
        const std::size_t t = std::size_t(v) * p + c;
        x_old_[t] = x_[t];
        g_old_[t] = g_[t];
        x_[t] -= alpha * g_[t];
        dd += (x_[t] - x_old_[t]) * (x_[t] - x_old_[t]);
        xs += x_[t] * x_[t];
        gs += g_[t] * g_[t];
      }
    }
    diff_sq_ = dd;
    x_sq_ = xs;
    gsq_ = gs;
  }

  int T_;
  std::vector<double> x_old_, g_old_, c_, cn_, wt_, self_;
  std::int64_t k_ = 0;
  double diff_sq_ = 0, x_sq_ = 0, gsq_ = 0;
};

}  // namespace snl::detail
