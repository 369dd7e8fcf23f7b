// The asynchronous method of 003 (Algorithm 2), run in parallel with exactly
// its sequential semantics (so results are bit-identical for any rank count):
// node activations xi_k drawn uniformly (eq. 21) from a counter-based
// generator, so every rank knows the whole sequence. A prefix of activations in
// which no node is activated twice and no two activated nodes are neighbours
// commutes; the ranks agree on the longest such prefix (one MPI_Allreduce),
// apply it in parallel, exchange the halo, and go on. Inexact version (async):
// one step x_i <- x_i - grad_i f_hat / L (eq. 20); exact version (async-exact):
// minimise f_i(v) = sum_j 1/2 d_B(d_ij)(v - x_j)^2 + sum_k 1/2 d_B(r_ik)(v - a_k)^2
// by Nesterov's method (Algorithm 3) with the spec's weight 1/2 (003's eq. 19
// has 1/4, a slip) and L_i = delta_i + |A_i|.
// One iteration = n activations (one message per activation: 1 per sensor).
#include <algorithm>
#include <cmath>

#include "snl/core/random.hpp"
#include "snl/problem/metrics.hpp"
#include "solvers/algorithm_util.hpp"
#include "solvers/methods.hpp"

namespace snl {

namespace {

using detail::diff_norms;
const auto with_ghosts = detail::with_ghost_rows;

// f_i and its gradient at v for owned node i (the local problem of node i).
double local_cost_grad(const LocalizationProblem& prob, const double* x, LocalId i, const double* v, double* g) {
  const int p = prob.dim();
  const auto& gr = prob.graph();
  double f = 0;
  for (int k = 0; k < p; ++k) g[k] = 0;
  // Weighted / Huber terms w rho(t), t = |z| - rho outside the disk (weights.hpp);
  // the unweighted l2 model takes the plain expressions.
  const MeasurementModel& mo = prob.model();
  auto term = [&](const double* c, double rho, double w) {
    double s = 0;
    for (int k = 0; k < p; ++k) s += (v[k] - c[k]) * (v[k] - c[k]);
    const double nz = std::sqrt(s);
    if (nz > rho) {
      if (!mo.active()) {
        f += 0.5 * (nz - rho) * (nz - rho);
        const double a = 1.0 - rho / nz;
        for (int k = 0; k < p; ++k) g[k] += a * (v[k] - c[k]);
        return;
      }
      f += w * loss_value(mo.huber_delta, nz - rho);
      const double a = w * huber_factor(mo.huber_delta, nz - rho) * (1.0 - rho / nz);
      for (int k = 0; k < p; ++k) g[k] += a * (v[k] - c[k]);
    }
  };
  for (auto e = gr.offsets()[i]; e < gr.offsets()[i + 1]; ++e)
    term(x + std::size_t(gr.adjacency()[e]) * p, gr.edge_value(e), mo.edge_weight(e));
  for (auto e = prob.anchor_offsets()[i]; e < prob.anchor_offsets()[i + 1]; ++e)
    term(prob.anchors().data() + std::size_t(prob.anchor_ids()[e]) * p, prob.anchor_ranges()[e], mo.anchor_weight(e));
  return f;
}

// ---------------------------------------------------------------------------
class Async final : public Algorithm {
 public:
  Async(LocalizationProblem& prob, const SolverOptions& opt, bool exact)
      : prob_(prob), exact_(exact), seed_(opt.seed), L_(relaxation_lipschitz(prob)) {}
  std::string name() const override {
    return algorithm_info(exact_ ? AlgorithmId::kAsyncExact : AlgorithmId::kAsync).name;
  }
  double lipschitz() const override { return L_; }
  double reals_per_iteration() const override { return prob_.dim(); }

  void start(const std::vector<double>& x0) override {
    x_ = with_ghosts(prob_, x0);
    auto& g = prob_.graph();
    g.halo().exchange(x_.data(), prob_.dim());
    lookup_.resize(g.num_local());
    for (LocalId v = 0; v < g.num_local(); ++v) lookup_[v] = {g.global_id(v), v};
    std::sort(lookup_.begin(), lookup_.end());
    stamp_.assign(g.num_local(), -1);
    prev_.assign(std::size_t(g.num_owned()) * prob_.dim(), 0.0);
    k_ = 0;
    window_ = 64;
  }

  void iterate() override {
    const int p = prob_.dim();
    auto& g = prob_.graph();
    const GlobalId n = prob_.num_sensors();
    std::copy(x_.begin(), x_.begin() + prev_.size(), prev_.begin());
    const std::int64_t round_end = k_ + n;
    while (k_ < round_end) {
      const std::int64_t start = k_;
      const std::int64_t limit = std::min(round_end, start + window_);
      // This rank's first conflicting activation in [start, limit).
      long long mine = limit;
      for (std::int64_t k = start; k < limit; ++k) {
        const LocalId l = local_of(activation(k));
        if (l < 0) continue;
        if (l < g.num_owned()) {
          bool conflict = stamp_[l] >= start && stamp_[l] < k;
          for (auto e = g.offsets()[l]; e < g.offsets()[l + 1] && !conflict; ++e) {
            const auto s = stamp_[g.adjacency()[e]];
            conflict = s >= start && s < k;
          }
          if (conflict) {
            mine = k;
            break;
          }
        }
        stamp_[l] = k;
      }
      long long end = 0;
      MPI_Allreduce(&mine, &end, 1, MPI_LONG_LONG, MPI_MIN, prob_.comm());
      // Apply the conflict-free prefix [start, end): the updates commute.
      for (std::int64_t k = start; k < end; ++k) {
        const LocalId l = local_of(activation(k));
        if (l >= 0 && l < g.num_owned()) activate(l);
      }
      g.halo().exchange(x_.data(), p);
      window_ = std::max<std::int64_t>(64, 2 * (end - start));
      k_ = end;
    }
    diff_norms(prob_, x_.data(), prev_.data(), &diff_sq_, &x_sq_);
  }

