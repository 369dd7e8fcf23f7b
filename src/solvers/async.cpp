// The asynchronous method of 003 (Algorithm 2), run in parallel with exactly
// its sequential semantics (so results are bit-identical for any rank count):
// node activations xi_k drawn uniformly (eq. 21) from a counter-based
// generator, so every rank knows the whole sequence. Inexact version (async):
// one step x_i <- x_i - grad_i f_hat / L (eq. 20); exact version (async-exact):
// minimise f_i(v) = sum_j 1/2 d_B(d_ij)(v - x_j)^2 + sum_k 1/2 d_B(r_ik)(v - a_k)^2
// by Nesterov's method (Algorithm 3) with the spec's weight 1/2 (003's eq. 19
// has 1/4, a slip) and L_i = delta_i + |A_i|.
// One iteration = n activations (one message per activation: 1 per sensor).
//
// The replay (docs/design.md, "The asynchronous replay"): each rank lists the
// activations of its local nodes (owned and ghost) among the iteration's n and
// applies its own in passes over that list, in order, as a dataflow: an owned
// activation at k runs once every earlier activation of the node and of its
// neighbours is done (for a ghost neighbour: received, its row's version,
// the position of its last activation applied, reaching that activation);
// otherwise it waits and so do the later ones that touch it (the pass taints
// the node). Between passes the ranks exchange, neighbour to neighbour, the
// rows changed since the last exchange with their versions (DeltaHalo). An
// activation thus reads exactly the rows it reads in the sequential order:
// none is too old (every earlier activation it depends on is done) and none
// too new (a later activation of a neighbour waits for this one, on whichever
// rank it runs). The earliest activation not done can always run, so every
// round makes progress; the rounds an iteration takes are the cross-rank
// links of the longest chain of dependent activations, not the activations.
#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <thread>

#include "snl/core/mpi_util.hpp"
#include "snl/core/random.hpp"
#include "snl/core/stop_signal.hpp"
#include "snl/graph/delta_halo.hpp"
#include "snl/graph/free_halo.hpp"
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

// The gradient of f_i at v under the unweighted l2 model (eq. 20's step), the
// terms of local_cost_grad without its cost and without a branch: a term
// outside the disk adds a (v - c) as there; one inside adds +0.0, which leaves
// the sum's bits as they are (the sum starts at +0.0 and so is never -0.0),
// so the result is local_cost_grad's, bit for bit (tests/mpi/test_pm_async_mpi).
template <int P>
void l2_grad(const LocalizationProblem& prob, const double* x, LocalId i, const double* v, double* gout) {
  const auto& gr = prob.graph();
  const auto* adj = gr.adjacency().data();
  const double* ev = gr.edge_values().data();
  const std::int64_t w = gr.edge_width();
  double g[P];
  for (int k = 0; k < P; ++k) g[k] = 0;
  // The terms of up to kChunk neighbours at a time: first each term on its
  // own (no dependence between them, so the square roots and divisions
  // overlap or go two to a vector), then their sum in slot order.
  constexpr int kChunk = 16;
  double d[P][kChunk], rho[kChunk], t[P][kChunk];
  auto chunk = [&](int m) {
    double nz[kChunk], a[kChunk];
    for (int j = 0; j < m; ++j) {
      double s = 0;
      for (int k = 0; k < P; ++k) s += d[k][j] * d[k][j];
      nz[j] = std::sqrt(s);
    }
    for (int j = 0; j < m; ++j) a[j] = 1.0 - rho[j] / nz[j];
    // All bits of the term outside the disk, else +0.0 (a mask, not a branch).
    for (int j = 0; j < m; ++j) {
      const std::uint64_t mask = std::uint64_t(0) - std::uint64_t(nz[j] > rho[j]);
      for (int k = 0; k < P; ++k) {
        const double tv = a[j] * d[k][j];
        std::uint64_t b;
        std::memcpy(&b, &tv, sizeof b);
        b &= mask;
        std::memcpy(&t[k][j], &b, sizeof b);
      }
    }
    for (int j = 0; j < m; ++j)
      for (int k = 0; k < P; ++k) g[k] += t[k][j];
  };
  const auto e0 = gr.offsets()[i], e1 = gr.offsets()[i + 1];
  for (auto e = e0; e < e1; e += kChunk) {
    const int m = static_cast<int>(std::min<std::int64_t>(kChunk, e1 - e));
    for (int j = 0; j < m; ++j) {
      const double* c = x + std::size_t(adj[e + j]) * P;
      for (int k = 0; k < P; ++k) d[k][j] = v[k] - c[k];
      rho[j] = ev[(e + j) * w];
    }
    chunk(m);
  }
  const double* anc = prob.anchors().data();
  const auto a0 = prob.anchor_offsets()[i], a1 = prob.anchor_offsets()[i + 1];
  for (auto e = a0; e < a1; e += kChunk) {
    const int m = static_cast<int>(std::min<std::int64_t>(kChunk, a1 - e));
    for (int j = 0; j < m; ++j) {
      const double* c = anc + std::size_t(prob.anchor_ids()[e + j]) * P;
      for (int k = 0; k < P; ++k) d[k][j] = v[k] - c[k];
      rho[j] = prob.anchor_ranges()[e + j];
    }
    chunk(m);
  }
  for (int k = 0; k < P; ++k) gout[k] = g[k];
}

