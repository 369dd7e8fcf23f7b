// Accelerated MM (mm-accel): 000's MM step (Algorithm 1, eqs. 11-13) taken
// from a Nesterov-extrapolated point, kept monotone in the MM surrogate F by
// rejecting any step that would raise F and restarting the momentum there.
//
// MM is projected gradient on z = (x, y, w) with step 1/L over the product of
// R^{np} and the range spheres. Its accelerated form extrapolates z:
//   v = z(k) + beta_t (z(k) - z(k-1)),  z+ = P_C(v - grad F(v) / L),
// beta_t = t / (t + 3), t the steps accepted since the last restart (the
// (k-1)/(k+2) sequence of Nesterov's method). z+ is accepted when neither F
// nor the ML cost f rises: F(z+) <= F(z(k)) and f(x+) <= f(x(k)). Otherwise
// it is discarded, t = 0, the edge and anchor variables are reset to their
// best values for x(k) (y_e = P_sphere(d_e)(x_i - x_j), w likewise, where
// F(x(k), y, w) = f(x(k))), and the next iteration is a plain MM step from
// there, which 000's majorization argument makes monotone in both (a
// projected gradient step with step 1/L, L >= the Lipschitz constant of grad
// F, from a feasible point never raises F, and f(x+) <= F(z+) <= F(x(k), y,
// w) = f(x(k))). This is the function-value restart of O'Donoghue & Candes
// (Found. Comput. Math. 2015) made monotone as in Beck & Teboulle's MFISTA
// (IEEE TIP 2009) and Li & Lin's monotone APG for nonconvex problems (NeurIPS
// 2015): neither F nor f ever increases, and f(x) <= F(z) throughout. (With
// the test on F alone, f rose at some iterations on 8 of 50 small random
// networks.)
//
// One iteration is one kernel pass and one halo exchange (the new x rows),
// so one message per sensor as for MM; a rejected iteration counts as one.
// The test compares F and f as exact sums of per-node terms (detail::ExactSum;
// see add_terms), and the extrapolation is the same arithmetic on every copy of
// a row or edge variable, so the iterates are bit-identical for any number of
// ranks. Each iteration sums the terms in plain doubles with a rounding bound
// (add_terms_plain, accepts): only a comparison within the bounds, about
// 1e-13 of the costs, sums them exactly (the exact adds were a tenth of an
// iteration). Parameter-free: L is MM's (eq. 9).
//
// Under a measurement model (weights, Huber; weights.hpp) the step is
// ModelMM's (weighted.cpp: per-node steps from a diagonal majorizer of the
// quadratic majorizer at the current point), F is its surrogate Phi and f the
// weighted / Huber ML cost; the argument is unchanged: a plain step from a
// feasible point with (y, w) at their best values lowers Phi, and there
// Phi = f. Two cores, one algorithm: LaneCore (the SIMD kernels, plain l2)
// and ModelCore (model_mm.hpp, one node at a time).
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <cstdlib>
#include <cstring>

#include "core/dim_dispatch.hpp"
#include "core/exact_sum.hpp"
#include "kernels/kernels.hpp"
#include "solvers/algorithm_util.hpp"
#include "solvers/methods.hpp"
#include "solvers/model_mm.hpp"

