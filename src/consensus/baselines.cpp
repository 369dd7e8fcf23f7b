// The paper's first-order baselines (001 Sec. 6).
// subgradient (Nedic-Ozdaglar): x_p <- sum_j W_pj x_j - alpha_k grad f_p(x_p)
//   with Metropolis weights W_pj = 1 / (1 + max(deg_p, deg_j)), W_pp = 1 - sum_j W_pj,
//   and running averages xhat_p(k) = (1/k) sum_{t=1..k} x_p(t).
// incremental (Ram-Nedic-Veeravalli): one iterate passed as a token along a
//   cycle, x <- x - alpha_k grad f_p(x) at each node it visits for the first time
//   in the cycle; running average of the iterate at the cycles' ends.
// Both use the diminishing step alpha_k = alpha0 / sqrt(k + 1), k the primal
// iteration (a cycle for incremental) counted from 0.
// Stopping rules (docs/distributed-newton.md): --tol T, the running average's
// largest change in one iteration, max_p |xhat_p(k) - xhat_p(k-1)| <= T (each
// node knows its own change; the max is exact in any order); --oracle-tol T,
// the running average's error against x* <= T (an oracle no node has).
#include <algorithm>
#include <cmath>

#include "consensus/solver_detail.hpp"
#include "snl/core/mpi_util.hpp"

namespace snl::consensus::detail {

namespace {

double step_size(double alpha0, std::int64_t k) { return alpha0 / std::sqrt(double(k) + 1.0); }

/// The baselines' stop: the change rule (tol) or the oracle rule (oracle_tol), either when set (> 0).
bool baseline_stop(const SolveOptions& opt, double tol, double change, const HistoryRecord& r) {
  const double oracle = opt.oracle_tol ? *opt.oracle_tol : 0.0;
  return (tol > 0 && change <= tol) || (oracle > 0 && r.avg_max_abs_error <= oracle);
}

/// max_j |sum_new[j] / (k + 1) - sum_old[j] / k| for q values: the running
/// average's change in iteration k -> k + 1 (xhat(0) = x(0) = 0).
double average_change(const double* sum_new, const double* sum_old, std::int64_t k, int q) {
  double m = 0;
  for (int j = 0; j < q; ++j) {
    const double before = k > 0 ? sum_old[j] / double(k) : 0.0;
    m = std::max(m, std::fabs(sum_new[j] / double(k + 1) - before));
  }
  return m;
}

class Subgradient final : public Runner {
 public:
  Subgradient(MPI_Comm comm, const ProblemData& data, const SolveOptions& opt, std::unique_ptr<DistGraph> graph,
              Counters& setup)
      : comm_(comm), opt_(opt), g_(std::move(graph)), q_(data.dim), n_(data.num_nodes),
        edges_(static_cast<GlobalId>(data.edges.size() / 2)) {
    const LocalId no = g_->num_owned(), nl = g_->num_local();
    std::vector<GlobalId> owned(g_->local_to_global().begin(), g_->local_to_global().begin() + no);
    obj_ = LocalObjectives(data, owned);
    gather_ = NodeGather(comm, n_, owned);
    // Metropolis weights from the neighbours' degrees (one exchange).
    std::vector<double> deg(nl, 0.0);
    for (LocalId v = 0; v < no; ++v) deg[v] = g_->degree(v);
    g_->halo().exchange(deg.data(), 1);
    setup.add(double(data.edges.size()), 1);
    const auto& off = g_->offsets();
    const auto& adj = g_->adjacency();
    wn_.resize(adj.size());
    ws_.resize(no);
    for (LocalId v = 0; v < no; ++v) {
      double sum = 0;
      for (auto e = off[v]; e < off[v + 1]; ++e) {
        wn_[e] = 1.0 / (1.0 + std::max(deg[v], deg[adj[e]]));
        sum += wn_[e];
      }
      ws_[v] = 1.0 - sum;
    }
    x_.assign(std::size_t(nl) * q_, 0.0);  // x(0) = 0
    xn_.assign(std::size_t(no) * q_, 0.0);
    sum_.assign(std::size_t(no) * q_, 0.0);
    grad_.assign(q_, 0.0);
    old_.assign(q_, 0.0);
  }

