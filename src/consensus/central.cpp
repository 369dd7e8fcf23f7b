// `central`: Newton's method on F = sum_p f_p with the gradient and Hessian
// summed over the nodes in node order (gathered to rank 0), so x* has the same
// bits on any number of ranks; Armijo or damped steps (primal_step). Every
// other method is measured against the x* of central_optimum.
#include <algorithm>
#include <cmath>

#include "consensus/solver_detail.hpp"
#include "snl/core/mpi_util.hpp"
#include "snl/io/network.hpp"

namespace snl::consensus {

namespace detail {
namespace {

std::vector<GlobalId> owned_by(const std::vector<int>& owner, int rank) {
  std::vector<GlobalId> ids;
  for (std::size_t i = 0; i < owner.size(); ++i)
    if (owner[i] == rank) ids.push_back(static_cast<GlobalId>(i));
  return ids;
}

class Central final : public Runner {
 public:
  Central(MPI_Comm comm, const ProblemData& data, const SolveOptions& opt, const std::vector<int>& owner)
      : comm_(comm), opt_(opt), q_(data.dim), n_(data.num_nodes) {
    const auto ids = owned_by(owner, comm_rank(comm));
    obj_ = LocalObjectives(data, ids);
    gather_ = NodeGather(comm, n_, ids);
    const std::size_t q = q_;
    x_.assign(q, 0.0);  // x(0) = 0
    rows_.assign(ids.size() * (q + q * q), 0.0);
    sums_.assign(q + q * q, 0.0);
    dx_.assign(q, 0.0);
    trial_.assign(q, 0.0);
    work_.assign(q * q, 0.0);
  }

  bool iterate(std::int64_t, Counters& c) override {
    const int q = q_, w = q + q * q;
    for (LocalId v = 0; v < static_cast<LocalId>(obj_.size()); ++v) {
      obj_.gradient(v, x_.data(), &rows_[std::size_t(v) * w]);
      obj_.hessian(v, x_.data(), &rows_[std::size_t(v) * w + q]);
    }
    gather_.sum(rows_.data(), w, sums_.data());
    // Communication of a central solver on the network: every node sends its
    // (g, H) to node 0, which sends x back.
    c.add(double(n_ - 1), w);
    c.add(double(n_ - 1), q);
    for (int k = 0; k < q; ++k) sums_[k] = -sums_[k];
    if (!spd_solve(q, sums_.data() + q, sums_.data(), dx_.data(), work_.data())) {
      theta_ = NAN;
      return false;
    }
    const double t2 = quad_form(q, sums_.data() + q, dx_.data());
    theta_ = (t2 >= 0 && std::isfinite(t2)) ? std::sqrt(t2) : NAN;
    if (!std::isfinite(theta_)) return false;
    step_ = primal_step(opt_, theta_, c, [&](double t) {
      for (int k = 0; k < q; ++k) trial_[k] = x_[k] + t * dx_[k];
      c.add(double(n_ - 1), 1);  // F's terms to node 0
      c.add(double(n_ - 1), 1);  // the verdict back
      return objective_at(gather_, obj_, trial_.data());
    });
    if (!std::isfinite(step_)) return false;
    for (int k = 0; k < q; ++k) x_[k] += step_ * dx_[k];
    f_ = NAN;
    return true;
  }

  bool converged(double tol, const HistoryRecord&) const override { return theta_ <= tol; }

  void measure(std::int64_t, const std::vector<double>& xstar, HistoryRecord& r) override {
    r.max_abs_error = max_abs_error(comm_, x_.data(), 1, xstar);
    r.objective = objective_at(gather_, obj_, x_.data());
    r.avg_max_abs_error = r.avg_objective = NAN;
    r.decrement = theta_;
    r.step = step_;
  }

  std::vector<double> x_rows() const override {
    std::vector<double> all;
    if (comm_rank(comm_) == 0)
      for (GlobalId i = 0; i < n_; ++i) all.insert(all.end(), x_.begin(), x_.end());
    return all;
  }
  void set_x_rows(const std::vector<double>& all) override { std::copy(all.begin(), all.begin() + q_, x_.begin()); }
  const std::vector<double>& x() const { return x_; }
  double theta() const { return theta_; }
  double objective() {  // F at x (collective)
    if (std::isnan(f_)) f_ = objective_at(gather_, obj_, x_.data());
    return f_;
  }

  void save(H5File& f) const override {
    f.write_replicated("state/x", x_);
    f.write_scalar("state/theta", theta_);
    f.write_scalar("state/step", step_);
  }
  void load(const H5File& f) override {
    const auto s = f.shape("state/x");
    if (s.size() != 1 || s[0] != static_cast<std::uint64_t>(q_))
      throw Error(f.path() + ": checkpoint dataset state/x has the wrong shape");
    x_ = f.read_rows_double("state/x", 0, q_);
    theta_ = f.read_scalar("state/theta");
    step_ = f.read_scalar("state/step");
  }

 private:
  MPI_Comm comm_;
  SolveOptions opt_;
  int q_;
  GlobalId n_;
  LocalObjectives obj_;
  NodeGather gather_;
  std::vector<double> x_, rows_, sums_, dx_, trial_, work_;
  double theta_ = NAN, step_ = 0, f_ = NAN;
};

}  // namespace

std::unique_ptr<Runner> make_central(MPI_Comm comm, const ProblemData& data, const SolveOptions& opt,
                                     const std::vector<int>& owner) {
  return std::make_unique<Central>(comm, data, opt, owner);
}

}  // namespace detail

Optimum central_optimum(MPI_Comm comm, const ProblemData& data, std::int64_t max_iterations) {
  // Any partition gives the same bits (sums in node order): the block one.
  const int size = comm_size(comm);
  std::vector<int> owner(static_cast<std::size_t>(data.num_nodes));
  for (int r = 0; r < size; ++r) {
    GlobalId b, e;
    block_range(data.num_nodes, size, r, b, e);
    std::fill(owner.begin() + b, owner.begin() + e, r);
  }
  SolveOptions opt;
  opt.method = "central";  // Armijo steps
  detail::Central c(comm, data, opt, owner);
  detail::Counters unused;
  Optimum o;
  double prev = INFINITY;
  for (std::int64_t k = 0; k < max_iterations; ++k) {
    const bool ok = c.iterate(k, unused);
    o.iterations = k + 1;
    o.decrement = c.theta();
    if (!ok) break;  // not converged: a Hessian sum that is not SPD, overflow, or no Armijo step
    const double t = c.theta();
    // theta < 1/4 took the full step; stagnation below 1e-8 (1 + |F|)^(1/2) is F's rounding level.
    if (t <= 1e-12 || (t >= prev && t <= 1e-8 * std::sqrt(1.0 + std::fabs(c.objective())))) {
      o.converged = true;
      break;
    }
    prev = t;
  }
  o.x = c.x();
  return o;
}

}  // namespace snl::consensus