namespace snl {

namespace {

using detail::project_sphere;

// One MM step from the point with rows v (ghost rows included) into xout, the
// edge and anchor variables y and w updated in place; with ya set (cores that
// extrapolate themselves), the step's input is (v + beta (v - xb), ya + beta
// (ya - yb)) instead.
struct StepArgs {
  const double* v;
  double* xout;
  double* y;
  double* w;
  const double* ya = nullptr;
  const double* yb = nullptr;
  const double* xb = nullptr;
  double beta = 0;
};

// Plain l2: MM's SIMD kernel on the lane layout (kernels.hpp); F and f summed
// per node in slot order (detail::mm_cost_chunk), then exactly.
class LaneCore {
 public:
  explicit LaneCore(LocalizationProblem& prob)
      : prob_(prob), L_(2.0 * prob.max_degree() + prob.max_anchor_degree() + 2.0) {
    lanes_ = detail::shared_lanes(prob);
    norms_.assign(2 * detail::kMaxLanes, 0.0);
    block_F_.assign(std::size_t(kCacheChunks) * detail::kMaxLanes, 0.0);
    block_f_.assign(block_F_.size(), 0.0);
    block_any_.assign(std::size_t(kCacheChunks), 0);
  }
  double lipschitz() const { return L_; }
  std::size_t y_size() const { return std::size_t(lanes_->groups()) * lanes_->lanes * prob_.dim(); }
  // Index in y (lane layout) of coordinate c of CSR slot e of owned node v.
  std::size_t y_index(LocalId v, std::int64_t e, int c) const {
    return lanes_->at(v, e - prob_.graph().offsets()[v], prob_.dim(), c);
  }
  std::int64_t chunks() const { return lanes_->size(); }
  std::int64_t split() const { return lanes_->split; }  // chunks [0, split) need no ghost row
  std::int64_t bytes() const {
    return (lanes_ ? lanes_->bytes() : 0) +
           std::int64_t(sizeof(double) * (norms_.capacity() + block_F_.capacity() + block_f_.capacity()) +
                        sizeof(unsigned) * block_any_.capacity());
  }

  void init(const double* x, double* y, double* w) const {
    detail::with_dim(prob_.dim(), [&](auto P) { init_p<decltype(P)::value>(x, y, w); });
  }
  // The kernels form the extrapolated point themselves (every kernel table
  // reads v + beta (v - xb) and ya + beta (ya - yb) on the fly: no buffer
  // and no pass for it).
  static constexpr bool kExtrapolates = true;
  void step(const StepArgs& a) { detail::mm_chunks(prob_, *lanes_, 0, lanes_->size(), step_args(a)); }
  // Chunks [c0, c1) of one pass: F and f of z = (x, y, w) into F (exactly or
  // in plain block sums), and the extrapolating step from v = x with ya = y
  // (the candidate, as pass() calls it) and yb into the step's buffers. The
  // step sums the chunks' edge terms itself (MMStep::cost_F: it loads the
  // same rows and edge variables), a block of chunks at a time into the
  // block's buffers; the anchor terms and the per-node adds follow, in
  // add_terms' order. The step's arithmetic per chunk is the whole-range
  // step's, so the iterates are the same bits.
  void terms_and_step(const double* x, const double* y, const double* w, std::int64_t c0, std::int64_t c1,
                      detail::ExactSum* F, bool exact, const StepArgs& a, bool /*boundary*/) {
    detail::MMStep st = step_args(a);
    st.cost_F = block_F_.data();
    st.cost_f = block_f_.data();
    st.cost_any = block_any_.data();
    for (std::int64_t b = c0; b < c1; b += kCacheChunks) {
      const std::int64_t e = std::min(c1, b + kCacheChunks);
      st.cost_base = b;
      detail::mm_chunks(prob_, *lanes_, b, e, st);
      const EdgeSums sums{block_F_.data(), block_f_.data(), block_any_.data(), b};
      detail::with_dim(prob_.dim(), [&](auto P) {
        constexpr int p = decltype(P)::value;
        if (exact)
          add_terms_p<p, true>(x, y, w, b, e, F, &sums);
        else
          add_terms_p<p, false>(x, y, w, b, e, F, &sums);
      });
    }
  }
  detail::MMStep step_args(const StepArgs& a) {
    std::fill(norms_.begin(), norms_.end(), 0.0);
    detail::MMStep st{a.v, a.xout, a.y, a.w, (L_ - 1.0) / L_, 1.0 / L_, norms_.data(), false};
    st.ya = a.ya;
    st.yb = a.yb;
    st.xb = a.ya ? a.xb : nullptr;
    st.beta = a.beta;
    st.stream_y = a.ya != nullptr && detail::stream_rows(sizeof(double) * y_size());
    return st;
  }
  void add_terms(const double* x, const double* y, const double* w, std::int64_t c0, std::int64_t c1,
                 detail::ExactSum* F) const {
    detail::with_dim(prob_.dim(), [&](auto P) { add_terms_p<decltype(P)::value, true>(x, y, w, c0, c1, F); });
  }
  // The same terms in plain doubles, each register lane's in blocks of at
  // most plain_block_adds() adds, the block sums added exactly into F: F and f
  // are then within 2 (m + 2) u of the exact sums (m the block length, u =
  // 2^-53; every term is >= 0, so the bound is relative to the sum itself).
  static constexpr bool kPlainSums = true;
  void add_terms_plain(const double* x, const double* y, const double* w, std::int64_t c0, std::int64_t c1,
                       detail::ExactSum* F) const {
    detail::with_dim(prob_.dim(), [&](auto P) { add_terms_p<decltype(P)::value, false>(x, y, w, c0, c1, F); });
  }
  double plain_block_adds() const {
    return double(std::max(kBlockAdds, 1 + detail::kMaxLanes * prob_.max_anchor_degree()));
  }

