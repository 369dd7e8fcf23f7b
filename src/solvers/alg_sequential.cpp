// Methods whose papers define them sequentially, run in parallel with exactly
// the sequential semantics (so results are bit-identical for any rank count):
//
// * PM, the projection method of Gholami et al. (IEEE TSP 2013) compared in 003:
//   cyclic block-coordinate steps x_i <- mean of the projections of x_i onto the
//   disks B(x_j, d_ij) and B(a_k, r_ik). The cyclic order is (colour, global id)
//   for a deterministic Jones-Plassmann colouring: nodes of one colour are never
//   neighbours, so each colour class updates in parallel, then one halo exchange.
// * The asynchronous method of 003 (Algorithm 2): node activations xi_k drawn
//   uniformly (eq. 21) from a counter-based generator, so every rank knows the
//   whole sequence. A prefix of activations in which no node is activated twice
//   and no two activated nodes are neighbours commutes; the ranks agree on the
//   longest such prefix (one MPI_Allreduce), apply it in parallel, exchange the
//   halo, and go on. Inexact version: one step x_i <- x_i - grad_i f_hat / L
//   (eq. 20); exact version: minimise f_i(v) = sum_j 1/2 d_B(d_ij)(v - x_j)^2 +
//   sum_k 1/2 d_B(r_ik)(v - a_k)^2 by Nesterov's method (Algorithm 3) with the
//   spec's weight 1/2 (003's eq. 19 has 1/4, a slip) and L_i = delta_i + |A_i|.
//   One iteration = n activations (one message per activation: 1 per sensor).
#include <algorithm>
#include <cmath>

#include "snl/problem/metrics.hpp"
#include "snl/core/random.hpp"
#include "snl/solvers/solver.hpp"
#include "solvers/algorithm_util.hpp"

namespace snl {

namespace {

using detail::diff_norms;
const auto with_ghosts = detail::with_ghost_rows;

// Projection of z onto the ball B(c, rho), accumulated into acc.
inline void add_ball_projection(const double* z, const double* c, double rho, int p, double* acc) {
  double s = 0;
  for (int k = 0; k < p; ++k) s += (z[k] - c[k]) * (z[k] - c[k]);
  const double nz = std::sqrt(s);
  const double f = nz > rho ? rho / nz : 1.0;
  for (int k = 0; k < p; ++k) acc[k] += c[k] + f * (z[k] - c[k]);
}

// f_i and its gradient at v for owned node i (the local problem of node i).
double local_cost_grad(const LocalizationProblem& prob, const double* x, LocalId i, const double* v, double* g) {
  const int p = prob.dim();
  const auto& gr = prob.graph();
  double f = 0;
  for (int k = 0; k < p; ++k) g[k] = 0;
  auto term = [&](const double* c, double rho) {
    double s = 0;
    for (int k = 0; k < p; ++k) s += (v[k] - c[k]) * (v[k] - c[k]);
    const double nz = std::sqrt(s);
    if (nz > rho) {
      f += 0.5 * (nz - rho) * (nz - rho);
      const double a = 1.0 - rho / nz;
      for (int k = 0; k < p; ++k) g[k] += a * (v[k] - c[k]);
    }
  };
  for (auto e = gr.offsets()[i]; e < gr.offsets()[i + 1]; ++e)
    term(x + std::size_t(gr.adjacency()[e]) * p, gr.edge_value(e));
  for (auto e = prob.anchor_offsets()[i]; e < prob.anchor_offsets()[i + 1]; ++e)
    term(prob.anchors().data() + std::size_t(prob.anchor_ids()[e]) * p, prob.anchor_ranges()[e]);
  return f;
}

}  // namespace

std::vector<int> jones_plassmann_coloring(DistGraph& g) {
  // Priority: a hash of the global id (ties by id), so colours depend on the
  // graph alone, never on the partition.
  const LocalId nl = g.num_local(), no = g.num_owned();
  std::vector<double> colour(nl, -1.0);
  std::vector<std::uint64_t> prio(nl);
  for (LocalId v = 0; v < nl; ++v) prio[v] = mix64(static_cast<std::uint64_t>(g.global_id(v)) ^ 0x5bd1e995ULL);
  auto higher = [&](LocalId a, LocalId b) {
    return prio[a] != prio[b] ? prio[a] > prio[b] : g.global_id(a) > g.global_id(b);
  };
  std::vector<char> used;
  for (;;) {
    long long left = 0;
    std::vector<LocalId> now;
    for (LocalId v = 0; v < no; ++v) {
      if (colour[v] >= 0) continue;
      ++left;
      bool top = true;
      for (auto e = g.offsets()[v]; e < g.offsets()[v + 1] && top; ++e) {
        const LocalId u = g.adjacency()[e];
        if (colour[u] < 0 && higher(u, v)) top = false;
      }
      if (top) now.push_back(v);
    }
    long long total = 0;
    MPI_Allreduce(&left, &total, 1, MPI_LONG_LONG, MPI_SUM, g.comm());
    if (total == 0) break;
    for (LocalId v : now) {
      used.assign(g.degree(v) + 2, 0);
      for (auto e = g.offsets()[v]; e < g.offsets()[v + 1]; ++e) {
        const double c = colour[g.adjacency()[e]];
        if (c >= 0 && c < used.size()) used[static_cast<std::size_t>(c)] = 1;
      }
      int c = 0;
      while (used[c]) ++c;
      colour[v] = c;
    }
    g.halo().exchange(colour.data(), 1);
  }
  return std::vector<int>(colour.begin(), colour.end());
}

namespace {

// ---------------------------------------------------------------------------
class ProjectionMethod final : public Algorithm {
 public:
  explicit ProjectionMethod(LocalizationProblem& prob) : prob_(prob) {}
  std::string name() const override { return "pm"; }
  double reals_per_iteration() const override { return prob_.dim(); }

