// The synchronous methods: disk relaxation by Nesterov's method (003, Alg. 1),
// MM nonconvex refinement (000, Alg. 1) and the Barzilai-Borwein baseline
// (Calafiore, Carlone, Wei 2010, as compared in 000). Every node sums its
// neighbours in global-id order, so iterates are bit-identical for any number
// of ranks. Each iteration: halo begin -> interior nodes -> halo end -> boundary.
#include <algorithm>
#include <cmath>

#include "snl/problem/metrics.hpp"
#include "snl/core/random.hpp"
#include "snl/solvers/solver.hpp"
#include "solvers/algorithm_util.hpp"
#include "kernels/kernels.hpp"

namespace snl {

namespace {

using detail::diff_norms;
using detail::with_ghost_rows;

// ---------------------------------------------------------------------------
// Disk relaxation, Nesterov's method (003, Algorithm 1):
//   w = x(k-1) + (k-2)/(k+1) (x(k-1) - x(k-2)),   x(k) = w - grad f_hat(w) / L.
class Relaxation final : public Algorithm {
 public:
  Relaxation(LocalizationProblem& prob, int levels) : prob_(prob), L_(relaxation_lipschitz(prob)), levels_(levels) {}
  std::string name() const override { return "relaxation"; }
  double lipschitz() const override { return L_; }
  double reals_per_iteration() const override { return prob_.dim(); }

  void start(const std::vector<double>& x0) override {
    x_ = with_ghost_rows(prob_, x0);
    prev_ = x_;  // x(-1) = x(0)
    w_.assign(x_.size(), 0.0);
    w_next_.assign(x_.size(), 0.0);
    w_ready_ = false;
    lanes_.build(prob_);
    plan_.build(prob_, lanes_, levels_);
    norms_.assign(std::size_t(levels_) * 3 * detail::kMaxLanes, 0.0);
    stream_ = detail::stream_rows(4 * sizeof(double) * x_.size());
    k_ = 0;
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
    double* const w[2] = {w_.data(), w_next_.data()};
    double* const x[2] = {x_.data(), prev_.data()};
    const std::int64_t k0 = k_;
    detail::run_levels(plan_, lanes_, n, prob_.graph().halo(), w, p, [&](int j, std::int64_t c0, std::int64_t c1) {
      const std::int64_t k = k0 + j + 1;  // the iteration this level computes
      const double beta_next = static_cast<double>(k - 1) / static_cast<double>(k + 2);
      // g = grad f_hat(w) (003, Alg. 1 steps 7-8); x(k) = w - g/L goes over
      // x(k-2), which is no longer needed; w(k+1) = x(k) + beta_next (x(k) - x(k-1)).
      detail::relax_chunks(prob_, lanes_, c0, c1,
                           {w[j & 1], x[j & 1], x[(j + 1) & 1], w[(j + 1) & 1], L_, beta_next,
                            &norms_[std::size_t(j) * 3 * detail::kMaxLanes], stream_ && j == n - 1});
    });
    k_ += n;
    double sums[3];
    detail::sum_lanes(&norms_[std::size_t(n - 1) * 3 * detail::kMaxLanes], lanes_.lanes, 3, sums);
    diff_sq_ = sums[0];
    x_sq_ = sums[1];
    gsq_ = sums[2];
    if (n % 2 == 1) {
      std::swap(x_, prev_);  // x <- x(k), prev <- x(k-1)
      std::swap(w_, w_next_);
    }
    w_ready_ = true;
  }

  const std::vector<double>& positions() const override { return x_; }
  std::int64_t memory_bytes() const override {
    return static_cast<std::int64_t>(sizeof(double) * (x_.capacity() + prev_.capacity() + w_.capacity() +
                                                       w_next_.capacity() + norms_.capacity())) +
           lanes_.bytes() + plan_.bytes();
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
    return evaluate_costs(prob_, x_.data()).relaxed;
  }
  void change_norms(double* d, double* s) const override {
    *d = diff_sq_;
    *s = x_sq_;
  }
  double grad_norm_sq() const override { return gsq_; }
  void save(StateWriter& w) const override {
    w.scalar("k", double(k_));
    w.node_rows("x", x_.data(), prob_.dim());
    w.node_rows("x_prev", prev_.data(), prob_.dim());
  }
  void load(const StateReader& r) override {
    k_ = static_cast<std::int64_t>(r.scalar("k"));
    r.node_rows("x", x_.data(), prob_.dim());
    r.node_rows("x_prev", prev_.data(), prob_.dim());
    w_ready_ = false;
  }