 private:
  static constexpr int kBlockAdds = 256;
  // Chunks per block of terms_and_step: their edge variables (a few KiB a
  // chunk) stay in the core's L2 between the two kernels.
  static constexpr std::int64_t kCacheChunks = 64;
  // A block's per-chunk edge sums, as mm_cost_chunk gives them (chunk c at c - base).
  struct EdgeSums {
    const double* F;
    const double* f;
    const unsigned* any;
    std::int64_t base;
  };
  template <int P>
  void init_p(const double* x, double* yv, double* wv) const {
    detail::best_edge_variables<P>(prob_, x, [&](LocalId v, std::int64_t e, int c) { return &yv[y_index(v, e, c)]; },
                                   wv);
  }

  // Chunks [c0, c1) of the lane layout: each sensor edge at the slot oriented
  // (owner, neighbour) in global-id order (so once over all ranks), then the
  // chunk's anchor edges.
  // F[0] gets F's terms, F[1] f's: 0.5 (|x_i - x_j| - d_e)^2 per edge.
  // Each node first sums its own edges' terms in plain doubles, in its slot
  // order (its neighbours' global-id order, the same on every partition;
  // detail::mm_cost_chunk, SIMD across the chunk's nodes), and only that
  // per-node sum enters the exact accumulator: one exact add per node
  // instead of one per edge (the exact adds were two thirds of an
  // iteration), with the same independence of the partition. Each register
  // lane adds into its own accumulators (merged at the end; the sums are
  // exact, so grouping changes no bit): consecutive adds then do not wait on
  // each other's digits.
  // Exact: each node's terms enter the exact accumulators; otherwise plain
  // block sums do (add_terms_plain), flushed before a lane's block would pass
  // kBlockAdds adds (a chunk's anchor terms go to lane 0).
  // pre: the chunks' edge sums already formed (by the step), else mm_cost_chunk's.
  template <int P, bool Exact>
  void add_terms_p(const double* x, const double* y, const double* w, std::int64_t c0, std::int64_t c1,
                   detail::ExactSum* F, const EdgeSums* pre = nullptr) const {
    const int C = lanes_->lanes;
    detail::ExactSum accF[detail::kMaxLanes], accf[detail::kMaxLanes];
    double blkF[detail::kMaxLanes] = {}, blkf[detail::kMaxLanes] = {};
    int adds = 0;  // lane 0's adds in the current block (the most of any lane)
    auto flush = [&] {
      for (int L = 0; L < C; ++L) {
        accF[L].add(blkF[L]);
        accf[L].add(blkf[L]);
        blkF[L] = blkf[L] = 0;
      }
      adds = 0;
    };
    auto put = [&](int L, double tF, double tf) {
      if (Exact) {
        accF[L].add(tF);
        accf[L].add(tf);
      } else {
        blkF[L] += tF;
        blkf[L] += tf;
      }
    };
    const auto& aoff = prob_.anchor_offsets();
    for (std::int64_t c = c0; c < c1; ++c) {
      if (!Exact) {
        const LocalId v0 = lanes_->first[c];
        const int here = 1 + int(aoff[v0 + lanes_->count[c]] - aoff[v0]);
        if (adds > 0 && adds + here > kBlockAdds) flush();
        adds += here;
      }
      double nodeF[detail::kMaxLanes] = {}, nodef[detail::kMaxLanes] = {};
      unsigned any;
      if (pre) {
        const std::size_t q = std::size_t(c - pre->base);
        any = pre->any[q];
        std::copy(pre->F + C * q, pre->F + C * (q + 1), nodeF);
        std::copy(pre->f + C * q, pre->f + C * (q + 1), nodef);
      } else {
        any = detail::mm_cost_chunk(*lanes_, P, c, x, y, nodeF, nodef);
      }
      for (int L = 0; L < C; ++L)
        if ((any >> L) & 1) put(L, 0.5 * nodeF[L], 0.5 * nodef[L]);
      for (LocalId v = lanes_->first[c]; v < lanes_->first[c] + lanes_->count[c]; ++v)
        for (auto e = aoff[v]; e < aoff[v + 1]; ++e) {
          const double* a = &prob_.anchors()[std::size_t(prob_.anchor_ids()[e]) * P];
          double s = 0, z2 = 0;
          for (int k = 0; k < P; ++k) {
            const double z = x[std::size_t(v) * P + k] - a[k], r = z - w[std::size_t(e) * P + k];
            s += r * r;
            z2 += z * z;
          }
          const double m = std::sqrt(z2) - prob_.anchor_ranges()[e];
          put(0, 0.5 * s, 0.5 * m * m);
        }
    }
    if (!Exact) flush();
    for (int L = 0; L < C; ++L) {
      F[0].add(accF[L]);
      F[1].add(accf[L]);
    }
  }