  bool iterate(std::int64_t k, Counters& c) override {
    const int q = q_;
    g_->halo().exchange(x_.data(), q);
    c.add(2.0 * double(edges_), q);  // every node to each neighbour
    const double alpha = step_size(opt_.step0(), k);
    const auto& off = g_->offsets();
    const auto& adj = g_->adjacency();
    const LocalId no = g_->num_owned();
    for (LocalId v = 0; v < no; ++v) {
      const double* xv = &x_[std::size_t(v) * q];
      double* out = &xn_[std::size_t(v) * q];
      obj_.gradient(v, xv, grad_.data());
      for (int j = 0; j < q; ++j) out[j] = ws_[v] * xv[j];
      for (auto e = off[v]; e < off[v + 1]; ++e)  // neighbours in global-id order
        for (int j = 0; j < q; ++j) out[j] += wn_[e] * x_[std::size_t(adj[e]) * q + j];
      for (int j = 0; j < q; ++j) out[j] -= alpha * grad_[j];
    }
    bool finite = true;
    double change = 0;
    for (LocalId v = 0; v < no; ++v) {
      const std::size_t at = std::size_t(v) * q;
      for (int j = 0; j < q; ++j) old_[j] = sum_[at + j];
      for (int j = 0; j < q; ++j) {
        x_[at + j] = xn_[at + j];
        sum_[at + j] += xn_[at + j];
        finite = finite && std::isfinite(xn_[at + j]);
      }
      change = std::max(change, average_change(&sum_[at], old_.data(), k, q));
    }
    int bad = finite ? 0 : 1, any = 0;
    MPI_Allreduce(&bad, &any, 1, MPI_INT, MPI_MAX, comm_);
    if (opt_.tolerance() > 0) MPI_Allreduce(&change, &change_, 1, MPI_DOUBLE, MPI_MAX, comm_);
    return any == 0;
  }

  bool converged(double tol, const HistoryRecord& r) const override { return baseline_stop(opt_, tol, change_, r); }

  void measure(std::int64_t k, const std::vector<double>& xstar, HistoryRecord& r) override {
    const LocalId no = g_->num_owned();
    r.max_abs_error = max_abs_error(comm_, x_.data(), no, xstar);
    r.objective = objective_at_average(gather_, obj_, n_, x_.data());
    if (k > 0) {
      std::vector<double> avg(sum_.size());
      for (std::size_t i = 0; i < avg.size(); ++i) avg[i] = sum_[i] / double(k);
      r.avg_max_abs_error = max_abs_error(comm_, avg.data(), no, xstar);
      r.avg_objective = objective_at_average(gather_, obj_, n_, avg.data());
    } else {
      r.avg_max_abs_error = r.max_abs_error;
      r.avg_objective = r.objective;
    }
    r.decrement = NAN;
    r.step = step_size(opt_.step0(), std::max<std::int64_t>(k - 1, 0));
  }

  std::vector<double> x_rows() const override { return gather_.to_root(x_.data(), q_); }
  void set_x_rows(const std::vector<double>& all) override { gather_.pick(all, q_, x_.data()); }
  void save(H5File& f) const override {
    write_node_rows(f, "state/x", gather_, n_, x_.data(), q_);
    write_node_rows(f, "state/sum", gather_, n_, sum_.data(), q_);
  }
  void load(const H5File& f) override {
    read_node_rows(f, "state/x", gather_, n_, x_.data(), q_);
    read_node_rows(f, "state/sum", gather_, n_, sum_.data(), q_);
  }

 private:
  MPI_Comm comm_;
  SolveOptions opt_;
  std::unique_ptr<DistGraph> g_;
  int q_;
  GlobalId n_, edges_;
  LocalObjectives obj_;
  NodeGather gather_;
  std::vector<double> wn_, ws_, x_, xn_, sum_, grad_, old_;
  double change_ = INFINITY;  ///< max_p |xhat_p(k) - xhat_p(k-1)| of the last iteration (all ranks)
};

// The token's tour is known to every rank (a path, or the Euler tour of the
// BFS tree); each rank walks it and acts on the visits of the nodes it owns,
// receiving the token from the previous owner and sending it on (one
// point-to-point message whenever the token changes rank; the network model
// counts one message per hop).
class Incremental final : public Runner {
 public:
  Incremental(MPI_Comm comm, const ProblemData& data, const SolveOptions& opt, const std::vector<int>& owner,
              std::vector<GlobalId> tour, std::vector<char> update, bool alternate)
      : comm_(comm), opt_(opt), owner_(owner), tour_(std::move(tour)), update_(std::move(update)),
        alternate_(alternate), q_(data.dim), n_(data.num_nodes), rank_(comm_rank(comm)) {
    for (std::size_t i = 0; i < owner.size(); ++i)
      if (owner[i] == rank_) owned_.push_back(static_cast<GlobalId>(i));
    obj_ = LocalObjectives(data, owned_);
    gather_ = NodeGather(comm, n_, owned_);
    local_.assign(owner.size(), -1);
    for (std::size_t v = 0; v < owned_.size(); ++v) local_[owned_[v]] = static_cast<LocalId>(v);
    x_.assign(owned_.size() * q_, 0.0);
    token_.assign(q_, 0.0);  // x(0) = 0
    sum_.assign(q_, 0.0);
    grad_.assign(q_, 0.0);
  }