 private:
  LocalizationProblem& prob_;
  double L_;
  std::vector<double> x_, prev_, w_, w_next_;
  detail::NodeLanes lanes_;
  int levels_;                 // iterations per pass at most (SolverOptions::temporal_block)
  detail::LevelPlan plan_;
  std::vector<double> norms_;  // per level and lane: ||x(k) - x(k-1)||^2, ||x(k)||^2, ||g||^2
  bool stream_ = false;        // non-temporal row stores (kernels.hpp)
  bool w_ready_ = false;
  std::int64_t k_ = 0;
  double diff_sq_ = 0, x_sq_ = 0, gsq_ = 0;
};

// ---------------------------------------------------------------------------
// MM / projected gradient on z = (x, y, w) (000, Algorithm 1, eqs. 11-13),
// L = 2 delta_max + max|A_i| + 2 (eq. 9). Edge variables y_e live with both
// ends of the edge and are updated redundantly with identical arithmetic, with
// the fixed orientation e = (i, j), i < j in global ids.
using detail::project_sphere;

class MM final : public Algorithm {
 public:
  MM(LocalizationProblem& prob, int levels)
      : prob_(prob), L_(2.0 * prob.max_degree() + prob.max_anchor_degree() + 2.0), levels_(levels) {}
  std::string name() const override { return "mm"; }
  double lipschitz() const override { return L_; }
  double reals_per_iteration() const override { return prob_.dim(); }

  void start(const std::vector<double>& x0) override {
    x_ = with_ghost_rows(prob_, x0);
    xn_ = x_;
    prob_.graph().halo().exchange(x_.data(), prob_.dim());
    lanes_.build(prob_);
    plan_.build(prob_, lanes_, levels_);
    norms_.assign(std::size_t(levels_) * 2 * detail::kMaxLanes, 0.0);
    if (prob_.dim() == 2)
      init<2>();
    else
      init<3>();
    stream_ = detail::stream_rows(sizeof(double) * (2 * x_.size() + y_.size()));
  }

  void iterate() override { iterate_levels(1); }
  int max_levels() const override { return levels_; }

  // n iterations in one pass over memory (detail::run_levels; n = 1: halo
  // begin -> interior chunks -> halo end -> boundary chunks). y is updated in
  // place, level after level; x(t + j) alternates between x_ and xn_. The
  // norms of the last level are summed per lane, then over the lanes in lane
  // order. Non-temporal stores only at the last level: the others' rows are
  // read again within the pass.
  void iterate_levels(int n) override {
    std::fill(norms_.begin(), norms_.end(), 0.0);
    double* const buf[2] = {x_.data(), xn_.data()};
    detail::run_levels(plan_, lanes_, n, prob_.graph().halo(), buf, prob_.dim(),
                       [&](int j, std::int64_t c0, std::int64_t c1) {
                         const detail::MMStep st{buf[j & 1], buf[(j + 1) & 1], y_.data(), aw_.data(),
                                                 (L_ - 1.0) / L_, 1.0 / L_, &norms_[std::size_t(j) * 2 * detail::kMaxLanes],
                                                 stream_ && j == n - 1};
                         detail::mm_chunks(prob_, lanes_, c0, c1, st);
                       });
    double sums[2];
    detail::sum_lanes(&norms_[std::size_t(n - 1) * 2 * detail::kMaxLanes], lanes_.lanes, 2, sums);
    diff_sq_ = sums[0];
    x_sq_ = sums[1];
    if (n % 2 == 1) std::swap(x_, xn_);
  }