  LocalizationProblem& prob_;
  double L_;
  std::shared_ptr<const detail::NodeLanes> lanes_;  // the phases share one (detail::shared_lanes)
  std::vector<double> norms_;  // the kernel's per-lane norms (unused: the solver sums the change itself)
  std::vector<double> block_F_, block_f_;  // terms_and_step: a block's edge sums (EdgeSums)
  std::vector<unsigned> block_any_;
};

// Weights and/or Huber: ModelMM's step and surrogate (model_mm.hpp); y per
// CSR slot; a chunk is one owned node (the interior ones first).
class ModelCore {
 public:
  explicit ModelCore(LocalizationProblem& prob) : prob_(prob), k_(prob) {}
  double lipschitz() const { return k_.lipschitz(); }
  std::size_t y_size() const { return prob_.graph().adjacency().size() * prob_.dim(); }
  std::size_t y_index(LocalId, std::int64_t e, int c) const { return std::size_t(e) * prob_.dim() + c; }
  std::int64_t chunks() const { return prob_.num_owned(); }
  std::int64_t split() const { return prob_.graph().num_interior(); }
  std::int64_t bytes() const { return k_.bytes(); }
  void init(const double* x, double* y, double* w) const { k_.init(x, y, w); }
  static constexpr bool kExtrapolates = false;  // MMAccel blends into buffers
  void step(const StepArgs& a) { k_.step(a.v, a.xout, a.y, a.w, nullptr, nullptr); }
  // The terms of chunks [c0, c1), and with the boundary part (the second
  // call of a pass, its input rows complete only then) the step over every
  // node: one node at a time, no cache blocking to gain.
  void terms_and_step(const double* x, const double* y, const double* w, std::int64_t c0, std::int64_t c1,
                      detail::ExactSum* F, bool, const StepArgs& a, bool boundary) {
    add_terms(x, y, w, c0, c1, F);
    if (boundary) step(a);
  }
  void add_terms(const double* x, const double* y, const double* w, std::int64_t c0, std::int64_t c1,
                 detail::ExactSum* F) const {
    k_.terms(x, y, w, LocalId(c0), LocalId(c1), &F[0], &F[1]);
  }
  static constexpr bool kPlainSums = false;  // every test by the exact sums
  void add_terms_plain(const double* x, const double* y, const double* w, std::int64_t c0, std::int64_t c1,
                       detail::ExactSum* F) const {
    add_terms(x, y, w, c0, c1, F);
  }
  double plain_block_adds() const { return 0; }