  bool iterate(std::int64_t k, Counters& c) override {
    const double alpha = step_size(opt_.step0(), k);
    const std::size_t len = tour_.size();
    const bool back = alternate_ && (k % 2 == 1);
    int holder = owner_[tour_[back ? len - 1 : 0]];
    // The token starts the cycle where the last one ended (the tour's start:
    // node 0, or the path's end that the previous cycle reached).
    for (std::size_t i = 0; i < len; ++i) {
      const std::size_t at = back ? len - 1 - i : i;
      const GlobalId p = tour_[at];
      const int o = owner_[p];
      if (o != holder) {
        if (rank_ == holder) MPI_Send(token_.data(), q_, MPI_DOUBLE, o, 17, comm_);
        if (rank_ == o) MPI_Recv(token_.data(), q_, MPI_DOUBLE, holder, 17, comm_, MPI_STATUS_IGNORE);
        holder = o;
      }
      if (rank_ == o && update_[at]) {
        const LocalId v = local_[p];
        obj_.gradient(v, token_.data(), grad_.data());
        for (int j = 0; j < q_; ++j) token_[j] -= alpha * grad_[j];
        std::copy(token_.begin(), token_.end(), x_.begin() + std::size_t(v) * q_);
      }
    }
    c.add(double(len - 1), q_);  // one message per hop
    // The iterate at the cycle's end, for the running average (a report, not
    // part of the method: every rank keeps the same copy).
    MPI_Bcast(token_.data(), q_, MPI_DOUBLE, holder, comm_);
    const std::vector<double> old = sum_;
    for (int j = 0; j < q_; ++j) sum_[j] += token_[j];
    change_ = average_change(sum_.data(), old.data(), k, q_);  // the same on every rank
    bool finite = true;
    for (double t : token_) finite = finite && std::isfinite(t);
    return finite;
  }

  bool converged(double tol, const HistoryRecord& r) const override { return baseline_stop(opt_, tol, change_, r); }

  void measure(std::int64_t k, const std::vector<double>& xstar, HistoryRecord& r) override {
    r.max_abs_error = max_abs_error(comm_, x_.data(), static_cast<LocalId>(owned_.size()), xstar);
    r.objective = objective_at_average(gather_, obj_, n_, x_.data());
    if (k > 0) {
      std::vector<double> avg(q_);
      for (int j = 0; j < q_; ++j) avg[j] = sum_[j] / double(k);
      double m = 0;
      for (int j = 0; j < q_; ++j) m = std::max(m, std::fabs(avg[j] - xstar[j]));
      r.avg_max_abs_error = m;
      r.avg_objective = objective_at(gather_, obj_, avg.data());
    } else {
      r.avg_max_abs_error = r.max_abs_error;
      r.avg_objective = r.objective;
    }
    r.decrement = NAN;
    r.step = step_size(opt_.step0(), std::max<std::int64_t>(k - 1, 0));
  }

  std::vector<double> x_rows() const override { return gather_.to_root(x_.data(), q_); }
  void set_x_rows(const std::vector<double>& all) override { gather_.pick(all, q_, x_.data()); }
  void save(H5File& f) const override {
    write_node_rows(f, "state/x", gather_, n_, x_.data(), q_);
    f.write_replicated("state/token", token_);
    f.write_replicated("state/sum", sum_);
  }
  void load(const H5File& f) override {
    read_node_rows(f, "state/x", gather_, n_, x_.data(), q_);
    for (const char* name : {"state/token", "state/sum"}) {
      const auto s = f.shape(name);
      if (s.size() != 1 || s[0] != static_cast<std::uint64_t>(q_))
        throw Error(f.path() + ": checkpoint dataset " + name + " has the wrong shape");
    }
    token_ = f.read_rows_double("state/token", 0, q_);
    sum_ = f.read_rows_double("state/sum", 0, q_);
  }

 private:
  MPI_Comm comm_;
  SolveOptions opt_;
  std::vector<int> owner_;
  std::vector<GlobalId> tour_;
  std::vector<char> update_;
  bool alternate_;
  int q_;
  GlobalId n_;
  int rank_;
  std::vector<GlobalId> owned_;
  std::vector<LocalId> local_;
  LocalObjectives obj_;
  NodeGather gather_;
  std::vector<double> x_, token_, sum_, grad_;
  double change_ = INFINITY;  ///< the running average's change in the last cycle (every rank the same)
};

}  // namespace

std::unique_ptr<Runner> make_subgradient(MPI_Comm comm, const ProblemData& data, const SolveOptions& opt,
                                         std::unique_ptr<DistGraph> graph, Counters& setup) {
  return std::make_unique<Subgradient>(comm, data, opt, std::move(graph), setup);
}

std::unique_ptr<Runner> make_incremental(MPI_Comm comm, const ProblemData& data, const SolveOptions& opt,
                                         const std::vector<int>& owner, std::vector<GlobalId> tour,
                                         std::vector<char> update, bool alternate) {
  return std::make_unique<Incremental>(comm, data, opt, owner, std::move(tour), std::move(update), alternate);
}

}  // namespace snl::consensus::detail
