// Disk relaxation by Nesterov's method (003, Algorithm 1). Every node sums its
// neighbours in global-id order, so iterates are bit-identical for any number
// of ranks. Each iteration: halo begin -> interior nodes -> halo end -> boundary;
// with temporal blocking, several iterations per pass over memory (kernels.hpp).
//
// The same loop on the ML cost f is ml-agd, dv-pipeline's last phase: Nesterov's
// accelerated gradient with the step D^-1, D_v = 2 delta_v + |A_v| per node (f's
// curvature is bounded above by the graph Laplacian plus the anchor terms: each
// edge term 1/2 |z|^2 - d |z| + d^2/2 is a quadratic plus a concave function;
// and the Laplacian is at most twice its diagonal, so the descent lemma holds
// in D's norm), and the gradient restart of O'Donoghue & Candes (Found.
// Comput. Math. 2015): when grad f(w(k)) . (x(k) - x(k-1)) > 0 the momentum
// starts again from x(k). That sum is exact over the nodes, so the restarts,
// like the iterates, are the same for any number of ranks. One kernel pass
// and one halo exchange per iteration, with no edge variables: a fifth of
// mm-accel's memory traffic.
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <cstdlib>

#include "core/exact_sum.hpp"
#include "kernels/kernels.hpp"
#include "solvers/lane_costs.hpp"
#include "snl/problem/metrics.hpp"
#include "solvers/algorithm_util.hpp"
#include "solvers/methods.hpp"

namespace snl {

namespace {

using detail::with_ghost_rows;

// Disk relaxation, Nesterov's method (003, Algorithm 1):
//   w = x(k-1) + (k-2)/(k+1) (x(k-1) - x(k-2)),   x(k) = w - grad f_hat(w) / L.
class Relaxation final : public Algorithm {
 public:
  Relaxation(LocalizationProblem& prob, int levels, bool ml = false)
      : prob_(prob), L_(relaxation_lipschitz(prob)), levels_(ml ? 1 : levels), ml_(ml) {}
  std::string name() const override {
    return algorithm_info(ml_ ? AlgorithmId::kMlAgd : AlgorithmId::kRelaxation).name;
  }
  double lipschitz() const override { return L_; }
  double reals_per_iteration() const override { return prob_.dim(); }

  void start(const std::vector<double>& x0) override {
    x_ = with_ghost_rows(prob_, x0);
    prev_ = x_;  // x(-1) = x(0)
    w_.assign(x_.size(), 0.0);
    w_next_.assign(x_.size(), 0.0);
    w_ready_ = false;
    lanes_ = detail::shared_lanes(prob_);
    plan_.build(prob_, *lanes_, levels_);
    norms_.assign(std::size_t(levels_) * 3 * detail::kMaxLanes, 0.0);
    stream_ = detail::stream_rows(4 * sizeof(double) * x_.size());
    k_ = 0;
    exact_restart_tests_ = std::getenv("SNL_TEST_EXACT_RESTART") != nullptr;  // tests: the exact path always
    if (ml_) {  // 1 / (2 delta_v + |A_v|); 0 for a node with no terms (its gradient is 0)
      inv_d_.assign(prob_.num_owned(), 0.0);
      const auto& aoff = prob_.anchor_offsets();
      for (LocalId v = 0; v < prob_.num_owned(); ++v) {
        const double d = 2.0 * prob_.graph().degree(v) + double(aoff[v + 1] - aoff[v]);
        inv_d_[v] = d > 0 ? 1.0 / d : 0.0;
      }
    }
  }

  void iterate() override { iterate_levels(1); }
  int max_levels() const override { return levels_; }