 private:
  LocalizationProblem& prob_;
  detail::ModelMMKernel k_;
};

template <class Core>
class MMAccel final : public Algorithm {
 public:
  explicit MMAccel(LocalizationProblem& prob) : prob_(prob), core_(prob) {}
  std::string name() const override { return algorithm_info(AlgorithmId::kMMAccel).name; }
  double lipschitz() const override { return core_.lipschitz(); }
  double reals_per_iteration() const override { return prob_.dim(); }

  void start(const std::vector<double>& x0) override {
    // Plain sums where the exact adds cost (a tenth of an iteration at
    // scale); below 10,000 sensors the solver records every iteration, which
    // needs F exactly anyway. SNL_TEST_ACCEPT=plain|exact: tests choose.
    const char* choice = std::getenv("SNL_TEST_ACCEPT");
    plain_ = Core::kPlainSums && (choice ? std::strcmp(choice, "plain") == 0 : prob_.num_sensors() >= 10000);
    for (auto& b : x_) b.clear();
    for (int b = 0; b < (Core::kExtrapolates ? kV : kV + 1); ++b) x_[b].assign(std::size_t(prob_.num_local()) * prob_.dim(), 0.0);
    std::copy(x0.begin(), x0.begin() + std::size_t(prob_.num_owned()) * prob_.dim(), x_[kCur].begin());
    prob_.graph().halo().exchange(x_[kCur].data(), prob_.dim());
    x_[kPrev] = x_[kCur];
    for (auto& b : y_) b.assign(core_.y_size(), 0.0);
    for (auto& b : w_) b.assign(prob_.anchor_ranges().size() * prob_.dim(), 0.0);
    init_for_dim();
    y_[kPrev] = y_[kCur];
    w_[kPrev] = w_[kCur];
    t_ = 0;
    rejected_ = 0;
    cur_ = surrogate(kCur, true);
    candidate();
  }

  // The candidate z+ (made from z(k) by the last iteration, or by start(),
  // load() or a restart) is accepted or rejected. One pass exchanges its
  // rows, sums F(z+) and f(x+), and takes the next step from z+'s
  // extrapolation as if z+ were accepted (the step the next iteration would
  // take then), reading z+'s edge variables once for both; a rejection
  // discards that step and makes a plain one from z(k).
  void iterate() override {
    const bool tested = t_ > 0;  // z+ came from an extrapolated point (a plain step is always accepted)
    Costs c = pass(double(t_ + 1) / double(t_ + 4));  // beta_t of the next step, t = t_ + 1
    if (tested && !accepts(c)) {  // F or f would rise: keep x(k), restart
      ++rejected_;
      restart();
      return;
    }
    // z(k+1) = z+, z(k) becomes the previous point, the pass's step the candidate.
    std::swap(x_[kPrev], x_[kCur]);
    std::swap(x_[kCur], x_[kOut]);
    std::swap(x_[kOut], x_[kNext]);
    for (auto* b : {&y_, &w_}) {  // the step wrote the spare (z(k-1)'s) buffer
      std::swap((*b)[kPrev], (*b)[kCur]);
      std::swap((*b)[kCur], (*b)[kOut]);
    }
    cur_ = c;
    ++t_;
  }

