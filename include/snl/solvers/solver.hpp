#pragma once
// Solver interface in the style of Ceres: an Options struct with in-class
// defaults and validation, a Summary, iteration callbacks, and a small
// Algorithm interface that every method (relaxation, MM, BB, ...) implements,
// so the driver never changes when an algorithm is added: a method is one .cpp
// file in src/solvers/ plus one row of the registry (registry.hpp).
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "snl/problem/metrics.hpp"
#include "snl/problem/problem.hpp"
#include "snl/solvers/checkpoint.hpp"
#include "snl/solvers/history.hpp"
#include "snl/solvers/registry.hpp"

namespace snl {

enum class TerminationType {
  kConvergence,    ///< a tolerance was met
  kNoConvergence,  ///< max_iter reached
  kUserAbort,      ///< a callback asked to stop
  kSignal,         ///< SIGTERM/SIGUSR1 asked to stop (a checkpoint was written)
  kFailure,        ///< numerical failure (non-finite iterate)
};
const char* to_string(TerminationType t);

struct SolverOptions {
  /// A name of the registry (registry.hpp): dv-pipeline | relaxation | mm | pipeline | bb | pm | async | ...
  std::string algorithm = "dv-pipeline";
  /// Iterations per phase (the pipelines have two phases).
  std::int64_t max_iter = 10000;
  /// dv-pipeline: iterations of its relaxation phase, which smooths the
  /// distance-vector start (outliers pulled in) before mm-accel; run much
  /// longer, the relaxation draws sensors outside the anchors' hull onto it
  /// and the refinement ends in folded local minima (docs/quality.md).
  std::int64_t smooth_iter = 200;
  /// dv-pipeline: iterations of its mm-accel phase before ml-agd takes over
  /// (mm-accel's edge variables keep sensors from flipping while the basin is
  /// settled; ml-agd then converges at a quarter of the cost per iteration).
  /// 400 ends within about 1e-5 of mm-accel run to convergence, 200 within
  /// about 1e-4 in two thirds of the time (docs/dv-pipeline.md).
  std::int64_t settle_iter = 200;
  /// Iterations the phase `index` of `count` run phases may run.
  std::int64_t phase_max_iter(std::size_t index, std::size_t count) const;
  /// Tolerance of the stopping rule `stop` (0 disables it; unset: the rule's
  /// default, stop_tol()): with papers, the relative improvement
  /// ||x(k) - x(k-1)|| / ||x(k)|| at or below which a phase stops (003,
  /// Sec. V uses 1e-6); with gradient, the relative gradient.
  std::optional<double> tol;
  /// Stopping rule of each phase, with --tol as its tolerance:
  ///   papers:   ||x(k) - x(k-1)|| / ||x(k)|| <= tol (003, Sec. V; it shrinks
  ///             with the step 1/L and with n, not with the distance to the optimum);
  ///   gradient: ||grad c(x)|| / (2 sqrt f(x)) <= tol, c the phase's cost (f for
  ///             MM, mm-accel and BB, f_hat for the others): the gradient against
  ///             the norm it would have if its edge terms did not cancel
  ///             (docs/quality.md, "Stopping rule"), tested every
  ///             test_every iterations (0: automatic; from 10,000 sensors
  ///             an interval that grows with the iterations done).
  std::string stop = "gradient";
  /// The refinement the pipeline runs after the relaxation: mm | mm-accel, or
  /// auto (the default): mm-accel, under every measurement model (it reaches
  /// the ML cost's optimum in 14-40 times fewer messages than MM with weights
  /// or Huber too; docs/quality.md, "Accelerated refinement").
  std::string refine = "auto";
  /// `refine` with auto resolved.
  std::string resolved_refine() const { return refine != "auto" ? refine : "mm-accel"; }
  /// A copy with auto resolved (the pipeline's refine), as the Solver runs it
  /// and its checkpoints record it.
  SolverOptions resolved() const;
  /// tol, or where it is unset the rule's default: 1e-6 (papers), 1e-5 (gradient).
  double stop_tol() const { return tol ? *tol : (stop == "papers" ? 1e-6 : 1e-5); }
  /// Stop when the norm of the gradient the method computes falls to this
  /// (the relaxation's grad f_hat at the extrapolated point). 0 disables it.
  double grad_tol = 0.0;
  /// Record history (and report progress) every this many iterations; 0: auto
  /// (every iteration up to 2000, else about 1000 records per phase; above
  /// 10,000 sensors at least every 100 iterations, at gradient tests).
  std::int64_t history_every = 0;
  /// Iterations between the gradient rule's tests (each an extra exchange and
  /// a pass over the edges, about three iterations' time), rounded up to a
  /// multiple of the record interval; 0: auto, 10, or 50 from 10,000
  /// sensors (docs/performance.md, "Bookkeeping").
  std::int64_t test_every = 0;
  /// Consensus rounds per BB iteration (Calafiore et al. use 20).
  int bb_rounds = 20;
  /// ADMM penalty of esdp-dist (docs/esdp-dist.md).
  double esdp_rho = 1.0;
  /// Temporal blocking: up to this many relaxation or MM iterations per pass over memory
  /// (the same iterates, bit for bit, with far less memory traffic). The
  /// stopping tests, history records, callbacks, signals and checkpoints are
  /// then taken at the end of a pass: a pass ends at every multiple of
  /// history_every and of the checkpoint interval and at max_iter, but a
  /// tolerance met inside a pass stops the phase at its end. 1: off.
  int temporal_block = 1;
  /// Check after every iteration that the MM surrogate did not increase
  /// (one extra reduction per iteration). On by default in debug builds.
#ifdef NDEBUG
  bool check_monotone = false;
#else
  bool check_monotone = true;
#endif
  std::uint64_t seed = 1;
  /// async, async-exact: replay (the sequential activation order, bit for
  /// bit, any rank count) or free (each rank activates its own nodes on its own
  /// clock, rows sent with nonblocking messages; not reproducible; docs/async.md).
  std::string mode = "replay";
  /// Test option: the rank `straggler_rank` (-1: the last) sleeps this many
  /// seconds per iteration (free mode: per n_own activations of its own).
  double straggler_delay = 0;
  int straggler_rank = -1;
  /// Benchmark option: stop a phase once its objective (f_hat for the
  /// relaxation and async) is at or below this, tested where the stopping
  /// rule is tested (free mode: also its own estimate); 0: off.
  double target_cost = 0;
  /// Weights of the ML cost (weights.hpp): file | multiplicative:NF | none, or
  /// auto (file when the network has sigmas, else none).
  std::string weights = "auto";
  /// Loss on the range residuals: l2 | huber:DELTA.
  std::string loss = "l2";
  /// The phases the Solver runs: the algorithm's (registry), the pipeline's
  /// refinement replaced by `refine`; under a measurement model (weights or
  /// Huber) dv-pipeline ends with mm-accel, without ml-agd (plain l2 only).
  std::vector<AlgorithmId> phases(bool measurement_model = false) const;
  /// "" if valid, else the message (unsupported_option() included).
  std::string validate() const;
  /// "" unless an option is set to a non-default value that the algorithm
  /// cannot honour (its capabilities in the registry: --grad-tol,
  /// --temporal-block, --bb-rounds); then the message saying so.
  std::string unsupported_option() const;
};

enum class CallbackReturn { kContinue, kAbort };

class IterationCallback {
 public:
  virtual ~IterationCallback() = default;
  /// Called collectively on every rank at recorded iterations.
  virtual CallbackReturn operator()(const IterationSummary& s) = 0;
};

struct Summary {
  std::string algorithm;
  TerminationType termination = TerminationType::kNoConvergence;
  std::string message;
  std::int64_t iterations = 0;  ///< all phases
  bool converged = false;
  double initial_cost = NAN, final_cost = NAN;  ///< of the last phase's own objective
  CostTerms costs;                              ///< at the final point
  /// Eq. (22) bound on f* - f_hat*, valid only at the relaxation's minimizer:
  /// evaluated where a relaxation phase ended (NaN if the run had none).
  double gap_certificate = NAN;
  double relaxed_optimum = NAN;  ///< f_hat where the relaxation phase ended
  ErrorMetrics errors;
  double messages_per_sensor = 0, reals_per_sensor = 0;
  std::int64_t mpi_bytes = 0;        ///< halo bytes sent, all ranks (algorithm exchanges)
  double comm_wait_fraction = 0;     ///< time waiting in halo end() / wall (max over ranks)
  double wall_seconds = 0;
  /// Time inside Algorithm::iterate() only (no history metrics, reductions or
  /// checkpoints), max over ranks; and the halo wait within it, max over ranks.
  double iterate_seconds = 0, iterate_wait_seconds = 0;
  /// Bookkeeping outside iterate(), max over ranks: the stopping sums and
  /// tests of every pass, and the records (history metrics, callbacks).
  double stop_test_seconds = 0, record_seconds = 0;
  /// Gradient stopping tests run (--stop gradient), over all phases.
  std::int64_t gradient_tests = 0;
  /// Of those, the ones settled on plain sums with a rounding bound (the rest
  /// by exact sums; the outcome is the same either way).
  std::int64_t gradient_tests_bounded = 0;
  /// Per phase (pipeline: relaxation then mm), same meaning as iterate_seconds.
  std::vector<std::pair<std::string, double>> phase_iterate_seconds;
  /// Algorithm state (iterates, edge variables), all ranks; max over phases.
  std::int64_t algorithm_state_bytes = 0;
  /// Per phase: modelled memory traffic of one iteration, all ranks (bytes).
  std::vector<std::pair<std::string, double>> phase_traffic_bytes;
  double lipschitz = NAN;
  /// What the last phase's method reports beyond these (Algorithm::report).
  std::vector<std::pair<std::string, double>> method_values;
  std::vector<std::pair<std::string, std::string>> method_texts;
  int ranks = 1;
  std::vector<IterationSummary> history;
  std::string brief_report() const;
};

/// One iterative method on a LocalizationProblem. Positions are local arrays
/// [num_local * p]: owned rows first, ghost rows after.
class Algorithm {
 public:
  virtual ~Algorithm() = default;
  virtual std::string name() const = 0;
  /// Collective. Starts from x (owned rows valid; ghosts are exchanged here).
  virtual void start(const std::vector<double>& x) = 0;
  /// Collective. One iteration of the paper's update.
  virtual void iterate() = 0;
  /// A free-running method (async --mode free): iterate_levels(n) runs up to n
  /// iterations on every rank, without synchronising, and may stop earlier by
  /// its own distributed test; the Solver then runs passes as long as its
  /// records and checkpoints allow and reads levels_run().
  virtual bool free_running() const { return false; }
  /// Free-running methods: the iterations the last iterate_levels() ran (the
  /// most of any rank; < n when it stopped by its own test or a signal).
  virtual std::int64_t levels_run() const { return 0; }
  /// Iterations one iterate_levels() call may run (temporal blocking); 1 if none.
  virtual int max_levels() const { return 1; }
  /// Collective. n <= max_levels() iterations, the same iterates as n calls of
  /// iterate(); change_norms() and grad_norm_sq() then refer to the last.
  virtual void iterate_levels(int n) {
    for (int j = 0; j < n; ++j) iterate();
  }
  /// Current iterate; owned rows valid.
  virtual const std::vector<double>& positions() const = 0;
  /// Collective: the objective the method minimizes at the current iterate.
  virtual double objective() = 0;
  /// True when objective() is the ML cost f at positions() (evaluate_ml_cost):
  /// the Solver then reuses the f its gradient test formed at the same iterate.
  virtual bool objective_is_ml_cost() const { return false; }
  /// This rank's sums over owned rows of ||x(k)-x(k-1)||^2 and ||x(k)||^2.
  virtual void change_norms(double* diff_sq, double* x_sq) const = 0;
  /// This rank's squared norm of the last gradient computed (NaN if none).
  virtual double grad_norm_sq() const { return std::numeric_limits<double>::quiet_NaN(); }
  /// x(k-1), owned rows valid. With positions(), the solver sums the per-node
  /// terms of the stopping test exactly, so the test (and so the stopping
  /// iteration) is the same for any partition; nullptr: change_norms() is used.
  virtual const double* previous_positions() const { return nullptr; }
  /// Collective (may exchange ghost rows): owned rows of the gradient whose
  /// norm grad_norm_sq() gives, summed per node exactly by the solver;
  /// nullptr: grad_norm_sq() is used.
  virtual const double* gradient_rows() { return nullptr; }
  /// Per sensor per iteration (spec: one broadcast of a p-vector = 1 message, p reals).
  virtual double messages_per_iteration() const { return 1.0; }
  virtual double reals_per_iteration() const = 0;
  /// Constant used by the method (NaN if none).
  virtual double lipschitz() const { return std::numeric_limits<double>::quiet_NaN(); }
  /// Bytes of this rank's state arrays (capacities), for the memory report.
  virtual std::int64_t memory_bytes() const { return 0; }
  /// Bytes this rank sent in the method's own messages, beside the graph's halo
  /// plan (async's sparse exchanges); counted in Summary::mpi_bytes.
  virtual std::int64_t bytes_sent() const { return 0; }
  /// Bytes this rank must move to or from memory in one iteration: every
  /// array streamed once, gathered neighbour rows once (the model of
  /// docs/performance.md, for the bandwidth bound); NaN if not modelled.
  virtual double traffic_bytes_per_iteration() const { return std::numeric_limits<double>::quiet_NaN(); }
  /// Values the method reports beyond the common ones (the SDP relaxations: their
  /// objective, the solver's status and time), the same on every rank; they go to
  /// the result file's attributes and the JSON summary.
  virtual void report(std::vector<std::pair<std::string, double>>* /*values*/,
                      std::vector<std::pair<std::string, std::string>>* /*texts*/) const {}
  /// Collective. Everything needed to continue bit for bit (after start()).
  virtual void save(StateWriter& w) const = 0;
  virtual void load(const StateReader& r) = 0;
};

/// The methods of the registry that are not synchronous (PM, async, async-exact); nullptr for other names.
std::unique_ptr<Algorithm> make_sequential_algorithm(const std::string& name, LocalizationProblem& prob,
                                                     const SolverOptions& opt);
/// Deterministic Jones-Plassmann colouring (priorities hashed from global ids; PM's order, pm.cpp):
/// a colour per local node (owned and ghost); neighbours never share one.
std::vector<int> jones_plassmann_coloring(DistGraph& g);

/// The rank --straggler-delay slows: --straggler-rank, or the last rank of comm.
int straggler_rank(const SolverOptions& opt, MPI_Comm comm);

/// Initial point: --init random (uniform in the bounding box of the anchors,
/// keyed by (seed, global id): the same for any number of ranks). Owned rows.
std::vector<double> random_initial_positions(const LocalizationProblem& prob, std::uint64_t seed);

/// Checkpointing of a Solver run (layout in docs/formats.md).
struct CheckpointConfig {
  std::string path;                 ///< write checkpoints here ("" = never)
  std::int64_t every = 0;           ///< every K iterations (0 = off)
  double seconds = 0;               ///< and/or every S seconds of wall clock (0 = off)
  std::string restart;              ///< resume from this checkpoint ("" = fresh start)
  std::string network_fingerprint;  ///< network_fingerprint() of the input
  bool stop_on_signal = false;      ///< SIGTERM/SIGUSR1: checkpoint and stop (kSignal)
};

/// Runs the configured algorithm (or pipeline) from x0 (owned rows, local
/// order). Collective. The final owned positions are left in `x_out`.
class Solver {
 public:
  Solver(LocalizationProblem& prob, SolverOptions opt);
  void add_callback(IterationCallback* cb) { callbacks_.push_back(cb); }
  void set_checkpointing(const CheckpointConfig& c) { ckpt_ = c; }
  /// Fingerprint of the options that a checkpoint must match to be resumed (checkpoint_options()).
  std::string options_fingerprint() const;
  Summary solve(const std::vector<double>& x0, std::vector<double>* x_out);

 private:
  LocalizationProblem& prob_;
  SolverOptions opt_;
  std::vector<IterationCallback*> callbacks_;
  CheckpointConfig ckpt_;
  class Run;  // one call of solve(), as named steps (solver.cpp)
};

}  // namespace snl