  const std::vector<double>& positions() const override { return x_; }
  std::int64_t memory_bytes() const override {
    return static_cast<std::int64_t>(sizeof(double) * (x_.capacity() + xn_.capacity() + y_.capacity() +
                                                       aw_.capacity() + norms_.capacity())) +
           lanes_.bytes() + plan_.bytes();
  }
  // Per owned node: offsets and anchor offsets 16, x rows 8p (ghosts
  // included), x(t+1) written 8p; per slot: adjacency 4, range 8, orientation
  // 1, y read and written 16p; per anchor pair: id 4, range 8, w read and
  // written 16p. A pass of S > 1 levels moves all that once (the levels reuse
  // it from cache) but leaves both row arrays written: 16p instead of 8p.
  double traffic_bytes_per_iteration() const override {
    const double p = prob_.dim(), n = prob_.num_owned(), g = prob_.num_local() - prob_.num_owned();
    const double D = double(prob_.graph().adjacency().size()), A = double(prob_.anchor_ranges().size());
    const double rows = (levels_ == 1 ? 8 : 16) * p * n;
    return (16 * n + 8 * p * (n + g) + rows + (13 + 16 * p) * D + (12 + 16 * p) * A) / levels_;
  }
  double objective() override {
    prob_.graph().halo().exchange(x_.data(), prob_.dim());
    return prob_.dim() == 2 ? surrogate<2>() : surrogate<3>();
  }
  void change_norms(double* d, double* s) const override {
    *d = diff_sq_;
    *s = x_sq_;
  }
  // Checkpoints hold y per edge, independent of the lane layout (edge_rows
  // with an accessor: the layout is not copied).
  void save(StateWriter& w) const override {
    w.node_rows("x", x_.data(), prob_.dim());
    w.edge_rows("y", prob_.dim(), [&](LocalId v, std::int64_t e, int c) { return y_[y_index(v, e, c)]; });
    w.anchor_rows("w", aw_.data(), prob_.dim());
  }
  void load(const StateReader& r) override {
    r.node_rows("x", x_.data(), prob_.dim());
    r.edge_rows("y", prob_.dim(), [&](LocalId v, std::int64_t e, int c, double y) { y_[y_index(v, e, c)] = y; });
    r.anchor_rows("w", aw_.data(), prob_.dim());
  }

 private:
  // Index in y_ (lane layout) of coordinate c of CSR slot e of owned node v.
  std::size_t y_index(LocalId v, std::int64_t e, int c) const {
    return lanes_.at(v, e - prob_.graph().offsets()[v], prob_.dim(), c);
  }

  template <int P>
  void init() {
    const auto& gr = prob_.graph();
    const auto& off = gr.offsets();
    const auto& adj = gr.adjacency();
    y_.assign(std::size_t(lanes_.groups()) * lanes_.lanes * P, 0.0);
    aw_.assign(prob_.anchor_ranges().size() * P, 0.0);
    for (LocalId v = 0; v < gr.num_owned(); ++v) {
      for (auto e = off[v]; e < off[v + 1]; ++e) {
        const LocalId i = oriented_first(v, adj[e]), j = i == v ? adj[e] : v;
        double y[P];
        for (int c = 0; c < P; ++c) y[c] = x_[std::size_t(i) * P + c] - x_[std::size_t(j) * P + c];
        project_sphere<P>(gr.edge_value(e), y);
        for (int c = 0; c < P; ++c) y_[y_index(v, e, c)] = y[c];
      }
      const auto& aoff = prob_.anchor_offsets();
      for (auto e = aoff[v]; e < aoff[v + 1]; ++e) {
        const double* a = &prob_.anchors()[std::size_t(prob_.anchor_ids()[e]) * P];
        double* w = &aw_[std::size_t(e) * P];
        for (int c = 0; c < P; ++c) w[c] = x_[std::size_t(v) * P + c] - a[c];
        project_sphere<P>(prob_.anchor_ranges()[e], w);
      }
    }
  }

  LocalId oriented_first(LocalId v, LocalId u) const {
    return prob_.graph().global_id(v) < prob_.graph().global_id(u) ? v : u;
  }

