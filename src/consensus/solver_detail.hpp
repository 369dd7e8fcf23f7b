#pragma once
// Internals of the consensus solvers (src/consensus/*): small dense algebra,
// communication counters, the common interface of the methods and the
// checkpoint helpers. Not installed.
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "snl/consensus/problem.hpp"
#include "snl/consensus/solver.hpp"
#include "snl/consensus/tree.hpp"
#include "snl/io/h5file.hpp"

namespace snl::consensus::detail {

/// In-place Cholesky of a q x q SPD matrix (row-major, lower triangle used).
/// Returns false if it is not positive definite.
bool cholesky(int q, double* a);
/// Inverse of an SPD matrix h into hinv; work[q*q]. False if not SPD.
bool spd_inverse(int q, const double* h, double* hinv, double* work);
/// Solves h x = b for SPD h; work[q*q]. False if not SPD.
bool spd_solve(int q, const double* h, const double* b, double* x, double* work);
/// y = a x (q x q row-major).
inline void matvec(int q, const double* a, const double* x, double* y) {
  for (int i = 0; i < q; ++i) {
    double s = 0;
    for (int j = 0; j < q; ++j) s += a[i * q + j] * x[j];
    y[i] = s;
  }
}
/// x^T a x.
inline double quad_form(int q, const double* a, const double* x) {
  double s = 0;
  for (int i = 0; i < q; ++i) {
    double r = 0;
    for (int j = 0; j < q; ++j) r += a[i * q + j] * x[j];
    s += x[i] * r;
  }
  return s;
}

/// Communication of the network algorithm, summed over all nodes (identical on
/// every rank: each count follows from global quantities). Per node = / n.
struct Counters {
  double messages = 0;  ///< total messages sent by all nodes
  double reals = 0;     ///< total reals in them
  std::int64_t dual_iterations = 0;
  std::int64_t line_search_trials = 0;
  void add(double msgs, double reals_each) {
    messages += msgs;
    reals += msgs * reals_each;
  }
};

/// The primal step along a Newton direction dx whose directional derivative
/// is -theta^2. Damped (001, Wei-Ozdaglar-Jadbabaie): 1 if theta < 1/4, else
/// b / (theta + 1). Armijo (Boyd & Vandenberghe Alg. 9.2, alpha = 1/4,
/// beta = 1/2): the largest t = 2^-j, j < 60, with F(x + t dx) <= F(x) -
/// t theta^2 / 4; the full step without a trial once theta < 1/4, where
/// Newton is in its quadratic phase and F's decrease can be below F's
/// rounding. `f_at(t)` is collective and returns F(x + t dx) on every rank
/// (t = 0: F(x)); each call is counted in c.line_search_trials. NaN: no t.
template <class FAt>
double primal_step(const SolveOptions& opt, double theta, Counters& c, FAt&& f_at) {
  if (theta < 0.25) return 1.0;
  if (opt.step_kind() == StepRule::kDamped) return opt.damping_b() / (theta + 1.0);
  const double f0 = f_at(0.0);
  ++c.line_search_trials;
  double t = 1.0;
  for (int j = 0; j < 60; ++j, t *= 0.5) {
    const double f = f_at(t);
    ++c.line_search_trials;
    if (f <= f0 - 0.25 * t * theta * theta) return t;  // false for NaN
  }
  return NAN;
}

/// One method's state and iteration. Every call is collective.
class Runner {
 public:
  virtual ~Runner() = default;
  /// Primal iteration k -> k+1 (k counts from 0). Returns false on a
  /// numerical failure (a non-finite decrement or a Hessian that is not SPD).
  virtual bool iterate(std::int64_t k, Counters& c) = 0;
  /// After iterate() and measure(): has the method's stopping rule fired?
  virtual bool converged(double tol, const HistoryRecord& r) const = 0;
  /// Fills the record's error, objective, average and step fields.
  virtual void measure(std::int64_t k, const std::vector<double>& xstar, HistoryRecord& r) = 0;
  /// Node copies in node order on rank 0 ([n*q]), empty elsewhere.
  virtual std::vector<double> x_rows() const = 0;
  virtual void save(H5File& f) const = 0;
  virtual void load(const H5File& f) = 0;
  virtual std::int32_t tree_depth() const { return 0; }
  /// Sets every node's copy from rows in node order (every rank) (tests).
  virtual void set_x_rows(const std::vector<double>& all) = 0;
  /// Link duals in node order on every rank (Newton; empty otherwise) (tests).
  virtual std::vector<double> dual_rows() const { return {}; }
};

/// Writes node rows (owned, local order) as a dataset [n, width] in node order.
void write_node_rows(H5File& f, const std::string& name, const NodeGather& g, GlobalId n, const double* owned,
                     int width);
/// Reads them back into this rank's owned rows.
void read_node_rows(const H5File& f, const std::string& name, const NodeGather& g, GlobalId n, double* owned,
                    int width);

/// Maximum over owned rows of |x - xstar| (q per row), then over all ranks.
double max_abs_error(MPI_Comm comm, const double* x, LocalId rows, const std::vector<double>& xstar);
/// F at the average of the rows (sums in node order), and the average itself.
double objective_at_average(const NodeGather& g, const LocalObjectives& obj, GlobalId n, const double* x,
                            std::vector<double>* avg = nullptr);
/// F at a point (every rank the same point), summed in node order.
double objective_at(const NodeGather& g, const LocalObjectives& obj, const double* point);

/// Factories of the methods. `tree`: the BFS tree or the path.
std::unique_ptr<Runner> make_newton(MPI_Comm comm, const ProblemData& data, const SolveOptions& opt,
                                    std::unique_ptr<Tree> tree);
std::unique_ptr<Runner> make_central(MPI_Comm comm, const ProblemData& data, const SolveOptions& opt,
                                     const std::vector<int>& owner);
std::unique_ptr<Runner> make_subgradient(MPI_Comm comm, const ProblemData& data, const SolveOptions& opt,
                                         std::unique_ptr<DistGraph> graph, Counters& setup);
/// `tour`: the token's cycle (global ids), `update[i]`: whether visit i applies
/// a gradient step; `alternate`: odd cycles run the tour backwards (a path).
std::unique_ptr<Runner> make_incremental(MPI_Comm comm, const ProblemData& data, const SolveOptions& opt,
                                         const std::vector<int>& owner, std::vector<GlobalId> tour,
                                         std::vector<char> update, bool alternate);

}  // namespace snl::consensus::detail