// ---------------------------------------------------------------------------
class Async final : public Algorithm {
 public:
  Async(LocalizationProblem& prob, const SolverOptions& opt, bool exact)
      : prob_(prob),
        exact_(exact),
        free_(opt.mode == "free"),
        gradient_rule_(opt.stop == "gradient"),
        tol_(opt.stop_tol()),
        target_(opt.target_cost),
        straggler_delay_(comm_rank(prob.comm()) == straggler_rank(opt, prob.comm()) ? opt.straggler_delay : 0.0),
        seed_(opt.seed),
        L_(relaxation_lipschitz(prob)) {}
  bool free_running() const override { return free_; }
  std::int64_t levels_run() const override { return levels_run_; }
  std::string name() const override {
    return algorithm_info(exact_ ? AlgorithmId::kAsyncExact : AlgorithmId::kAsync).name;
  }
  double lipschitz() const override { return L_; }
  double reals_per_iteration() const override { return prob_.dim(); }

  void start(const std::vector<double>& x0) override {
    x_ = with_ghosts(prob_, x0);
    auto& g = prob_.graph();
    g.halo().exchange(x_.data(), prob_.dim());
    // Global id -> local id (-1: not local): 4 bytes per sensor on every rank,
    // as every rank reads the whole activation sequence (n draws per iteration).
    g2l_.assign(std::size_t(prob_.num_sensors()), -1);
    for (LocalId v = 0; v < g.num_local(); ++v) g2l_[std::size_t(g.global_id(v))] = v;
    version_.assign(std::size_t(g.num_local()), -1);
    taint_.assign(std::size_t(g.num_local()), 0);
    prev_.assign(std::size_t(g.num_owned()) * prob_.dim(), 0.0);
    k_ = 0;
    if (free_) {
      // Free mode: no activation sequence to replay, no per-node versions.
      g2l_ = {};
      version_ = {};
      taint_ = {};
      free_halo_ = FreeHalo(g.halo(), prob_.dim());
      red_comm_ = DupComm(prob_.comm());
      rank_ = comm_rank(prob_.comm());
      return;
    }
    delta_ = DeltaHalo(g.halo(), prob_.dim());
    const std::size_t expect = std::size_t(g.num_local()) + std::size_t(g.num_local()) / 4 + 64;
    acts_.clear();
    acts_.reserve(expect);
  }

  void iterate_levels(int n) override {
    if (free_) {
      free_run(n);
      return;
    }
    for (int j = 0; j < n; ++j) iterate();
  }