  const std::vector<double>& positions() const override { return x_[kCur]; }
  // The last accepted step's change (an iteration that rejected its step leaves it as it was).
  const double* previous_positions() const override { return x_[kPrev].data(); }
  void change_norms(double* d, double* s) const override {
    detail::diff_norms(prob_, x_[kCur].data(), x_[kPrev].data(), d, s);
  }
  // F(z(k)) exactly (the same for any partition), summed again if the
  // iteration's test settled on the plain sums.
  double objective() override {
    if (!cur_.exact) cur_ = exact_costs(kCur);
    return cur_.F;
  }
  std::int64_t memory_bytes() const override {
    std::size_t n = 0;
    for (const auto& b : x_) n += b.capacity();
    for (const auto& b : y_) n += b.capacity();
    for (const auto& b : w_) n += b.capacity();
    return static_cast<std::int64_t>(sizeof(double) * n) + core_.bytes();
  }
  void report(std::vector<std::pair<std::string, double>>* values,
              std::vector<std::pair<std::string, std::string>>*) const override {
    values->emplace_back("rejected_steps", double(rejected_));
  }
  // z(k), z(k-1) and the steps since the restart: the candidate, and so every
  // later iterate, follows from them. (After a rejection, t = 0 and z(k-1)'s
  // edge and anchor variables are not read again.)
  void save(StateWriter& w) const override {
    const int p = prob_.dim();
    w.scalar("t", double(t_));
    w.scalar("rejected_steps", double(rejected_));
    w.node_rows("x", x_[kCur].data(), p);
    w.node_rows("x_prev", x_[kPrev].data(), p);
    w.edge_rows("y", p, [&](LocalId v, std::int64_t e, int c) { return y_[kCur][y_index(v, e, c)]; });
    w.edge_rows("y_prev", p, [&](LocalId v, std::int64_t e, int c) { return y_[kPrev][y_index(v, e, c)]; });
    w.anchor_rows("w", w_[kCur].data(), p);
    w.anchor_rows("w_prev", w_[kPrev].data(), p);
  }
  void load(const StateReader& r) override {
    const int p = prob_.dim();
    t_ = static_cast<std::int64_t>(r.scalar("t"));
    rejected_ = static_cast<std::int64_t>(r.scalar("rejected_steps"));
    r.node_rows("x", x_[kCur].data(), p);
    r.node_rows("x_prev", x_[kPrev].data(), p);
    r.edge_rows("y", p, [&](LocalId v, std::int64_t e, int c, double y) { y_[kCur][y_index(v, e, c)] = y; });
    r.edge_rows("y_prev", p, [&](LocalId v, std::int64_t e, int c, double y) { y_[kPrev][y_index(v, e, c)] = y; });
    r.anchor_rows("w", w_[kCur].data(), p);
    r.anchor_rows("w_prev", w_[kPrev].data(), p);
    prob_.graph().halo().exchange(x_[kPrev].data(), p);
    cur_ = surrogate(kCur, true);  // exchanges x's ghost rows; F and f are functions of z(k)
    candidate();
  }

 private:
  // The surrogate F(z) and the ML cost f(x), exact or from plain block sums
  // (Core::add_terms_plain) within eF and ef of the exact sums.
  struct Costs {
    double F = 0, f = 0;
    double eF = 0, ef = 0;
    bool exact = true;
  };

  // The acceptance test F(z+) <= F(z(k)) and f(x+) <= f(x(k)) on the exact
  // sums, as every partition takes it. The plain sums settle it unless one
  // comparison falls within their bounds; then z+ and z(k) are summed exactly
  // (a pass more, rarely: the bounds are about 1e-13 of the costs).
  bool accepts(Costs& c) {
    auto le = [](double a, double ea, double b, double eb) {  // 1: a <= b, 0: a > b, -1: not settled
      if (a + ea <= b - eb) return 1;
      if (a - ea > b + eb) return 0;
      return -1;  // also NaN and inf
    };
    if (c.exact && cur_.exact) return c.F <= cur_.F && c.f <= cur_.f;
    const int dF = le(c.F, c.eF, cur_.F, cur_.eF), df = le(c.f, c.ef, cur_.f, cur_.ef);
    if (dF == 0 || df == 0) return false;
    if (dF == 1 && df == 1) return true;
    c = exact_costs(kOut);  // x+'s ghost rows were exchanged by pass()
    if (!cur_.exact) cur_ = exact_costs(kCur);
    return c.F <= cur_.F && c.f <= cur_.f;
  }