  // F(z) = 1/2 sum ||x_i - x_j - y_e||^2 + 1/2 sum ||x_i - a_k - w_ik||^2 (000, eq. 2).
  template <int P>
  double surrogate() const {
    const auto& gr = prob_.graph();
    const auto& off = gr.offsets();
    const auto& adj = gr.adjacency();
    const auto& aoff = prob_.anchor_offsets();
    double F = 0;
    for (LocalId v = 0; v < gr.num_owned(); ++v) {
      const GlobalId gv = gr.global_id(v);
      for (auto e = off[v]; e < off[v + 1]; ++e) {
        const LocalId u = adj[e];
        if (gr.global_id(u) < gv) continue;
        double s = 0;
        for (int c = 0; c < P; ++c) {
          const double r = x_[std::size_t(v) * P + c] - x_[std::size_t(u) * P + c] - y_[y_index(v, e, c)];
          s += r * r;
        }
        F += 0.5 * s;
      }
      for (auto e = aoff[v]; e < aoff[v + 1]; ++e) {
        const double* a = &prob_.anchors()[std::size_t(prob_.anchor_ids()[e]) * P];
        double s = 0;
        for (int c = 0; c < P; ++c) {
          const double r = x_[std::size_t(v) * P + c] - a[c] - aw_[std::size_t(e) * P + c];
          s += r * r;
        }
        F += 0.5 * s;
      }
    }
    double G = 0;
    MPI_Allreduce(&F, &G, 1, MPI_DOUBLE, MPI_SUM, prob_.comm());
    return G;
  }

  LocalizationProblem& prob_;
  double L_;
  std::vector<double> x_, xn_, y_, aw_;  // y_: edge variables in the lane layout (NodeLanes::at)
  detail::NodeLanes lanes_;
  int levels_;              // iterations per pass at most (SolverOptions::temporal_block)
  detail::LevelPlan plan_;
  std::vector<double> norms_;  // per level and lane: ||x(t+1) - x(t)||^2, ||x(t+1)||^2
  bool stream_ = false;        // non-temporal row stores (kernels.hpp)
  double diff_sq_ = 0, x_sq_ = 0;
};

// ---------------------------------------------------------------------------
// Barzilai-Borwein gradient descent on the ML cost f (Calafiore et al. 2010):
// alpha = s's / s'y with both inner products estimated by T rounds of average
// consensus with Metropolis weights, so each node uses its own estimate.
class BB final : public Algorithm {
 public:
  BB(LocalizationProblem& prob, int rounds) : prob_(prob), T_(rounds), alpha0_(1.0 / relaxation_lipschitz(prob)) {}
  std::string name() const override { return "bb"; }
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

std::unique_ptr<Algorithm> make_algorithm(const std::string& name, LocalizationProblem& prob,
                                          const SolverOptions& opt) {
  if (name == "relaxation") return std::make_unique<Relaxation>(prob, opt.temporal_block);
  if (name == "mm") return std::make_unique<MM>(prob, opt.temporal_block);
  if (name == "bb") return std::make_unique<BB>(prob, opt.bb_rounds);
  if (auto a = make_sequential_algorithm(name, prob, opt)) return a;
  throw Error("unknown algorithm '" + name + "'");
}

std::vector<double> random_initial_positions(const LocalizationProblem& prob, std::uint64_t seed) {
  const int p = prob.dim();
  std::vector<double> lo(p, 0.0), hi(p, 1.0);
  const auto& a = prob.anchors();
  if (!a.empty()) {
    for (int c = 0; c < p; ++c) lo[c] = hi[c] = a[c];
    for (std::size_t k = 0; k < a.size() / p; ++k)
      for (int c = 0; c < p; ++c) {
        lo[c] = std::min(lo[c], a[k * p + c]);
        hi[c] = std::max(hi[c], a[k * p + c]);
      }
  }
  std::vector<double> x(std::size_t(prob.num_owned()) * p);
  for (LocalId v = 0; v < prob.num_owned(); ++v) {
    const auto g = static_cast<std::uint64_t>(prob.graph().global_id(v));
    for (int c = 0; c < p; ++c)
      x[std::size_t(v) * p + c] = lo[c] + (hi[c] - lo[c]) * uniform01(seed, RngStream::kInit, g * p + c);
  }
  return x;
}

}  // namespace snl