  void iterate() override {
    if (free_) {
      free_run(1);
      return;
    }
    auto& g = prob_.graph();
    const GlobalId n = prob_.num_sensors();
    std::copy(x_.begin(), x_.begin() + prev_.size(), prev_.begin());
    const std::int64_t round_end = k_ + n;
    // This iteration's activations of local nodes, in order.
    acts_.clear();
    for (std::int64_t k = k_; k < round_end; ++k) {
      const LocalId l = g2l_[std::size_t(activation(k))];
      if (l >= 0) acts_.push_back({k, l});
    }
    delta_.reset(0, 1);
    const LocalId n_owned = g.num_owned(), n_interior = g.num_interior();
    const auto* off = g.offsets().data();
    const auto* adj = g.adjacency().data();
    // Passes over the activations not done, in order; each pass keeps (in
    // place, at the front of acts_) those still waiting: an owned one not
    // applied, a ghost's whose row has not arrived.
    std::size_t left = acts_.size();
    std::int64_t rounds = 0;
    for (;;) {
      // taint_[v] == pass_: v has an earlier activation not done in this pass.
      if (++pass_ == 0) {  // wrapped: clear the stamps
        std::fill(taint_.begin(), taint_.end(), 0u);
        pass_ = 1;
      }
      bool tainted = false;
      std::size_t kept = 0, owned_left = 0;
      for (std::size_t t = 0; t < left; ++t) {
        prefetch(t, left);
        const Act a = acts_[t];
        const LocalId v = a.node;
        if (v >= n_owned) {  // a ghost's activation: done once its owner's row of version >= k arrived
          if (version_[v] < a.k) {
            taint_[v] = pass_;
            tainted = true;
            acts_[kept++] = a;
          }
          continue;
        }
        bool ready = !tainted || taint_[v] != pass_;
        for (auto e = off[v]; e < off[v + 1] && ready && tainted; ++e) ready = taint_[adj[e]] != pass_;
        if (ready) {
          activate(v);
          if (v >= n_interior) {
            version_[v] = a.k;
            if (!drop_row(v)) delta_.mark(v);
          }
        } else {
          taint_[v] = pass_;
          tainted = true;
          acts_[kept++] = a;
          ++owned_left;
        }
      }
      left = kept;
      if (delta_.done()) break;
      // Every round runs the earliest activation not done (on some rank), so
      // an iteration takes at most n + 1 rounds: more means a row was lost,
      // which would otherwise leave the ranks exchanging forever.
      if (++rounds > n + 1)
        throw std::runtime_error("async: the replay waited " + std::to_string(rounds) +
                                 " rounds for rows that never came (a row was lost), at activation " +
                                 std::to_string(k_));
      // Clock 1: this rank has done all its activations.
      delta_.exchange(x_.data(), version_.data(), owned_left == 0 ? 1 : 0);
    }
    // Left: at most ghosts' activations whose rows came in the last exchange.
    // (Rank-local, so not an agreed snl::Error: the Solver aborts every rank.)
    for (std::size_t t = 0; t < left; ++t)
      if (acts_[t].node < n_owned || version_[acts_[t].node] < acts_[t].k)
        throw std::runtime_error("async: the replay stopped before the end of its activations (a row was lost)");
    k_ = round_end;
    diff_norms(prob_, x_.data(), prev_.data(), &diff_sq_, &x_sq_);
  }