  // The momentum restart: t = 0 and (y, w) of z(k) reset to their best values
  // for x(k) (x(k)'s ghost rows are those exchanged when it was computed), so
  // that the next, plain, step lowers f as well as F. F is summed again (one
  // reduction, no halo message).
  void restart() {
    t_ = 0;
    init_for_dim();
    cur_ = exact_costs(kCur);
    candidate();
  }

  // Collective: F and f of z in buffers b exactly, x_[b]'s ghost rows as they are.
  Costs exact_costs(int b) {
    detail::ExactSum sums[2];
    core_.add_terms(x_[b].data(), y_[b].data(), w_[b].data(), 0, core_.chunks(), sums);
    return finish(sums, true);
  }

  // x_: z(k), z(k-1), the candidate z+, the pass's step, and (cores that do
  // not extrapolate x themselves) the extrapolated rows. y_, w_: z(k), z(k-1),
  // z+; the pass's step writes z(k-1)'s, which an accepted z+ frees.
  enum { kCur = 0, kPrev = 1, kOut = 2, kNext = 3, kV = 4 };

  // blend(a, b) = a + beta (a - b) over [i0, i1), the same arithmetic the
  // kernels use where they extrapolate on the fly.
  static void blend(const double* a, const double* b, double beta, double* out, std::size_t i0, std::size_t i1) {
    for (std::size_t i = i0; i < i1; ++i) out[i] = a[i] + beta * (a[i] - b[i]);
  }

  // The candidate from z(k) alone (no collective): a plain MM step (t = 0),
  // or the step from the extrapolation with beta_t = t / (t + 3) of z(k) and
  // z(k-1) (load(): the candidate the interrupted run had made). Either way
  // the same bits as pass()'s step.
  void candidate() {
    if (t_ == 0) {
      y_[kOut] = y_[kCur];
      w_[kOut] = w_[kCur];
      core_.step({x_[kCur].data(), x_[kOut].data(), y_[kOut].data(), w_[kOut].data()});
      return;
    }
    const double beta = double(t_) / double(t_ + 3);
    blend(w_[kCur].data(), w_[kPrev].data(), beta, w_[kOut].data(), 0, w_[kOut].size());
    core_.step(extrapolated(kCur, kPrev, kOut, beta, 0, x_[kCur].size()));
  }

  // The step from z_a + beta (z_a - z_b) into x_[out] and the (y, w) buffers
  // `out` (w there already blended): the kernel extrapolates x's rows [r0, r1)
  // and y itself, or they are blended here into x_[kV] and y_[out] first.
  StepArgs extrapolated(int a, int b, int out, double beta, std::size_t r0, std::size_t r1) {
    const int xo = out == kOut ? kOut : kNext;
    StepArgs st{x_[a].data(), x_[xo].data(), y_[out].data(), w_[out].data()};
    if (Core::kExtrapolates) {
      st.ya = y_[a].data();
      st.yb = y_[b].data();
      st.xb = x_[b].data();
      st.beta = beta;
      return st;
    }
    blend(x_[a].data(), x_[b].data(), beta, x_[kV].data(), r0, r1);
    if (r0 == 0) blend(y_[a].data(), y_[b].data(), beta, y_[out].data(), 0, y_[out].size());
    st.v = x_[kV].data();
    return st;
  }