  void start(const std::vector<double>& x0) override {
    x_ = with_ghosts(prob_, x0);
    auto& g = prob_.graph();
    g.halo().exchange(x_.data(), prob_.dim());
    const auto colour = jones_plassmann_coloring(g);
    int nc = 0;
    for (LocalId v = 0; v < g.num_owned(); ++v) nc = std::max(nc, colour[v] + 1);
    MPI_Allreduce(MPI_IN_PLACE, &nc, 1, MPI_INT, MPI_MAX, prob_.comm());
    class_begin_.assign(nc + 1, 0);
    for (LocalId v = 0; v < g.num_owned(); ++v) ++class_begin_[colour[v] + 1];
    for (int c = 0; c < nc; ++c) class_begin_[c + 1] += class_begin_[c];
    order_.resize(g.num_owned());
    std::vector<std::int64_t> fill(class_begin_.begin(), class_begin_.end() - 1);
    for (LocalId v = 0; v < g.num_owned(); ++v) order_[fill[colour[v]]++] = v;
    prev_.assign(std::size_t(g.num_owned()) * prob_.dim(), 0.0);
  }

  void iterate() override {
    const int p = prob_.dim();
    auto& g = prob_.graph();
    std::copy(x_.begin(), x_.begin() + prev_.size(), prev_.begin());
    for (std::size_t c = 0; c + 1 < class_begin_.size(); ++c) {
      for (auto t = class_begin_[c]; t < class_begin_[c + 1]; ++t) {
        const LocalId i = order_[t];
        const auto deg = g.degree(i) + (prob_.anchor_offsets()[i + 1] - prob_.anchor_offsets()[i]);
        if (deg == 0) continue;
        double acc[3] = {0, 0, 0};
        const double* xi = &x_[std::size_t(i) * p];
        for (auto e = g.offsets()[i]; e < g.offsets()[i + 1]; ++e)
          add_ball_projection(xi, &x_[std::size_t(g.adjacency()[e]) * p], g.edge_value(e), p, acc);
        for (auto e = prob_.anchor_offsets()[i]; e < prob_.anchor_offsets()[i + 1]; ++e)
          add_ball_projection(xi, &prob_.anchors()[std::size_t(prob_.anchor_ids()[e]) * p],
                              prob_.anchor_ranges()[e], p, acc);
        for (int k = 0; k < p; ++k) x_[std::size_t(i) * p + k] = acc[k] / static_cast<double>(deg);
      }
      g.halo().exchange(x_.data(), p);  // the next colour sees this one's values
    }
    diff_norms(prob_, x_.data(), prev_.data(), &diff_sq_, &x_sq_);
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
  void save(StateWriter& w) const override { w.node_rows("x", x_.data(), prob_.dim()); }
  void load(const StateReader& r) override {
    r.node_rows("x", x_.data(), prob_.dim());
    prob_.graph().halo().exchange(x_.data(), prob_.dim());
  }

 private:
  LocalizationProblem& prob_;
  std::vector<double> x_, prev_;
  std::vector<std::int64_t> class_begin_;
  std::vector<LocalId> order_;
  double diff_sq_ = 0, x_sq_ = 0;
};

// ---------------------------------------------------------------------------
class Async final : public Algorithm {
 public:
  Async(LocalizationProblem& prob, const SolverOptions& opt, bool exact)
      : prob_(prob), exact_(exact), seed_(opt.seed), L_(relaxation_lipschitz(prob)) {}
  std::string name() const override { return exact_ ? "async-exact" : "async"; }
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
    const double Li = prob_.graph().degree(i) + double(prob_.anchor_offsets()[i + 1] - prob_.anchor_offsets()[i]);
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

std::unique_ptr<Algorithm> make_sequential_algorithm(const std::string& name, LocalizationProblem& prob,
                                                     const SolverOptions& opt) {
  if (name == "pm") return std::make_unique<ProjectionMethod>(prob);
  if (name == "async") return std::make_unique<Async>(prob, opt, false);
  if (name == "async-exact") return std::make_unique<Async>(prob, opt, true);
  return nullptr;
}

}  // namespace snl