  // Free mode (docs/async.md): each rank activates its own nodes, drawn
  // uniformly among them from its own stream, on its own clock, up to
  // `levels` times n_own activations; changed boundary rows go out with
  // nonblocking messages (FreeHalo) and come in whenever they arrive. The
  // stopping test: at the end of each of its epochs (n_own activations) a
  // rank has the epoch's sum of squared gradients and steps and its part of
  // f_hat and ||x||^2; it contributes the latest to a nonblocking reduction
  // (MPI_Iallreduce, one in flight, polled), whose result every rank reads
  // alike, so all stop after the same reduction: when every rank has an epoch
  // and the estimate meets the tolerance, when every rank has used its
  // budget, on a stop signal or when a rank failed. Then the halo session is
  // closed (every ghost row its owner's final value, no message in flight).
  void free_run(int levels) {
    auto& g = prob_.graph();
    const LocalId n_own = g.num_owned(), n_interior = g.num_interior();
    const int size = comm_size(red_comm_.get());
    free_halo_.open();
    std::int64_t epochs = 0, in_epoch = 0;
    double G = 0, D = 0;               // the current epoch's sums of ||g||^2 and ||step||^2
    double last[4] = {0, 0, 0, 0};     // the last complete epoch's G, f_hat part, D, ||x||^2
    bool budget_done = n_own == 0, failed = false, stop = false, fresh = false, red_active = false;
    std::string fail_msg;
    double red_in[8], red_out[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    MPI_Request red = MPI_REQUEST_NULL;
    const std::uint64_t stream_seed = mix64(seed_ ^ mix64(0x5851f42d4c957f2dULL * std::uint64_t(rank_ + 1)));
    std::string why;
    while (!stop) {
      if (!budget_done && !failed) {
        const std::int64_t m = std::min<std::int64_t>(kChunk, n_own - in_epoch);
        try {
          if (in_epoch == 0) test_fail_point("async-free", epochs_total_ + 1);  // fault-injection tests
          // The chunk's nodes drawn first, so that their rows are fetched ahead (prefetch_node).
          LocalId ids[kChunk];
          for (std::int64_t j = 0; j < m; ++j) {
            const double u = uniform01(stream_seed, RngStream::kAsyncClock, draws_++);
            ids[j] = std::min<LocalId>(static_cast<LocalId>(u * double(n_own)), n_own - 1);
          }
          for (std::int64_t j = 0; j < std::min<std::int64_t>(m, kFreeAhead); ++j) prefetch_node(ids[j], 1);
          for (std::int64_t j = 0; j < m; ++j) {
            if (j + 2 * kFreeAhead < m) prefetch_node(ids[j + 2 * kFreeAhead], 0);
            if (j + kFreeAhead < m) prefetch_node(ids[j + kFreeAhead], 1);
            const LocalId v = ids[j];
            double g2 = 0, s2 = 0;
            activate(v, &g2, &s2);
            G += g2;
            D += s2;
            if (v >= n_interior) free_halo_.mark(v);
          }
        } catch (const std::exception& e) {
          failed = true;
          fail_msg = "rank " + std::to_string(rank_) + ": " + e.what() + " (in the free asynchronous loop)";
        }
        in_epoch += m;
        if (!failed && in_epoch == n_own) {  // an epoch ends
          last[0] = G;
          last[2] = D;
          owned_cost_norm(&last[1], &last[3]);
          G = D = 0;
          in_epoch = 0;
          ++epochs;
          ++epochs_total_;
          fresh = true;
          if (epochs == levels) budget_done = true;
          if (straggler_delay_ > 0) std::this_thread::sleep_for(std::chrono::duration<double>(straggler_delay_));
        }
        free_halo_.flush(x_.data());
      } else {
        std::this_thread::sleep_for(std::chrono::microseconds(20));  // idle: leave the core to the others
      }
      free_halo_.poll(x_.data());
      if (red_active) {
        int done = 0;
        MPI_Test(&red, &done, MPI_STATUS_IGNORE);
        if (done) {
          red_active = false;
          stop = decide(red_out, size, &why);
        }
      }
      if (!stop && !red_active && (fresh || budget_done || failed)) {
        red_in[0] = last[0];
        red_in[1] = last[1];
        red_in[2] = last[2];
        red_in[3] = last[3];
        red_in[4] = (epochs > 0 || n_own == 0) ? 1 : 0;  // this rank has a complete epoch in this pass
        red_in[5] = budget_done ? 1 : 0;
        red_in[6] = failed ? 1 : 0;
        red_in[7] = stop_signal_received() ? 1 : 0;
        MPI_Iallreduce(red_in, red_out, 8, MPI_DOUBLE, MPI_SUM, red_comm_.get(), &red);
        red_active = true;
        fresh = false;
      }
    }
    free_halo_.close(x_.data());
    // Outside the loop (every rank is here): the iterations run, a failure.
    long long mine[2] = {epochs, -epochs}, most[2] = {0, 0};
    MPI_Allreduce(mine, most, 2, MPI_LONG_LONG, MPI_MAX, red_comm_.get());
    levels_run_ = most[0];
    fewest_total_ += -most[1];
    most_total_ += most[0];
    levels_total_ += most[0];
    k_ = levels_total_ * prob_.num_sensors();  // the clock a checkpoint records
    diff_sq_ = last[2];
    x_sq_ = last[3];
    if (red_out[6] > 0) agree(red_comm_.get(), failed ? fail_msg : std::string());
  }

  // Free mode's fetch ahead: stage 0 the node's offsets, stage 1 its neighbour list, ranges and rows.
  static constexpr std::int64_t kFreeAhead = 8;
  void prefetch_node(LocalId v, int stage) const {
    const auto& g = prob_.graph();
    if (stage == 0) {
      __builtin_prefetch(&g.offsets()[v]);
      __builtin_prefetch(&prob_.anchor_offsets()[v]);
      __builtin_prefetch(&x_[std::size_t(v) * prob_.dim()]);
      return;
    }
    const auto e0 = g.offsets()[v], e1 = g.offsets()[v + 1];
    const auto w = g.edge_width();
    __builtin_prefetch(&g.edge_values()[e0 * w]);
    __builtin_prefetch(&g.edge_values()[e0 * w] + 8);
    const int p = prob_.dim();
    for (auto e = e0; e < e1; ++e) __builtin_prefetch(&x_[std::size_t(g.adjacency()[e]) * p]);
  }

  // The reduced epoch sums -> stop? (the same answer on every rank).
  bool decide(const double* r, int size, std::string* why) const {
    if (r[6] > 0) return *why = "failure", true;
    if (r[7] > 0) return *why = "signal", true;
    if (r[4] >= size && target_ > 0 && r[1] <= target_) return *why = "target", true;
    if (r[4] >= size && tol_ > 0) {
      const double est = gradient_rule_ ? (r[1] > 0 ? std::sqrt(r[0]) / (2.0 * std::sqrt(r[1])) : std::sqrt(r[0]))
                                        : (r[3] > 0 ? std::sqrt(r[2] / r[3]) : std::sqrt(r[2]));
      if (est <= tol_) return *why = "converged", true;
    }
    if (r[5] >= size) return *why = "budget", true;
    return false;
  }

  // This rank's part of f_hat (each sensor pair halved between its ends) and ||x||^2, over owned rows.
  void owned_cost_norm(double* f, double* xs) const {
    const int p = prob_.dim();
    const auto& gr = prob_.graph();
    const MeasurementModel& mo = prob_.model();
    double fs = 0, ss = 0;
    for (LocalId i = 0; i < gr.num_owned(); ++i) {
      const double* v = &x_[std::size_t(i) * p];
      auto term = [&](const double* c, double rho, double w) {
        double q = 0;
        for (int k = 0; k < p; ++k) q += (v[k] - c[k]) * (v[k] - c[k]);
        const double nz = std::sqrt(q);
        if (nz <= rho) return 0.0;
        return mo.active() ? w * loss_value(mo.huber_delta, nz - rho) : 0.5 * (nz - rho) * (nz - rho);
      };
      for (auto e = gr.offsets()[i]; e < gr.offsets()[i + 1]; ++e)
        fs += 0.5 * term(&x_[std::size_t(gr.adjacency()[e]) * p], gr.edge_value(e), mo.edge_weight(e));
      for (auto e = prob_.anchor_offsets()[i]; e < prob_.anchor_offsets()[i + 1]; ++e)
        fs += term(prob_.anchors().data() + std::size_t(prob_.anchor_ids()[e]) * p, prob_.anchor_ranges()[e],
                   mo.anchor_weight(e));
      for (int k = 0; k < p; ++k) ss += v[k] * v[k];
    }
    *f = fs;
    *xs = ss;
  }

  // Test hook (SNL_TEST_ASYNC_DROP_ROW=<rank>): that rank never sends the
  // rows of its first boundary node activated in the second iteration (a lost
  // message; the replay must end with an error, not wait forever).
  bool drop_row(LocalId v) {
    static const int drop_rank = [] {
      const char* e = std::getenv("SNL_TEST_ASYNC_DROP_ROW");
      return e && *e ? std::atoi(e) : -1;
    }();
    if (drop_rank < 0 || k_ != prob_.num_sensors()) return false;
    if (comm_rank(prob_.comm()) != drop_rank) return false;
    if (dropped_ < 0) dropped_ = v;
    return v == dropped_;
  }

  const std::vector<double>& positions() const override { return x_; }
  double objective() override {
    prob_.graph().halo().exchange(x_.data(), prob_.dim());
    return evaluate_costs(prob_, x_.data()).relaxed;
  }
  // Free mode: the change norms of the last complete epoch (steps summed), no x(k-1).
  const double* previous_positions() const override { return free_ ? nullptr : prev_.data(); }
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
    // Free mode: the clock in epochs; each rank's stream continues past the draws of every epoch so far.
    levels_total_ = epochs_total_ = k_ / std::max<GlobalId>(1, prob_.num_sensors());
    draws_ = std::uint64_t(epochs_total_) * std::uint64_t(prob_.graph().num_owned());
    r.node_rows("x", x_.data(), prob_.dim());
    prob_.graph().halo().exchange(x_.data(), prob_.dim());
  }
  // Free mode: how far the ranks drifted apart (the iterations reported are the fastest rank's).
  void report(std::vector<std::pair<std::string, double>>* values,
              std::vector<std::pair<std::string, std::string>>* texts) const override {
    if (!free_) return;
    values->emplace_back("free_epochs_fastest_rank", double(most_total_));
    values->emplace_back("free_epochs_slowest_rank", double(fewest_total_));
    texts->emplace_back("async_mode", "free");
  }
  std::int64_t bytes_sent() const override { return free_ ? free_halo_.bytes_sent() : delta_.bytes_sent(); }
  std::int64_t memory_bytes() const override {
    return static_cast<std::int64_t>((x_.capacity() + prev_.capacity()) * sizeof(double) +
                                     g2l_.capacity() * sizeof(LocalId) + version_.capacity() * sizeof(std::int64_t) +
                                     taint_.capacity() * sizeof(std::uint32_t) + acts_.capacity() * sizeof(Act)) +
           delta_.memory_bytes() + free_halo_.memory_bytes();
  }

