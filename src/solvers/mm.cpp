// MM nonconvex refinement (000, Algorithm 1): projected gradient on z = (x, y, w).
// Every node sums its neighbours in global-id order, so iterates are
// bit-identical for any number of ranks. Each iteration: halo begin -> interior
// nodes -> halo end -> boundary; with temporal blocking, several iterations per
// pass over memory (kernels.hpp).
#include <algorithm>
#include <cmath>
#include <memory>

#include "core/dim_dispatch.hpp"
#include "core/exact_sum.hpp"
#include "kernels/kernels.hpp"
#include "snl/problem/metrics.hpp"
#include "solvers/algorithm_util.hpp"
#include "solvers/methods.hpp"

namespace snl {

namespace {

using detail::with_ghost_rows;

// MM / projected gradient on z = (x, y, w) (000, Algorithm 1, eqs. 11-13),
// L = 2 delta_max + max|A_i| + 2 (eq. 9). Edge variables y_e live with both
// ends of the edge and are updated redundantly with identical arithmetic, with
// the fixed orientation e = (i, j), i < j in global ids.
using detail::project_sphere;

class MM final : public Algorithm {
 public:
  MM(LocalizationProblem& prob, int levels)
      : prob_(prob), L_(2.0 * prob.max_degree() + prob.max_anchor_degree() + 2.0), levels_(levels) {}
  std::string name() const override { return algorithm_info(AlgorithmId::kMM).name; }
  double lipschitz() const override { return L_; }
  double reals_per_iteration() const override { return prob_.dim(); }

  void start(const std::vector<double>& x0) override {
    x_ = with_ghost_rows(prob_, x0);
    xn_ = x_;
    prob_.graph().halo().exchange(x_.data(), prob_.dim());
    lanes_ = detail::shared_lanes(prob_);
    plan_.build(prob_, *lanes_, levels_);
    norms_.assign(std::size_t(levels_) * 2 * detail::kMaxLanes, 0.0);
    detail::with_dim(prob_.dim(), [&](auto P) { init<decltype(P)::value>(); });
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
    detail::run_levels(plan_, *lanes_, n, prob_.graph().halo(), buf, prob_.dim(),
                       [&](int j, std::int64_t c0, std::int64_t c1) {
                         const detail::MMStep st{buf[j & 1], buf[(j + 1) & 1], y_.data(), aw_.data(),
                                                 (L_ - 1.0) / L_, 1.0 / L_, &norms_[std::size_t(j) * 2 * detail::kMaxLanes],
                                                 stream_ && j == n - 1};
                         detail::mm_chunks(prob_, *lanes_, c0, c1, st);
                       });
    double sums[2];
    detail::sum_lanes(&norms_[std::size_t(n - 1) * 2 * detail::kMaxLanes], lanes_->lanes, 2, sums);
    diff_sq_ = sums[0];
    x_sq_ = sums[1];
    if (n % 2 == 1) std::swap(x_, xn_);
  }

  const std::vector<double>& positions() const override { return x_; }
  std::int64_t memory_bytes() const override {
    return static_cast<std::int64_t>(sizeof(double) * (x_.capacity() + xn_.capacity() + y_.capacity() +
                                                       aw_.capacity() + norms_.capacity())) +
           (lanes_ ? lanes_->bytes() : 0) + plan_.bytes();
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
    return detail::with_dim(prob_.dim(), [&](auto P) { return surrogate<decltype(P)::value>(); });
  }
  const double* previous_positions() const override { return xn_.data(); }
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
    return lanes_->at(v, e - prob_.graph().offsets()[v], prob_.dim(), c);
  }

  template <int P>
  void init() {
    y_.assign(std::size_t(lanes_->groups()) * lanes_->lanes * P, 0.0);
    aw_.assign(prob_.anchor_ranges().size() * P, 0.0);
    detail::best_edge_variables<P>(prob_, x_.data(),
                                   [&](LocalId v, std::int64_t e, int c) { return &y_[y_index(v, e, c)]; }, aw_.data());
  }

  // F(z) = 1/2 sum ||x_i - x_j - y_e||^2 + 1/2 sum ||x_i - a_k - w_ik||^2 (000, eq. 2).
  template <int P>
  double surrogate() const {
    const auto& gr = prob_.graph();
    const auto& off = gr.offsets();
    const auto& adj = gr.adjacency();
    const auto& aoff = prob_.anchor_offsets();
    detail::ExactSum F;  // exact: the same surrogate for any partition
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
        F.add(0.5 * s);
      }
      for (auto e = aoff[v]; e < aoff[v + 1]; ++e) {
        const double* a = &prob_.anchors()[std::size_t(prob_.anchor_ids()[e]) * P];
        double s = 0;
        for (int c = 0; c < P; ++c) {
          const double r = x_[std::size_t(v) * P + c] - a[c] - aw_[std::size_t(e) * P + c];
          s += r * r;
        }
        F.add(0.5 * s);
      }
    }
    detail::allreduce_exact(&F, 1, prob_.comm());
    return F.value();
  }

  LocalizationProblem& prob_;
  double L_;
  std::vector<double> x_, xn_, y_, aw_;  // y_: edge variables in the lane layout (NodeLanes::at)
  std::shared_ptr<const detail::NodeLanes> lanes_;  // the phases share one (detail::shared_lanes)
  int levels_;              // iterations per pass at most (SolverOptions::temporal_block)
  detail::LevelPlan plan_;
  std::vector<double> norms_;  // per level and lane: ||x(t+1) - x(t)||^2, ||x(t+1)||^2
  bool stream_ = false;        // non-temporal row stores (kernels.hpp)
  double diff_sq_ = 0, x_sq_ = 0;
};

}  // namespace

namespace detail {

std::unique_ptr<Algorithm> make_mm(LocalizationProblem& prob, const SolverOptions& opt) {
  if (prob.model().active()) return make_model_mm(prob);  // weights or Huber: weighted.cpp
  return std::make_unique<MM>(prob, opt.temporal_block);
}

}  // namespace detail

}  // namespace snl