  // n iterations in one pass over the owned nodes, in chunks of SIMD lanes
  // (kernels.hpp, detail::run_levels): per node and level, the gradient at w,
  // x(k) = w - g/L, the norms of the stopping tests and next iteration's
  // extrapolation point (one read of w and x(k-1), one write of x(k) and
  // w(k+1)). Level j reads w from w_ / w_next_ and x(k-1) from x_ / prev_
  // alternately (j even / odd) and writes the other. The norms of the last
  // level are summed per lane, then over the lanes in lane order.
  void iterate_levels(int n) override {
    const int p = prob_.dim();
    const LocalId n_owned = prob_.num_owned();
    if (!w_ready_) {  // first iteration or after a restart
      const double beta = static_cast<double>(k_ - 1) / static_cast<double>(k_ + 2);
      const std::size_t m = std::size_t(n_owned) * p;
      for (std::size_t t = 0; t < m; ++t) w_[t] = x_[t] + beta * (x_[t] - prev_[t]);
    }
    std::fill(norms_.begin(), norms_.end(), 0.0);
    restart_sums_.fill(0.0);
    double* const w[2] = {w_.data(), w_next_.data()};
    double* const x[2] = {x_.data(), prev_.data()};
    const std::int64_t k0 = k_;
    detail::run_levels(plan_, *lanes_, n, prob_.graph().halo(), w, p, [&](int j, std::int64_t c0, std::int64_t c1) {
      const std::int64_t k = k0 + j + 1;  // the iteration this level computes
      const double beta_next = static_cast<double>(k - 1) / static_cast<double>(k + 2);
      // g = grad f_hat(w) (003, Alg. 1 steps 7-8); x(k) = w - g/L goes over
      // x(k-2), which is no longer needed; w(k+1) = x(k) + beta_next (x(k) - x(k-1)).
      detail::relax_chunks(prob_, *lanes_, c0, c1,
                           {w[j & 1], x[j & 1], x[(j + 1) & 1], w[(j + 1) & 1], L_, beta_next,
                            &norms_[std::size_t(j) * 3 * detail::kMaxLanes], stream_ && j == n - 1, ml_,
                            ml_ ? inv_d_.data() : nullptr, ml_ && j == n - 1 ? restart_sums_.data() : nullptr});
    });
    k_ += n;
    double sums[3];
    detail::sum_lanes(&norms_[std::size_t(n - 1) * 3 * detail::kMaxLanes], lanes_->lanes, 3, sums);
    diff_sq_ = sums[0];
    x_sq_ = sums[1];
    gsq_ = sums[2];
    if (n % 2 == 1) {
      std::swap(x_, prev_);  // x <- x(k), prev <- x(k-1)
      std::swap(w_, w_next_);
    }
    w_ready_ = true;
    if (ml_ && restart_due()) {  // w(k+1) is formed again, from x(k) alone
      k_ = 1;
      w_ready_ = false;
      ++restarts_;
    }
  }

  const std::vector<double>& positions() const override { return x_; }
  std::int64_t memory_bytes() const override {
    return static_cast<std::int64_t>(sizeof(double) * (x_.capacity() + prev_.capacity() + w_.capacity() +
                                                       w_next_.capacity() + norms_.capacity())) +
           (lanes_ ? lanes_->bytes() : 0) + plan_.bytes();
  }
  // Per owned node: offsets and anchor offsets 16, w rows 8p (own and
  // neighbours' once, ghosts included), x(k-1) read, x(k) and w(k+1) written
  // 24p; per slot: adjacency 4 and range 8; per anchor pair: id 4, range 8.
  // A pass of S > 1 levels moves all that once (the levels reuse it from
  // cache) but leaves all four row arrays written: 40p instead of 24p.
  double traffic_bytes_per_iteration() const override {
    const double p = prob_.dim(), n = prob_.num_owned(), g = prob_.num_local() - prob_.num_owned();
    const double D = double(prob_.graph().adjacency().size()), A = double(prob_.anchor_ranges().size());
    const double rows = (levels_ == 1 ? 24 : 40) * p * n;
    return (16 * n + 8 * p * (n + g) + rows + 12 * D + 12 * A) / levels_;
  }
  double objective() override {
    prob_.graph().halo().exchange(x_.data(), prob_.dim());
    return ml_ ? detail::exact_costs(prob_, x_.data(), detail::kMlSum).ml
               : detail::exact_costs(prob_, x_.data(), detail::kRelaxedSum).relaxed;
  }
  bool objective_is_ml_cost() const override { return ml_; }
  void change_norms(double* d, double* s) const override {
    *d = diff_sq_;
    *s = x_sq_;
  }
  double grad_norm_sq() const override { return gsq_; }
  const double* previous_positions() const override { return prev_.data(); }
  // The kernels sum the gradient norm per SIMD lane (partition-dependent):
  // the gradient at w(k), which the last level read from w_next_, again per node.
  const double* gradient_rows() override {
    if (!w_ready_) return nullptr;
    grad_.resize(std::size_t(prob_.num_owned()) * prob_.dim());
    prob_.graph().halo().exchange(w_next_.data(), prob_.dim());
    if (ml_)
      ml_gradient(prob_, w_next_.data(), grad_.data(), 0, prob_.num_owned());
    else
      relaxed_gradient(prob_, w_next_.data(), grad_.data(), 0, prob_.num_owned());
    return grad_.data();
  }
  void report(std::vector<std::pair<std::string, double>>* values,
              std::vector<std::pair<std::string, std::string>>*) const override {
    if (ml_) values->emplace_back("restarts", double(restarts_));
  }
  void save(StateWriter& w) const override {
    w.scalar("k", double(k_));
    if (ml_) w.scalar("restarts", double(restarts_));
    w.node_rows("x", x_.data(), prob_.dim());
    w.node_rows("x_prev", prev_.data(), prob_.dim());
  }
  void load(const StateReader& r) override {
    k_ = static_cast<std::int64_t>(r.scalar("k"));
    if (ml_) restarts_ = static_cast<std::int64_t>(r.scalar("restarts"));
    r.node_rows("x", x_.data(), prob_.dim());
    r.node_rows("x_prev", prev_.data(), prob_.dim());
    w_ready_ = false;
  }