 private:
  GlobalId activation(std::int64_t k) const {
    const auto n = static_cast<double>(prob_.num_sensors());
    auto i = static_cast<GlobalId>(uniform01(seed_, RngStream::kAsyncClock, static_cast<std::uint64_t>(k)) * n);
    return std::min<GlobalId>(i, prob_.num_sensors() - 1);
  }
  // The rows a later activation reads, fetched ahead (activations jump at
  // random over the graph) in three stages: the offsets 3 * kAhead entries
  // ahead, the neighbour lists and ranges 2 * kAhead ahead, the neighbours'
  // rows kAhead ahead.
  static constexpr std::size_t kAhead = 12;
  void prefetch(std::size_t t, std::size_t m) const {
    const auto& g = prob_.graph();
    const LocalId n_owned = g.num_owned();
    if (t + 3 * kAhead < m) {
      const LocalId v = acts_[t + 3 * kAhead].node;
      if (v < n_owned) {
        __builtin_prefetch(&g.offsets()[v]);
        __builtin_prefetch(&prob_.anchor_offsets()[v]);
      }
    }
    if (t + 2 * kAhead < m) {
      const LocalId v = acts_[t + 2 * kAhead].node;
      if (v < n_owned) {
        const auto e = g.offsets()[v];
        const auto w = g.edge_width();
        __builtin_prefetch(&g.adjacency()[e]);
        __builtin_prefetch(&g.adjacency()[e] + 15);
        __builtin_prefetch(&g.edge_values()[e * w]);
        __builtin_prefetch(&g.edge_values()[e * w] + 8);
        __builtin_prefetch(&g.edge_values()[e * w] + 15);
      }
    }
    if (t + kAhead < m) {
      const LocalId v = acts_[t + kAhead].node;
      if (v < n_owned) {
        const int p = prob_.dim();
        for (auto e = g.offsets()[v]; e < g.offsets()[v + 1]; ++e)
          __builtin_prefetch(&x_[std::size_t(g.adjacency()[e]) * p]);
        __builtin_prefetch(&x_[std::size_t(v) * p]);
      }
    }
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

  // One activation of owned node i; with g2/s2 (free mode) also ||grad_i f_hat||^2
  // at the old x_i and ||x_i(new) - x_i(old)||^2 (the replay passes neither).
  void activate(LocalId i, double* g2 = nullptr, double* s2 = nullptr) {
    const int p = prob_.dim();
    double* xi = &x_[std::size_t(i) * p];
    double g[3], v[3];
    if (!exact_) {
      // eq. (20): one gradient step with the global L (>= delta_i + |A_i|).
      if (!prob_.model().active() && p == 2) l2_grad<2>(prob_, x_.data(), i, xi, g);
      else if (!prob_.model().active() && p == 3) l2_grad<3>(prob_, x_.data(), i, xi, g);
      else local_cost_grad(prob_, x_.data(), i, xi, g);
      for (int k = 0; k < p; ++k) xi[k] -= g[k] / L_;
      if (g2) {
        double q = 0;
        for (int k = 0; k < p; ++k) q += g[k] * g[k];
        *g2 = q;
        *s2 = q / (L_ * L_);
      }
      return;
    }
    // Algorithm 3 on f_i with L_i = delta_i + |A_i|, warm-started at x_i.
    const double Li = local_lipschitz(i);
    if (Li == 0) return;
    double z[3], zm[3], w[3];
    for (int k = 0; k < p; ++k) z[k] = zm[k] = xi[k];
    const double f0 = local_cost_grad(prob_, x_.data(), i, xi, g);
    if (g2) {
      double q = 0;
      for (int k = 0; k < p; ++k) q += g[k] * g[k];
      *g2 = q;
    }
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
    if (local_cost_grad(prob_, x_.data(), i, v, g) <= f0) {
      if (s2) {
        double q = 0;
        for (int k = 0; k < p; ++k) q += (v[k] - xi[k]) * (v[k] - xi[k]);
        *s2 = q;
      }
      for (int k = 0; k < p; ++k) xi[k] = v[k];
    }
  }

  static constexpr int kInnerMax = 500;
  static constexpr double kInnerTol = 1e-12;
  static constexpr std::int64_t kChunk = 64;  // free mode: activations between polls
  LocalizationProblem& prob_;
  bool exact_;
  bool free_;
  bool gradient_rule_;
  double tol_;
  double target_;           // --target-cost (0: off)
  double straggler_delay_;  // seconds per epoch on this rank (free mode)
  std::uint64_t seed_;
  double L_;
  // Free mode.
  FreeHalo free_halo_;
  DupComm red_comm_;            // the stopping test's reductions
  int rank_ = 0;
  std::uint64_t draws_ = 0;     // this rank's draws so far (its stream's counter)
  std::int64_t epochs_total_ = 0;
  std::int64_t levels_run_ = 0, levels_total_ = 0;
  std::int64_t fewest_total_ = 0, most_total_ = 0;  // epochs of the slowest / fastest rank, summed over passes
  LocalId dropped_ = -1;        // drop_row()'s node
  struct Act {
    std::int64_t k;  // position in the activation sequence
    LocalId node;    // local id (owned or ghost)
  };
  std::vector<double> x_, prev_;
  std::vector<LocalId> g2l_;          // [n] global id -> local id, -1 if not local
  std::vector<std::int64_t> version_; // [local] position of the row's last activation applied (boundary and ghost rows)
  std::vector<std::uint32_t> taint_;  // [local] == pass_: an earlier activation not done in this pass
  std::uint32_t pass_ = 0;
  std::vector<Act> acts_;             // this iteration's activations of local nodes (then those left)
  DeltaHalo delta_;
  std::int64_t k_ = 0;
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
