// The Barzilai-Borwein baseline (Calafiore, Carlone, Wei 2010, as compared in
// 000). Every node sums its neighbours in global-id order, so iterates are
// bit-identical for any number of ranks. Each iteration: halo begin -> interior
// nodes -> halo end -> boundary, then T consensus rounds.
#include <algorithm>
#include <cmath>

#include "kernels/kernels.hpp"
#include "snl/problem/metrics.hpp"
#include "solvers/algorithm_util.hpp"
#include "solvers/methods.hpp"

namespace snl {

namespace {

using detail::with_ghost_rows;

// Barzilai-Borwein gradient descent on the ML cost f (Calafiore et al. 2010):
// alpha = s's / s'y with both inner products estimated by T rounds of average
// consensus with Metropolis weights, so each node uses its own estimate.
class BB final : public Algorithm {
 public:
  BB(LocalizationProblem& prob, int rounds) : prob_(prob), T_(rounds), alpha0_(1.0 / relaxation_lipschitz(prob)) {}
  std::string name() const override { return algorithm_info(AlgorithmId::kBB).name; }
  double lipschitz() const override { return relaxation_lipschitz(prob_); }
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
    // Metropolis weights W_ij = 1 / (1 + max(deg_i, deg_j)) from the neighbours' degrees.
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
    k_ = 0;
  }

  void iterate() override {
    ++k_;
    const int p = prob_.dim();
    auto& gr = prob_.graph();
    HaloPlan& halo = gr.halo();
    const LocalId n_owned = gr.num_owned(), n_int = gr.num_interior();
    halo.begin(x_.data(), p);
    ml_gradient(prob_, x_.data(), g_.data(), 0, n_int);
    halo.end(x_.data(), p);
    ml_gradient(prob_, x_.data(), g_.data(), n_int, n_owned);
    // Local inner products s_i's_i and s_i'y_i, then T consensus rounds.
    for (LocalId v = 0; v < n_owned; ++v) {
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
    for (int r = 0; r < T_; ++r) {
      halo.exchange(c_.data(), 2);
      for (LocalId v = 0; v < n_owned; ++v) {
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
    double dd = 0, xs = 0, gs = 0;
    for (LocalId v = 0; v < n_owned; ++v) {
      double alpha = alpha0_;
      if (k_ > 1) {
        const double a = c_[2 * std::size_t(v)] / c_[2 * std::size_t(v) + 1];
        if (std::isfinite(a) && a > 0) alpha = a;  // safeguard: fall back to 1/L
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

  const std::vector<double>& positions() const override { return x_; }
  std::int64_t memory_bytes() const override {
    return static_cast<std::int64_t>(sizeof(double) * (x_.capacity() + x_old_.capacity() + g_.capacity() +
                                                       g_old_.capacity() + c_.capacity() + cn_.capacity() +
                                                       wt_.capacity() + self_.capacity()));
  }
  double objective() override {
    prob_.graph().halo().exchange(x_.data(), prob_.dim());
    return evaluate_costs(prob_, x_.data()).ml;
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

 private:
  LocalizationProblem& prob_;
  int T_;
  double alpha0_;
  std::vector<double> x_, x_old_, g_, g_old_, c_, cn_, wt_, self_;
  std::int64_t k_ = 0;
  double diff_sq_ = 0, x_sq_ = 0, gsq_ = 0;
};

}  // namespace

namespace detail {

std::unique_ptr<Algorithm> make_bb(LocalizationProblem& prob, const SolverOptions& opt) {
  return std::make_unique<BB>(prob, opt.bb_rounds);
}

}  // namespace detail

}  // namespace snl