  const std::vector<double>& positions() const override { return x_; }
  double objective() override {
    prob_.graph().halo().exchange(x_.data(), prob_.dim());
    return evaluate_costs(prob_, x_.data()).relaxed;
  }
  const double* previous_positions() const override { return prev_.data(); }
  void change_norms(double* d, double* s) const override {
    *d = diff_sq_;
    *s = x_sq_;
  }
  void save(StateWriter& w) const override {
    w.scalar("activations", double(k_));  // the clock: the sequence is a function of (seed, k)
    w.node_rows("x", x_.data(), prob_.dim());
  }
  void load(const StateReader& r) override {
    k_ = static_cast<std::int64_t>(r.scalar("activations"));
    r.node_rows("x", x_.data(), prob_.dim());
    prob_.graph().halo().exchange(x_.data(), prob_.dim());
  }

 private:
  GlobalId activation(std::int64_t k) const {
    const auto n = static_cast<double>(prob_.num_sensors());
    auto i = static_cast<GlobalId>(uniform01(seed_, RngStream::kAsyncClock, static_cast<std::uint64_t>(k)) * n);
    return std::min<GlobalId>(i, prob_.num_sensors() - 1);
  }
  LocalId local_of(GlobalId g) const {
    auto it = std::lower_bound(lookup_.begin(), lookup_.end(), std::make_pair(g, LocalId(-1)));
    return (it != lookup_.end() && it->first == g) ? it->second : -1;
  }

  // L_i = delta_i + |A_i|; weighted: sum_j w_ij + sum_k w_ik (Huber keeps it).
  double local_lipschitz(LocalId i) const {
    const auto ab = prob_.anchor_offsets()[i], ae = prob_.anchor_offsets()[i + 1];
    const MeasurementModel& mo = prob_.model();
    if (!mo.weighted) return prob_.graph().degree(i) + double(ae - ab);
    double s = 0;
    for (auto e = prob_.graph().offsets()[i]; e < prob_.graph().offsets()[i + 1]; ++e) s += mo.edge_weight(e);
    for (auto e = ab; e < ae; ++e) s += mo.anchor_weight(e);
    return s;
  }

  void activate(LocalId i) {
    const int p = prob_.dim();
    double* xi = &x_[std::size_t(i) * p];
    double g[3], v[3];
    if (!exact_) {
      // eq. (20): one gradient step with the global L (>= delta_i + |A_i|).
      local_cost_grad(prob_, x_.data(), i, xi, g);
      for (int k = 0; k < p; ++k) xi[k] -= g[k] / L_;
      return;
    }
    // Algorithm 3 on f_i with L_i = delta_i + |A_i|, warm-started at x_i.
    const double Li = local_lipschitz(i);
    if (Li == 0) return;
    double z[3], zm[3], w[3];
    for (int k = 0; k < p; ++k) z[k] = zm[k] = xi[k];
    const double f0 = local_cost_grad(prob_, x_.data(), i, xi, g);
    for (int l = 1; l <= kInnerMax; ++l) {
      const double beta = double(l - 2) / double(l + 1);
      for (int k = 0; k < p; ++k) w[k] = z[k] + beta * (z[k] - zm[k]);
      local_cost_grad(prob_, x_.data(), i, w, g);
      double step = 0, nz = 0;
      for (int k = 0; k < p; ++k) {
        zm[k] = z[k];
        z[k] = w[k] - g[k] / Li;
        step += (z[k] - zm[k]) * (z[k] - zm[k]);
        nz += z[k] * z[k];
      }
      if (step <= kInnerTol * kInnerTol * (1 + nz)) break;
    }
    for (int k = 0; k < p; ++k) v[k] = z[k];
    // Keep the activation monotone even if the inner solve stopped early.
    if (local_cost_grad(prob_, x_.data(), i, v, g) <= f0)
      for (int k = 0; k < p; ++k) xi[k] = v[k];
  }

  static constexpr int kInnerMax = 500;
  static constexpr double kInnerTol = 1e-12;
  LocalizationProblem& prob_;
  bool exact_;
  std::uint64_t seed_;
  double L_;
  std::vector<double> x_, prev_;
  std::vector<std::pair<GlobalId, LocalId>> lookup_;
  std::vector<std::int64_t> stamp_;
  std::int64_t k_ = 0, window_ = 64;
  double diff_sq_ = 0, x_sq_ = 0;
};

}  // namespace

namespace detail {

std::unique_ptr<Algorithm> make_async(LocalizationProblem& prob, const SolverOptions& opt) {
  return std::make_unique<Async>(prob, opt, false);
}

std::unique_ptr<Algorithm> make_async_exact(LocalizationProblem& prob, const SolverOptions& opt) {
  return std::make_unique<Async>(prob, opt, true);
}

}  // namespace detail

}  // namespace snl
