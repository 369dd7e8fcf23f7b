// PM, the projection method of Gholami et al. (IEEE TSP 2013) compared in 003,
// run in parallel with exactly its sequential semantics (so results are
// bit-identical for any rank count): cyclic block-coordinate steps x_i <- mean
// of the projections of x_i onto the disks B(x_j, d_ij) and B(a_k, r_ik). The
// cyclic order is (colour, global id) for a deterministic Jones-Plassmann
// colouring: nodes of one colour are never neighbours, so each colour class
// updates in parallel, then one halo exchange.
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

// Projection of z onto the ball B(c, rho), accumulated into acc.
inline void add_ball_projection(const double* z, const double* c, double rho, int p, double* acc) {
  double s = 0;
  for (int k = 0; k < p; ++k) s += (z[k] - c[k]) * (z[k] - c[k]);
  const double nz = std::sqrt(s);
  const double f = nz > rho ? rho / nz : 1.0;
  for (int k = 0; k < p; ++k) acc[k] += c[k] + f * (z[k] - c[k]);
}

// Weighted / Huber model (weights.hpp): x_i <- sum_e a_e P_e(x_i) / sum_e a_e
// with a_e = w_e rho'(t_e)/t_e, t_e the distance of x_i to the disk: one
// gradient step of size 1/sum_e a_e on the quadratic majorizer of node i's
// terms at x_i, so each block step still decreases f_hat (unweighted l2: the mean).
inline void add_weighted_projection(const double* z, const double* c, double rho, double w, double delta, int p,
                                    double* acc, double* wsum) {
  double s = 0;
  for (int k = 0; k < p; ++k) s += (z[k] - c[k]) * (z[k] - c[k]);
  const double nz = std::sqrt(s);
  const double f = nz > rho ? rho / nz : 1.0;
  const double a = w * huber_factor(delta, nz > rho ? nz - rho : 0.0);
  for (int k = 0; k < p; ++k) acc[k] += a * (c[k] + f * (z[k] - c[k]));
  *wsum += a;
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

class ProjectionMethod final : public Algorithm {
 public:
  explicit ProjectionMethod(LocalizationProblem& prob) : prob_(prob) {}
  std::string name() const override { return algorithm_info(AlgorithmId::kPM).name; }
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
        if (prob_.model().active()) {
          weighted_step(i, xi, acc);
          continue;
        }
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

  // The weighted average of the projections (add_weighted_projection) into row i.
  void weighted_step(LocalId i, const double* xi, double* acc) {
    const int p = prob_.dim();
    const auto& g = prob_.graph();
    const MeasurementModel& mo = prob_.model();
    double wsum = 0;
    for (auto e = g.offsets()[i]; e < g.offsets()[i + 1]; ++e)
      add_weighted_projection(xi, &x_[std::size_t(g.adjacency()[e]) * p], g.edge_value(e), mo.edge_weight(e),
                              mo.huber_delta, p, acc, &wsum);
    for (auto e = prob_.anchor_offsets()[i]; e < prob_.anchor_offsets()[i + 1]; ++e)
      add_weighted_projection(xi, &prob_.anchors()[std::size_t(prob_.anchor_ids()[e]) * p], prob_.anchor_ranges()[e],
                              mo.anchor_weight(e), mo.huber_delta, p, acc, &wsum);
    for (int k = 0; k < p; ++k) x_[std::size_t(i) * p + k] = acc[k] / wsum;
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

}  // namespace

namespace detail {

std::unique_ptr<Algorithm> make_pm(LocalizationProblem& prob, const SolverOptions&) {
  return std::make_unique<ProjectionMethod>(prob);
}

}  // namespace detail

}  // namespace snl