  // Collective, the iteration's message: exchange x+'s ghost rows; F(z+) and
  // f(x+) (plain sums with bounds where plain_); the step from the point
  // z+ + beta (z+ - z(k)) into x_[kNext] and z(k-1)'s (y, w). The interior
  // chunks (no ghost row read, by the cost terms or the step) overlap the
  // exchange.
  Costs pass(double beta) {
    const bool exact = !plain_;
    const int p = prob_.dim();
    const std::size_t no = std::size_t(prob_.num_owned()) * p, nl = x_[kOut].size();
    HaloPlan& halo = prob_.graph().halo();
    blend(w_[kOut].data(), w_[kCur].data(), beta, w_[kPrev].data(), 0, w_[kPrev].size());
    halo.begin(x_[kOut].data(), p);
    StepArgs st = extrapolated(kOut, kCur, kPrev, beta, 0, no);
    detail::ExactSum sums[2];
    core_.terms_and_step(x_[kOut].data(), y_[kOut].data(), w_[kOut].data(), 0, core_.split(), sums, exact, st,
                         false);
    halo.end(x_[kOut].data(), p);
    st = extrapolated(kOut, kCur, kPrev, beta, no, nl);
    core_.terms_and_step(x_[kOut].data(), y_[kOut].data(), w_[kOut].data(), core_.split(), core_.chunks(), sums,
                         exact, st, true);
    return finish(sums, exact);
  }

  std::size_t y_index(LocalId v, std::int64_t e, int c) const { return core_.y_index(v, e, c); }

  // (y, w) of z(k) at their best values for x(k), where F = f.
  void init_for_dim() { core_.init(x_[kCur].data(), y_[kCur].data(), w_[kCur].data()); }

  // Collective: F at (x_[b], y_[b], w_[b]) (000, eq. 2) and f at x_[b] (the
  // ML cost, the same terms as evaluate_costs), after exchanging x_[b]'s
  // ghost rows; the interior chunks' terms overlap the exchange.
  Costs surrogate(int b, bool exact) {
    exact = exact || !plain_;
    HaloPlan& halo = prob_.graph().halo();
    detail::ExactSum sums[2];
    halo.begin(x_[b].data(), prob_.dim());
    add_surrogate_terms(b, 0, core_.split(), sums, exact);
    halo.end(x_[b].data(), prob_.dim());
    add_surrogate_terms(b, core_.split(), core_.chunks(), sums, exact);
    return finish(sums, exact);
  }
  void add_surrogate_terms(int b, std::int64_t c0, std::int64_t c1, detail::ExactSum* F, bool exact) const {
    if (exact)
      core_.add_terms(x_[b].data(), y_[b].data(), w_[b].data(), c0, c1, F);
    else
      core_.add_terms_plain(x_[b].data(), y_[b].data(), w_[b].data(), c0, c1, F);
  }
  // Collective: the ranks' sums combined exactly. Plain sums carry their
  // bounds, 2 (m + 2) u of the sum (every term is >= 0) and 2^-1000 for
  // subnormal terms.
  Costs finish(detail::ExactSum* sums, bool exact) {
    detail::allreduce_exact(sums, 2, prob_.comm());
    Costs c;
    c.F = sums[0].value();
    c.f = sums[1].value();
    if (!exact) {
      const double r = 2.0 * (core_.plain_block_adds() + 2.0) * 0x1p-53;
      c.eF = r * c.F + 0x1p-1000;
      c.ef = r * c.f + 0x1p-1000;
      c.exact = false;
    }
    return c;
  }

  LocalizationProblem& prob_;
  Core core_;
  std::array<std::vector<double>, 5> x_;      // see the enum above
  std::array<std::vector<double>, 3> y_, w_;  // z(k), z(k-1), z+; y_ in lane layout
  std::int64_t t_ = 0;         // steps accepted since the last restart
  std::int64_t rejected_ = 0;  // candidates rejected (each one a restart)
  Costs cur_;                  // F(z(k)), f(x(k))
  bool plain_ = false;         // acceptance tests on plain sums first (start())
};

}  // namespace

namespace detail {

std::unique_ptr<Algorithm> make_mm_accel(LocalizationProblem& prob, const SolverOptions&) {
  if (prob.model().active()) return std::make_unique<MMAccel<ModelCore>>(prob);  // weights or Huber
  return std::make_unique<MMAccel<LaneCore>>(prob);
}

}  // namespace detail

}  // namespace snl