 private:
  // ml-agd's restart test: grad f(w(k)) . (x(k) - x(k-1)) > 0, where
  // grad f(w(k))_v = D_v (w(k) - x(k))_v (w(k) is in w_next_ after the swap):
  // the sign of the exact sum of the per-node terms q_v (restart_term), the
  // same decision for any partition. The kernel adds the q_v in plain doubles
  // as it writes x(k) (RelaxStep::restart, the same bits per term); those sums
  // (one collective) settle the sign unless it is within their rounding
  // bound of zero, and then the exact sum decides (a pass over the rows).
  // Bound: a sum of n_r terms in any order is within gamma_{n_r-1} sum |q| of
  // the exact one (Higham, Accuracy and Stability of Numerical Algorithms,
  // 2002, sec. 4.2), below n u sum |q| with n the sensors and u = 2^-53; the
  // ranks' sums are added exactly; 2 n u A leaves a factor two for the
  // rounding of A and of the total, and n 2^-1074 covers subnormal terms.
  double restart_term(LocalId v) const {
    const int p = prob_.dim();
    double t = 0;
    for (int c = 0; c < p; ++c) {
      const std::size_t i = std::size_t(v) * p + c;
      t += (w_next_[i] - x_[i]) * (x_[i] - prev_[i]);
    }
    return t / inv_d_[v];
  }
  bool restart_due() const {
    double s = 0, a = 0;  // the kernel's lane sums (RelaxStep::restart), in any order: the bound holds
    for (int L = 0; L < lanes_->lanes; ++L) {
      s += restart_sums_[std::size_t(L)];
      a += restart_sums_[std::size_t(lanes_->lanes + L)];
    }
    detail::ExactSum sums[2];
    sums[0].add(s);
    sums[1].add(a);
    detail::allreduce_exact(sums, 2, prob_.comm());
    const double S = sums[0].value(), A = sums[1].value();
    const double n = static_cast<double>(prob_.num_sensors()) + 2.0;
    if (!exact_restart_tests_ && std::fabs(S) > 2.0 * n * 0x1p-53 * A + n * 0x1p-1074)
      return S > 0;  // NaN or inf: not settled here
    detail::ExactSum e;
    for (LocalId v = 0; v < prob_.num_owned(); ++v)
      if (inv_d_[v] > 0) e.add(restart_term(v));
    detail::allreduce_exact(&e, 1, prob_.comm());
    return e.value() > 0;
  }

  LocalizationProblem& prob_;
  double L_;
  std::vector<double> x_, prev_, w_, w_next_;
  std::shared_ptr<const detail::NodeLanes> lanes_;  // the phases share one (detail::shared_lanes)
  int levels_;                 // iterations per pass at most (SolverOptions::temporal_block)
  detail::LevelPlan plan_;
  std::vector<double> norms_;  // per level and lane: ||x(k) - x(k-1)||^2, ||x(k)||^2, ||g||^2
  std::vector<double> grad_;   // gradient_rows(), sized on first use
  std::vector<double> inv_d_;  // ml-agd: 1 / D_v per owned node
  std::array<double, 2 * detail::kMaxLanes> restart_sums_{};  // ml-agd: the kernel's restart sums per lane
  bool stream_ = false;        // non-temporal row stores (kernels.hpp)
  bool w_ready_ = false;
  bool ml_ = false;            // ml-agd: the ML cost's gradient, restarts
  std::int64_t restarts_ = 0;
  bool exact_restart_tests_ = false;  // SNL_TEST_EXACT_RESTART: every restart test by the exact sum
  std::int64_t k_ = 0;
  double diff_sq_ = 0, x_sq_ = 0, gsq_ = 0;
};

}  // namespace

namespace detail {

std::unique_ptr<Algorithm> make_relaxation(LocalizationProblem& prob, const SolverOptions& opt) {
  if (prob.model().active()) return make_model_relaxation(prob);  // weights or Huber: weighted.cpp
  return std::make_unique<Relaxation>(prob, opt.temporal_block);
}

std::unique_ptr<Algorithm> make_ml_agd(LocalizationProblem& prob, const SolverOptions&) {
  if (prob.model().active()) throw Error("ml-agd minimizes the unweighted l2 ML cost only");
  return std::make_unique<Relaxation>(prob, 1, true);
}

}  // namespace detail

}  // namespace snl
