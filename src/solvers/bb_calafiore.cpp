// Calafiore, Carlone and Wei's distributed Barzilai-Borwein method (CDC 2010)
// as published: gradient descent on the squared-distance discrepancy
//   F(x) = sum_{i~j} (||x_i - x_j||^2 - d_ij^2)^2 + sum_{i,k} (||x_i - a_k||^2 - r_ik^2)^2,
// each node's step alpha_i = s's / s'y with both inner products estimated by T
// rounds of average consensus (Metropolis weights). The registry's `bb` is the
// project's variant of it on the ML cost f (bb.cpp). Every node sums its
// neighbours in global-id order, so iterates are bit-identical for any number
// of ranks.
#include <mpi.h>

#include <algorithm>
#include <cmath>

#include "core/exact_sum.hpp"
#include "snl/problem/metrics.hpp"
#include "solvers/algorithm_util.hpp"
#include "solvers/methods.hpp"

namespace snl {

namespace {

using detail::with_ghost_rows;

class BBCalafiore final : public Algorithm {
 public:
  BBCalafiore(LocalizationProblem& prob, int rounds) : prob_(prob), T_(rounds) {}
  std::string name() const override { return algorithm_info(AlgorithmId::kBBCalafiore).name; }
  double messages_per_iteration() const override { return 1.0 + T_; }
  double reals_per_iteration() const override { return prob_.dim() + 2.0 * T_; }
  double lipschitz() const override { return 1.0 / alpha0_; }

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
  // The objective the method minimizes: F, summed exactly (the same for any partition).
  double objective() override {
    const int p = prob_.dim();
    prob_.graph().halo().exchange(x_.data(), p);
    detail::ExactSum s;
    each_term(0, prob_.num_owned(), [&](LocalId, const double*, double r, double w) { s.add(w * r * r); });
    detail::allreduce_exact(&s, 1, prob_.comm());
    return s.value();
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
  // f(v, z, res, w) for every term of owned nodes [b, e): z = x_v - x_u (or - a_k),
  // res = ||z||^2 - d^2; w = 1/2 for sensor pairs (each is seen from both ends), 1 for anchors.
  template <class F>
  void each_term(LocalId b, LocalId e, F&& f) const {
    const int p = prob_.dim();
    const auto& gr = prob_.graph();
    const double* anc = prob_.anchors().data();
    double z[3];
    auto visit = [&](LocalId v, const double* other, double d, double w) {
      double n2 = 0;
      for (int c = 0; c < p; ++c) {
        z[c] = x_[std::size_t(v) * p + c] - other[c];
        n2 += z[c] * z[c];
      }
      f(v, z, n2 - d * d, w);
    };
    for (LocalId v = b; v < e; ++v) {
      for (auto t = gr.offsets()[v]; t < gr.offsets()[v + 1]; ++t)
        visit(v, &x_[std::size_t(gr.adjacency()[t]) * p], gr.edge_value(t), 0.5);
      for (auto t = prob_.anchor_offsets()[v]; t < prob_.anchor_offsets()[v + 1]; ++t)
        visit(v, anc + std::size_t(prob_.anchor_ids()[t]) * p, prob_.anchor_ranges()[t], 1.0);
    }
  }
  // grad_i F = sum_j 4 res_ij (x_i - x_j) + sum_k 4 res_ik (x_i - a_k), owned nodes [b, e).
  void gradient(LocalId b, LocalId e) {
    const int p = prob_.dim();
    std::fill(g_.begin() + std::size_t(b) * p, g_.begin() + std::size_t(e) * p, 0.0);
    each_term(b, e, [&](LocalId v, const double* z, double res, double) {
      for (int c = 0; c < p; ++c) g_[std::size_t(v) * p + c] += 4.0 * res * z[c];
    });
  }
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
  // The first step (before any s, y exist): 1 / (8 D^2 L), with L the Lipschitz
  // constant of the ML relaxation's gradient and D the largest range: the
  // curvature of F near a fit, 8 ||z||^2 per term against 1 for f (the
  // project's choice; the published first step is not in our sources).
  double first_step() const {
    double dmax = 0;
    const auto& gr = prob_.graph();
    for (std::size_t t = 0; t < gr.adjacency().size(); ++t) dmax = std::max(dmax, gr.edge_value(std::int64_t(t)));
    for (double r : prob_.anchor_ranges()) dmax = std::max(dmax, r);
    MPI_Allreduce(MPI_IN_PLACE, &dmax, 1, MPI_DOUBLE, MPI_MAX, prob_.comm());
    return 1.0 / (8.0 * std::max(dmax * dmax, 1e-12) * relaxation_lipschitz(prob_));
  }

  LocalizationProblem& prob_;
  int T_;
  double alpha0_ = 0;
  std::vector<double> x_, x_old_, g_, g_old_, c_, cn_, wt_, self_;
  std::int64_t k_ = 0;
  double diff_sq_ = 0, x_sq_ = 0, gsq_ = 0;
};

}  // namespace

namespace detail {

std::unique_ptr<Algorithm> make_bb_calafiore(LocalizationProblem& prob, const SolverOptions& opt) {
  return std::make_unique<BBCalafiore>(prob, opt.bb_rounds);
}

}  // namespace detail

}  // namespace snl
