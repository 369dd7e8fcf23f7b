// The Solver's run as named steps (start, phases, passes, tests, records,
// checkpoints, summary). Over 600 lines because the steps share one Run's
// state; the stopping rule and the records are candidates for files of their own.
#include "snl/solvers/solver.hpp"

#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <thread>

#include "core/exact_sum.hpp"
#include "solvers/gradient_test.hpp"
#include "solvers/lane_costs.hpp"
#include "snl/core/memory.hpp"
#include "snl/core/mpi_util.hpp"

namespace snl {

const char* to_string(TerminationType t) {
  switch (t) {
    case TerminationType::kConvergence: return "CONVERGENCE";
    case TerminationType::kNoConvergence: return "NO_CONVERGENCE";
    case TerminationType::kUserAbort: return "USER_ABORT";
    case TerminationType::kSignal: return "SIGNAL";
    case TerminationType::kFailure: return "FAILURE";
  }
  return "?";
}

std::string SolverOptions::validate() const {
  if (!find_algorithm(algorithm))
    return "unknown --algorithm '" + algorithm + "' (expected " + algorithm_names(", ", " or ") + ")";
  if (max_iter < 0) return "--max-iter must be >= 0";
  if (smooth_iter < 0) return "--smooth-iter must be >= 0";
  if (settle_iter < 0) return "--settle-iter must be >= 0";
  if (tol && (!(*tol >= 0) || !std::isfinite(*tol))) return "--tol must be a finite number >= 0";
  if (!(grad_tol >= 0) || !std::isfinite(grad_tol)) return "--grad-tol must be a finite number >= 0";
  if (history_every < 0) return "--history-every must be >= 0";
  if (test_every < 0) return "--test-every must be >= 0";
  if (bb_rounds < 1 || bb_rounds > 10000) return "--bb-rounds must be in [1, 10000]";
  if (!(esdp_rho > 0) || !std::isfinite(esdp_rho)) return "--esdp-rho must be a finite number > 0";
  if (temporal_block < 1 || temporal_block > 64) return "--temporal-block must be in [1, 64]";
  if (mode != "replay" && mode != "free") return "unknown --mode '" + mode + "' (expected replay or free)";
  if (!(straggler_delay >= 0) || !std::isfinite(straggler_delay)) return "--straggler-delay must be a finite number >= 0";
  if (straggler_rank < -1) return "--straggler-rank must be >= 0 (or -1: the last rank)";
  if (!(target_cost >= 0) || !std::isfinite(target_cost)) return "--target-cost must be a finite number >= 0";
  try {
    parse_weights_spec(weights);
    parse_loss_spec(loss);
  } catch (const Error& e) {
    return e.what();
  }
  if (stop != "papers" && stop != "gradient") return "unknown --stop '" + stop + "' (expected papers or gradient)";
  if (refine != "auto" && refine != "mm" && refine != "mm-accel")
    return "unknown --refine '" + refine + "' (expected auto, mm or mm-accel)";
  if (test_every != 0 && stop != "gradient") return "--test-every applies to --stop gradient only";
  return unsupported_option();
}

namespace {
// A method honours --weights/--loss when it and every phase it runs do (a
// pipeline whose refinement ignores the model must not claim it).
bool honours_model(const AlgorithmInfo& a, const SolverOptions& o) {
  if (!a.measurement_model) return false;
  for (AlgorithmId id : o.phases(true))  // the phases it runs under a model
    if (!algorithm_info(id).measurement_model) return false;
  return true;
}

}  // namespace

std::string SolverOptions::unsupported_option() const {
  const AlgorithmInfo* a = find_algorithm(algorithm);
  if (!a) return "";
  const SolverOptions defaults;
  // Each option with the capability that honours it; the message names the methods that have it.
  const struct {
    bool set;
    const char* option;
    bool AlgorithmInfo::*capability;
    const char* default_value;
  } checks[] = {
      {grad_tol != defaults.grad_tol, "--grad-tol", &AlgorithmInfo::gradient_stop, "0"},
      {temporal_block != defaults.temporal_block, "--temporal-block", &AlgorithmInfo::temporal_blocking, "1"},
      {bb_rounds != defaults.bb_rounds, "--bb-rounds", &AlgorithmInfo::consensus_rounds, "20"},
      {weights != defaults.weights && weights != "none", "--weights", &AlgorithmInfo::measurement_model, "none"},
      {loss != defaults.loss, "--loss", &AlgorithmInfo::measurement_model, "l2"},
      {esdp_rho != defaults.esdp_rho, "--esdp-rho", &AlgorithmInfo::admm, "1"},
  };
  const bool tol_given = tol.has_value();
  if (a->one_shot && (tol_given || max_iter != defaults.max_iter))
    return std::string(tol_given ? "--tol" : "--max-iter") + " is not honoured by --algorithm " +
           algorithm + " (a convex relaxation solved once by an SDP solver, to its own tolerance); leave it out";
  // ADMM's iterate is no minimizer of f or f_hat: the gradient rule would test the wrong cost.
  if (a->admm && stop == "gradient" && stop_tol() > 0)
    return "--algorithm " + algorithm + " stops only by the relative improvement: give --stop papers";
  for (const auto& c : checks)
    if (c.set && !(c.capability == &AlgorithmInfo::measurement_model ? honours_model(*a, *this) : a->*c.capability))
      return std::string(c.option) + " is not honoured by --algorithm " + algorithm + " (only by " +
             algorithms_with(c.capability) + "); leave it out or give its default " + c.default_value;
  if (mode != defaults.mode && !a->free_mode)
    return "--mode is not honoured by --algorithm " + algorithm + " (only by " +
           algorithms_with(&AlgorithmInfo::free_mode) + "); leave it out or give its default " + defaults.mode;
  if (smooth_iter != defaults.smooth_iter && a->id != AlgorithmId::kDvPipeline)
    return "--smooth-iter is not honoured by --algorithm " + algorithm +
           " (only by dv-pipeline); leave it out or give its default " + std::to_string(defaults.smooth_iter);
  if (settle_iter != defaults.settle_iter && a->id != AlgorithmId::kDvPipeline)
    return "--settle-iter is not honoured by --algorithm " + algorithm +
           " (only by dv-pipeline); leave it out or give its default " + std::to_string(defaults.settle_iter);
  if (refine != defaults.refine && a->id != AlgorithmId::kPipeline)
    return "--refine is not honoured by --algorithm " + algorithm + " (only by pipeline); leave it out or give its default " +
           defaults.refine;
  return "";
}

std::int64_t SolverOptions::phase_max_iter(std::size_t index, std::size_t count) const {
  const AlgorithmInfo* a = find_algorithm(algorithm);
  if (!a || a->id != AlgorithmId::kDvPipeline) return max_iter;
  if (index == 0) return std::min(max_iter, smooth_iter);
  if (index + 1 < count) return std::min(max_iter, settle_iter);
  return max_iter;
}

SolverOptions SolverOptions::resolved() const {
  SolverOptions o = *this;
  const AlgorithmInfo* a = find_algorithm(algorithm);
  if (a && a->id == AlgorithmId::kPipeline) o.refine = resolved_refine();
  return o;
}

std::vector<AlgorithmId> SolverOptions::phases(bool measurement_model) const {
  const AlgorithmInfo* a = find_algorithm(algorithm);
  if (!a) return {};
  std::vector<AlgorithmId> out = a->phases;
  const AlgorithmInfo* r = find_algorithm(resolved_refine());
  if (a->id == AlgorithmId::kPipeline && r) out.back() = r->id;
  if (a->id == AlgorithmId::kDvPipeline && measurement_model) out.pop_back();
  return out;
}

std::string Summary::brief_report() const {
  std::ostringstream os;
  os << "snl " << algorithm << ": " << to_string(termination) << " after " << iterations << " iterations";
  if (!message.empty()) os << " (" << message << ")";
  os.precision(6);
  os << "\n  ML cost " << costs.ml << ", relaxed cost " << costs.relaxed;
  if (std::isfinite(gap_certificate))
    os << "\n  at the relaxation's solution: f_hat " << relaxed_optimum << ", gap certificate (003 eq. 22) "
       << gap_certificate << ", a-priori bound (eq. 23) " << costs.apriori;
  if (errors.valid) os << "\n  RMSE " << errors.rmse << ", MPE " << errors.mpe;
  os << "\n  communications per sensor: " << messages_per_sensor << " messages, " << reals_per_sensor
     << " reals; MPI bytes " << mpi_bytes << "; " << wall_seconds << " s on " << ranks << " ranks";
  return os.str();
}

int straggler_rank(const SolverOptions& opt, MPI_Comm comm) {
  return opt.straggler_rank >= 0 ? opt.straggler_rank : comm_size(comm) - 1;
}

Solver::Solver(LocalizationProblem& prob, SolverOptions opt) : prob_(prob), opt_(std::move(opt)) {
  const std::string err = opt_.validate();
  if (!err.empty()) throw Error(err);
  if (opt_.straggler_rank >= comm_size(prob_.comm()))
    throw Error("--straggler-rank " + std::to_string(opt_.straggler_rank) + ": the run has only " +
                std::to_string(comm_size(prob_.comm())) + " ranks");
  // The measurement model every phase and cost uses; --weights auto means
  // none for a method that cannot honour weights (explicit values are refused).
  opt_ = opt_.resolved();
  WeightsSpec ws = parse_weights_spec(opt_.weights);
  if (!honours_model(*find_algorithm(opt_.algorithm), opt_)) ws.kind = WeightsSpec::Kind::kNone;
  prob_.set_measurement_model(ws, parse_loss_spec(opt_.loss));
}

std::string Solver::options_fingerprint() const { return checkpoint_options(opt_); }


// ---------------------------------------------------------------------------
// One call of solve(): the run's state and its steps. The phases run in turn
// (the pipeline: relaxation, then MM from where it ended); each phase is a loop
// of passes of up to temporal_block iterations: iterate, reduce the stopping
// sums, test for a stop, record, checkpoint.
class Solver::Run {
 public:
  Run(const Solver& s, const std::vector<double>& x0);
  void restore();  // from ckpt_.restart, if given
  void run_phases();
  Summary finish(std::vector<double>* x_out);

 private:
  struct Phase {
    std::size_t index = 0;                // in phases_
    const AlgorithmInfo* info = nullptr;  // of this phase's method
    std::unique_ptr<Algorithm> alg;
    std::int64_t k = 0;         // iterations done in this phase
    std::int64_t cap = 0;       // iterations this phase may run (SolverOptions::phase_max_iter)
    std::int64_t every = 1;     // record interval (the grown schedule: the grid records fall on)
    int requested_block = 1;    // iterations per pass asked for (phase_block)
    std::int64_t block = 1;     // iterations per pass at most
    std::int64_t stop_every = 1;  // --stop gradient: the test's (first) interval, a multiple of every
    // The grown schedule (large networks, automatic intervals): the test's
    // interval grows from stop_every with the iterations done (test_interval),
    // and a record falls on every record_tests-th one; 0: fixed intervals.
    bool free_early = false;    // a free-running method stopped its last pass by its own test
    double test_cost = 0;
    std::int64_t record_tests = 0;
    double prev_obj = 0;        // for check_monotone
    double time = 0;            // in iterate()
    double stop_time = 0;       // in the stopping sums and tests (reduce, relative_gradient)
    double record_time = 0;     // in records (history metrics, callbacks)
    TerminationType term = TerminationType::kNoConvergence;
    std::string msg;
  };
  // What the one reduction per pass tells every rank.
  struct PassResult {
    double rel = 0, gnorm = 0;
    bool has_gnorm = false;  // gnorm was reduced (grad-tol, or a record is due)
    bool finite = true;
    bool signalled = false;  // a stop signal on some rank
    bool clock = false;      // rank 0's checkpoint clock ran out
    double rel_grad = NAN;   // --stop gradient, where tested
    double objective = NAN;  // --target-cost, where tested
  };

  bool add_stop_terms(Phase& ph, bool with_grad, bool exact, detail::ExactSum* sums);
  double grad_norm(Phase& ph);
  double relative_gradient(Phase& ph);
  bool bounded_test_allowed(const Phase& ph) const;
  void start_phase(Phase& ph);
  void set_pass_sizes(Phase& ph) const;
  int phase_block(const Phase& ph) const;
  bool gradient_rule() const { return opt_.stop == "gradient" && opt_.stop_tol() > 0; }
  bool pass(Phase& ph);  // false: the phase ends
  std::int64_t pass_length(const Phase& ph) const;
  std::int64_t test_interval(const Phase& ph) const;
  bool test_due(const Phase& ph) const;
  bool reduce_due(const Phase& ph) const;
  bool record_due(const Phase& ph) const;
  void iterate(Phase& ph, std::int64_t n);
  PassResult reduce(Phase& ph);
  bool test_stop(Phase& ph, const PassResult& r) const;
  void check_monotone(Phase& ph);
  void record_start(const Phase& ph);
  bool record(Phase& ph, const PassResult& r);  // true: a callback asked to stop
  void checkpoint(const Phase& ph);
  bool stop(Phase& ph, TerminationType t, std::string msg);
  void end_phase(Phase& ph);
  void metrics_at(const std::vector<double>& x, IterationSummary& it);
  double objective_of(Algorithm& alg);

  const Solver& s_;
  LocalizationProblem& prob_;
  const SolverOptions& opt_;
  const CheckpointConfig& ckpt_;
  MPI_Comm comm_;
  int p_;
  bool root_;
  double t0_;
  HaloPlan& halo_;
  std::int64_t instrumentation_bytes_ = 0;  // halo bytes of metrics, not of the methods
  std::int64_t method_bytes_ = 0;           // the methods' own messages (Algorithm::bytes_sent)
  Summary sum_;
  std::vector<AlgorithmId> phases_;
  std::vector<double> xs_;  // scratch for metrics: a local array whose ghost rows they exchange
  std::vector<double> gs_;  // scratch: owned rows of a gradient (--stop gradient)
  std::int64_t xs_iteration_ = -1;  // >= 0: xs_ holds this total iteration's positions, ghosts exchanged
  double xs_ml_ = NAN;              // and f there
  std::vector<double> x_;   // owned rows: the start of the next phase, the result at the end
  double messages_ = 0, reals_ = 0;
  std::int64_t total_it_ = 0;
  std::size_t first_phase_ = 0;
  std::int64_t resume_k_ = -1;  // >= 0: resume phase first_phase_ at this iteration
  std::unique_ptr<H5File> restart_file_;
  double last_ckpt_ = 0;
  bool checkpointing_;
  bool stop_all_ = false;
  double iter_time_ = 0, iter_wait_ = 0;
  double stop_time_ = 0, record_time_ = 0;  // summed over phases, this rank
};

Summary Solver::solve(const std::vector<double>& x0, std::vector<double>* x_out) {
  Run run(*this, x0);
  run.restore();
  run.run_phases();
  return run.finish(x_out);
}

Solver::Run::Run(const Solver& s, const std::vector<double>& x0)
    : s_(s),
      prob_(s.prob_),
      opt_(s.opt_),
      ckpt_(s.ckpt_),
      comm_(prob_.comm()),
      p_(prob_.dim()),
      root_(comm_rank(comm_) == 0),
      t0_(MPI_Wtime()),
      halo_(prob_.graph().halo()),
      checkpointing_(!ckpt_.path.empty()) {
  halo_.reset_counters();
  sum_.algorithm = opt_.algorithm;
  sum_.ranks = comm_size(comm_);
  phases_ = opt_.phases(prob_.model().active());  // known: the options were validated
  xs_.assign(std::size_t(prob_.num_local()) * p_, 0.0);
  if (opt_.stop == "gradient") gs_.assign(std::size_t(prob_.num_owned()) * p_, 0.0);
  x_ = x0;
  x_.resize(std::size_t(prob_.num_owned()) * p_);
}

// Verifies the checkpoint matches this network and these options, and takes
// over its counters and history; its state is loaded when its phase starts.
void Solver::Run::restore() {
  if (!ckpt_.restart.empty()) {
    restart_file_ = std::make_unique<H5File>(ckpt_.restart, comm_, H5File::Mode::kRead);
    const CheckpointHeader h =
        read_checkpoint_header(*restart_file_, ckpt_.network_fingerprint, s_.options_fingerprint());
    first_phase_ = static_cast<std::size_t>(h.phase);
    resume_k_ = h.phase_iteration;
    total_it_ = h.total_iteration;
    messages_ = h.messages;
    reals_ = h.reals;
    t0_ -= h.elapsed;
    if (first_phase_ >= phases_.size() || resume_k_ < 0 || resume_k_ > opt_.max_iter)
      throw Error(ckpt_.restart + ": checkpoint state out of range");
    sum_.history = read_checkpoint_history(*restart_file_);
  }
  last_ckpt_ = MPI_Wtime();
}

void Solver::Run::run_phases() {
  for (std::size_t i = first_phase_; i < phases_.size() && !stop_all_; ++i) {
    {
      Phase ph;
      ph.index = i;
      ph.info = &algorithm_info(phases_[i]);
      ph.cap = opt_.phase_max_iter(i, phases_.size());
      start_phase(ph);
      while (ph.k < ph.cap && pass(ph)) {
      }
      end_phase(ph);
    }
    // The phase's state, freed, goes back to the system before the next one
    // allocates its own: where it had reused free blocks inside malloc's heap
    // (the setup's), it stayed resident beside the next phase's.
    return_free_memory();
  }
}

void Solver::Run::start_phase(Phase& ph) {
  SolverOptions po = opt_;
  po.temporal_block = ph.requested_block = phase_block(ph);
  ph.alg = make_algorithm(phases_[ph.index], prob_, po);
  ph.alg->start(x_);
  long long b = ph.alg->memory_bytes(), all = 0;
  MPI_Allreduce(&b, &all, 1, MPI_LONG_LONG, MPI_SUM, comm_);
  sum_.algorithm_state_bytes = std::max<std::int64_t>(sum_.algorithm_state_bytes, all);
  double tb = ph.alg->traffic_bytes_per_iteration(), tb_all = 0;
  MPI_Allreduce(&tb, &tb_all, 1, MPI_DOUBLE, MPI_SUM, comm_);
  sum_.phase_traffic_bytes.emplace_back(ph.info->name, tb_all);
  if (restart_file_ && ph.index == first_phase_) {
    ph.alg->load(StateReader(*restart_file_, prob_));
    ph.k = resume_k_;
    restart_file_.reset();
  }
  sum_.lipschitz = ph.alg->lipschitz();
  xs_iteration_ = -1;
  set_pass_sizes(ph);
  ph.prev_obj = objective_of(*ph.alg);
  if (ph.k == 0) {
    sum_.initial_cost = ph.prev_obj;
    record_start(ph);
  }
}

// From this many sensors the automatic record and test intervals follow the
// cost of a record and of a gradient test (several iterations each), so that
// bookkeeping stays a small share of the iterations' time; below it a run takes
// milliseconds and records every iteration (docs/performance.md, "Bookkeeping").
constexpr std::int64_t kLargeNetwork = 10000;
// On large networks: the automatic record interval (at least) and the
// automatic gradient-test interval at the start of a phase.
constexpr std::int64_t kLargeRecordEvery = 100;
constexpr std::int64_t kLargeTestEvery = 50;

// A gradient test's cost in iterations of the method (an exchange and a scalar
// pass over the edges with exact sums against the methods' SIMD kernels),
// measured on the default 1M network on 2 ranks (docs/performance.md); 0: not
// modelled, the interval stays fixed. The bounded test (relative_gradient)
// costs less, but these set the schedule, so they stay: the same stops.
double gradient_test_cost(AlgorithmId id) {
  switch (id) {
    case AlgorithmId::kRelaxation: return 7;
    case AlgorithmId::kMM: return 7;
    case AlgorithmId::kMMAccel: return 2.5;
    default: return 0;
  }
}

// Iterations per pass that phase ph asks for (collective): --temporal-block,
// except in dv-pipeline's smoothing relaxation on large networks whose lane
// arrays outgrow the cache (the mean rank's, 12 bytes a slot, beyond
// stream_rows' 16 MiB), which runs kSmoothBlock per pass: the same iterates,
// bit for bit, for less memory traffic (where the arrays stay in cache a
// pass gains nothing). That phase runs its iterations without a stopping
// test, and 5 divides the large networks' record intervals (10, 50, 100): its
// records fall where they would without. SNL_TEST_SMOOTH_BLOCK=1: tests
// take the blocked path on small arrays too.
constexpr int kSmoothBlock = 5;
int Solver::Run::phase_block(const Phase& ph) const {
  const bool smoothing = opt_.algorithm == "dv-pipeline" && ph.index == 0 && phases_.size() > 1;
  if (!smoothing || prob_.num_sensors() < kLargeNetwork) return opt_.temporal_block;
  long long slots = static_cast<long long>(prob_.graph().adjacency().size()), all = 0;
  MPI_Allreduce(&slots, &all, 1, MPI_LONG_LONG, MPI_SUM, comm_);
  const bool forced = std::getenv("SNL_TEST_SMOOTH_BLOCK") != nullptr;
  return forced || detail::stream_rows(std::size_t(12 * all / comm_size(comm_))) ? kSmoothBlock : opt_.temporal_block;
}

void Solver::Run::set_pass_sizes(Phase& ph) const {
  // Auto: every iteration for small runs; about 1000 records per phase for
  // long ones; at least every 10 iterations on large networks, where a record
  // and the gradient test cost several iterations (gradient_test_cost).
  std::int64_t every = opt_.history_every;
  const bool large = prob_.num_sensors() >= kLargeNetwork;
  if (every <= 0) {
    every = opt_.max_iter <= 2000 ? 1 : (opt_.max_iter + 999) / 1000;
    if (large) every = std::max<std::int64_t>(every, 10);
  }
  // Temporal blocking: passes of up to `block` iterations, ending at every
  // record and checkpoint iteration (so these see the same iterates); the
  // automatic record interval becomes a multiple of the pass.
  ph.block = std::max(1, std::min(ph.requested_block, ph.alg->max_levels()));
  if (ph.alg->free_running()) {
    // One pass to the end of the phase (no synchronisation between its
    // iterations), cut only by explicit records (--history-every) and checkpoints.
    ph.block = std::max<std::int64_t>(1, std::min<std::int64_t>(ph.cap, 1 << 30));
    if (opt_.history_every <= 0) every = std::max<std::int64_t>(1, ph.cap);
  }
  if (opt_.history_every <= 0) every = (every + ph.block - 1) / ph.block * ph.block;
  ph.every = every;
  // The gradient test (an exchange, a pass over the edges) at records (which
  // then reuse its f): every test_every iterations or the next record after.
  const std::int64_t test = opt_.test_every > 0 ? opt_.test_every : large ? kLargeTestEvery : 10;
  ph.stop_every = every * ((test + every - 1) / every);
  // A record (the history's costs, gradient norm and errors: three more passes)
  // costs about three iterations on large networks (docs/performance.md,
  // "Bookkeeping"): there the automatic interval is a multiple of the test's,
  // at least 100, which leaves the tests, and so the iterates, where they were.
  const std::int64_t record_tests = (kLargeRecordEvery + ph.stop_every - 1) / ph.stop_every;
  if (opt_.history_every <= 0 && large) ph.every = ph.stop_every * record_tests;
  // Tests T iterations dear, k iterations into a phase: an interval I costs
  // T/I of the iterations in tests and, once the phase has converged, I/2
  // iterations on average before a test sees it; I = sqrt(2 T k) makes the
  // sum smallest, sqrt(2 T / k) of the iterations. So with the automatic
  // interval on large networks the interval grows so, in steps of its start
  // (a function of k alone: the same tests for any partition and on a
  // resume), and the automatic records follow the tests.
  ph.test_cost = large && gradient_rule() && opt_.test_every <= 0 ? gradient_test_cost(ph.info->id) : 0;
  ph.record_tests = ph.test_cost > 0 && opt_.history_every <= 0 ? record_tests : 0;
  if (ph.record_tests > 0) ph.every = ph.stop_every;  // the grid the records fall on
}

std::int64_t Solver::Run::test_interval(const Phase& ph) const {
  if (ph.test_cost <= 0) return ph.stop_every;
  const double best = std::sqrt(2.0 * ph.test_cost * static_cast<double>(ph.k));
  return ph.stop_every * std::max<std::int64_t>(1, static_cast<std::int64_t>(best / static_cast<double>(ph.stop_every)));
}

bool Solver::Run::test_due(const Phase& ph) const {
  // A phase capped below --max-iter (dv-pipeline's smoothing and settling)
  // runs its iterations: its stopping rule could only end it early, and its
  // tests would cost more than they save.
  if (ph.free_early) return true;  // its own test fired: the Solver's exact test decides
  if (ph.cap < opt_.max_iter) return false;
  return ph.k % test_interval(ph) == 0 || ph.k == ph.cap;
}

bool Solver::Run::record_due(const Phase& ph) const {
  const std::int64_t every = ph.record_tests > 0 ? test_interval(ph) * ph.record_tests : ph.every;
  return ph.k % every == 0 || ph.k == ph.cap;
}

// Whether this pass needs the per-pass reduction: where it tests, records or
// ends the phase; where a checkpoint clock, a stop signal, a rule or an
// option reads every pass (papers, --grad-tol, --target-cost,
// --check-monotone, free-running methods); and every kFiniteEvery
// iterations. Elsewhere the reduction would only confirm that the iterate is
// finite, which the next of those passes does: one collective fewer per
// iteration, and the same iterates and stops (a non-finite iterate is found
// at most kFiniteEvery iterations later, on every rank at the same pass).
bool Solver::Run::reduce_due(const Phase& ph) const {
  constexpr std::int64_t kFiniteEvery = 50;
  if (!gradient_rule() || opt_.grad_tol > 0 || opt_.target_cost > 0 || opt_.check_monotone ||
      ph.alg->free_running() || ph.info->one_shot || ckpt_.stop_on_signal || (checkpointing_ && ckpt_.seconds > 0))
    return true;
  return test_due(ph) || record_due(ph) || ph.k == ph.cap || ph.k % kFiniteEvery == 0 ||
         (checkpointing_ && ckpt_.every > 0 && ph.k % ckpt_.every == 0);
}

bool Solver::Run::pass(Phase& ph) {
  iterate(ph, pass_length(ph));
  const double t0 = MPI_Wtime();
  PassResult r;
  if (reduce_due(ph))
    r = reduce(ph);
  else
    r.rel = NAN;
  if (gradient_rule() && r.finite && test_due(ph)) {
    r.rel_grad = relative_gradient(ph);
    ++sum_.gradient_tests;
  }
  if (opt_.target_cost > 0 && r.finite && test_due(ph)) r.objective = objective_of(*ph.alg);
  ph.stop_time += MPI_Wtime() - t0;
  if (!r.finite) return stop(ph, TerminationType::kFailure, "non-finite iterate");
  const bool converged = test_stop(ph, r);
  if (opt_.check_monotone && ph.info->monotone_surrogate) check_monotone(ph);
  const bool last = converged || ph.k == ph.cap;
  const double t1 = MPI_Wtime();
  const bool abort = (record_due(ph) || last) && record(ph, r);
  ph.record_time += MPI_Wtime() - t1;
  if (abort) return stop(ph, TerminationType::kUserAbort, "stopped by a callback");
  if (converged) {
    ph.term = TerminationType::kConvergence;
    return false;
  }
  // Checkpoint only while the phase goes on, so a resume never repeats a stop.
  if (checkpointing_ && !last && (r.signalled || r.clock || (ckpt_.every > 0 && ph.k % ckpt_.every == 0)))
    checkpoint(ph);
  if (r.signalled)
    return stop(ph, TerminationType::kSignal,
                checkpointing_ ? "stopped by a signal; checkpoint written to " + ckpt_.path
                               : "stopped by a signal (no --checkpoint given)");
  return true;
}

std::int64_t Solver::Run::pass_length(const Phase& ph) const {
  std::int64_t n = std::min({ph.block, ph.cap - ph.k, ph.every - ph.k % ph.every});
  if (checkpointing_ && ckpt_.every > 0) n = std::min(n, ckpt_.every - ph.k % ckpt_.every);
  return n;
}

void Solver::Run::iterate(Phase& ph, std::int64_t n) {
  test_delay("SNL_TEST_ITERATION_DELAY", static_cast<double>(n));  // tests/slurm: a job of known length
  const bool free = ph.alg->free_running();
  // --straggler-delay: one rank slowed per iteration (a free-running method sleeps per its own iterations).
  if (opt_.straggler_delay > 0 && !free && comm_rank(comm_) == straggler_rank(opt_, comm_))
    std::this_thread::sleep_for(std::chrono::duration<double>(opt_.straggler_delay * static_cast<double>(n)));
  const double w0 = halo_.wait_seconds(), ti = MPI_Wtime();
  // A rank-local failure (std::bad_alloc) while the others wait in the
  // iteration's collectives cannot be agreed on: it aborts every rank.
  abort_on_local_failure(comm_, "iteration", [&] {
    for (std::int64_t i = 1; i <= n; ++i) test_fail_point("solve", total_it_ + i);  // fault-injection tests
    ph.alg->iterate_levels(static_cast<int>(n));
  });
  ph.time += MPI_Wtime() - ti;
  iter_wait_ += halo_.wait_seconds() - w0;
  if (free) {
    const std::int64_t ran = ph.alg->levels_run();
    ph.free_early = ran < n;
    n = ran;
  }
  ph.k += n;
  total_it_ += n;
  for (std::int64_t i = 0; i < n; ++i) {  // summed as one iteration at a time
    messages_ += ph.alg->messages_per_iteration();
    reals_ += ph.alg->reals_per_iteration();
  }
}

// One reduction per pass: stopping sums, and flags every rank must agree on
// (a stop signal on any rank; rank 0's checkpoint clock), in one collective.
// The sums are exact (detail::ExactSum), so the stopping test is the same for
// any partition; the gradient is summed only where --grad-tol or a record
// needs it, and the change norms only where the papers rule or a record reads
// them: elsewhere they only check that the iterate is finite, which plain sums
// decide unless one comes near overflow (then every rank forms the exact ones).
Solver::Run::PassResult Solver::Run::reduce(Phase& ph) {
  const bool at_record = record_due(ph);
  const bool with_grad = opt_.grad_tol > 0 || at_record;
  const bool exact = opt_.stop != "gradient" || opt_.grad_tol > 0 || ph.info->one_shot || at_record;
  detail::ExactSum sums[3];  // ||x(k)-x(k-1)||^2, ||x(k)||^2, ||g||^2
  const bool plain_ok = add_stop_terms(ph, with_grad, exact, sums);
  // Summed over ranks: > 0 means "on some rank" (signal, clock, a plain sum not decisive).
  std::int64_t flags[3] = {(ckpt_.stop_on_signal && stop_signal_received()) ? 1 : 0,
                           (root_ && checkpointing_ && ckpt_.seconds > 0 && MPI_Wtime() - last_ckpt_ >= ckpt_.seconds) ? 1 : 0,
                           plain_ok ? 0 : 1};
  const int n_sums = !exact ? 0 : with_grad ? 3 : 2;
  detail::allreduce_exact(sums, n_sums, comm_, flags, 3);
  PassResult r;
  r.signalled = flags[0] > 0;
  r.clock = flags[1] > 0;
  r.has_gnorm = with_grad;
  if (!exact && flags[2] == 0) {  // every rank's plain sums finite and far from overflow
    r.rel = NAN;  // read by neither the gradient rule nor a record
    return r;
  }
  if (!exact) {  // with_grad is false here: the exact change norms, as below
    for (auto& t : sums) t.clear();
    add_stop_terms(ph, false, true, sums);
    detail::allreduce_exact(sums, 2, comm_);
  }
  const double d = sums[0].value(), x = sums[1].value();
  r.rel = x > 0 ? std::sqrt(d / x) : std::sqrt(d);
  r.gnorm = std::sqrt(sums[2].value());
  r.finite = std::isfinite(d) && std::isfinite(x);
  return r;
}

// This rank's terms of the stopping sums: per owned node where the method
// keeps x(k-1) and its gradient (the same terms for any partition), else the
// method's own partial sums. Without `exact` only the method's own sums are
// read (the relaxation's and MM's kernels form them as they write x(k), so
// this costs no pass over memory); returns whether they are finite and below
// 1e290, i.e. whether they show the exact sums over all ranks finite.
bool Solver::Run::add_stop_terms(Phase& ph, bool with_grad, bool exact, detail::ExactSum* sums) {
  const LocalId n = prob_.num_owned();
  const double* x = ph.alg->positions().data();
  if (!exact) {
    double d = 0, s = 0;
    ph.alg->change_norms(&d, &s);
    return d < 1e290 && s < 1e290;  // false for NaN
  }
  if (const double* prev = ph.alg->previous_positions()) {
    for (LocalId v = 0; v < n; ++v) {
      double dd = 0, xs = 0;
      for (int c = 0; c < p_; ++c) {
        const std::size_t t = std::size_t(v) * p_ + c;
        dd += (x[t] - prev[t]) * (x[t] - prev[t]);
        xs += x[t] * x[t];
      }
      sums[0].add(dd);
      sums[1].add(xs);
    }
  } else {
    double d = 0, s = 0;
    ph.alg->change_norms(&d, &s);
    sums[0].add(d);
    sums[1].add(s);
  }
  if (!with_grad || !std::isfinite(ph.alg->grad_norm_sq())) return true;
  const std::int64_t b0 = halo_.bytes_sent();  // a ghost exchange here is instrumentation
  const double* g = ph.alg->gradient_rows();
  instrumentation_bytes_ += halo_.bytes_sent() - b0;
  if (!g) {
    sums[2].add(ph.alg->grad_norm_sq());
    return true;
  }
  for (LocalId v = 0; v < n; ++v) {
    double gs = 0;
    for (int c = 0; c < p_; ++c) gs += g[std::size_t(v) * p_ + c] * g[std::size_t(v) * p_ + c];
    sums[2].add(gs);
  }
  return true;
}

// Collective: the gradient norm where the pass's reduction left it out.
double Solver::Run::grad_norm(Phase& ph) {
  detail::ExactSum sums[3];
  add_stop_terms(ph, true, true, sums);
  detail::allreduce_exact(&sums[2], 1, comm_);
  return std::sqrt(sums[2].value());
}

// Collective: ||grad c(x)|| / (2 sqrt f(x)) at the phase's positions, c the
// cost the phase minimizes (f for the refinements, f_hat for the others);
// both sums exact, so the test is the same for any partition. xs_ keeps the
// exchanged positions and f for a record at the same iteration.
double Solver::Run::relative_gradient(Phase& ph) {
  const LocalId n = prob_.num_owned();
  const auto& x = ph.alg->positions();
  std::copy(x.begin(), x.begin() + std::size_t(n) * p_, xs_.begin());
  const std::int64_t b0 = halo_.bytes_sent();
  halo_.exchange(xs_.data(), p_);
  instrumentation_bytes_ += halo_.bytes_sent() - b0;
  const AlgorithmId id = ph.info->id;
  const bool relaxed = !(id == AlgorithmId::kMM || id == AlgorithmId::kMMAccel || id == AlgorithmId::kBB ||
                         id == AlgorithmId::kMlAgd);
  // Most tests only have to say "not yet": plain sums in the lane kernels
  // settle that with a rounding bound, about two iterations' time instead of
  // a scalar pass with exact sums (about ten). A stop, a record (which keeps
  // f) and every undecided bound take the exact sums below, so the tests'
  // outcomes, and the iterates, are those of the exact test.
  if (bounded_test_allowed(ph)) {
    const detail::GradientBounds b =
        detail::bound_relative_gradient(prob_, *detail::shared_lanes(prob_), xs_.data(), relaxed, gs_.data());
    if (b.valid && b.lo > opt_.stop_tol()) {
      xs_iteration_ = -1;
      ++sum_.gradient_tests_bounded;
      return b.lo;
    }
  }
  xs_ml_ = detail::exact_ml_cost_and_gradient(prob_, xs_.data(), gs_.data(), relaxed);
  xs_iteration_ = total_it_;
  detail::ExactSum g;
  for (LocalId v = 0; v < n; ++v) {
    double s = 0;
    for (int c = 0; c < p_; ++c) s += gs_[std::size_t(v) * p_ + c] * gs_[std::size_t(v) * p_ + c];
    g.add(s);
  }
  detail::allreduce_exact(&g, 1, comm_);
  const double gn = std::sqrt(g.value());
  return xs_ml_ > 0 ? gn / (2.0 * std::sqrt(xs_ml_)) : gn;
}

// The bounded test needs the plain l2 model (the lane kernels' terms) and
// the lane layout, which it uses only where a phase has built it (it is a
// gigabyte per rank at 10^7); not where a record will want f exactly at
// these positions. SNL_TEST_GRADIENT_TEST=bounded|exact: tests choose
// (bounded: wherever the model allows, layout built if need be).
bool Solver::Run::bounded_test_allowed(const Phase& ph) const {
  const char* choice = std::getenv("SNL_TEST_GRADIENT_TEST");
  if (prob_.model().active() || (choice && std::strcmp(choice, "exact") == 0)) return false;
  if (choice && std::strcmp(choice, "bounded") == 0) return true;
  return prob_.derived_cache() != nullptr && ph.k != ph.cap && !record_due(ph);
}

bool Solver::Run::test_stop(Phase& ph, const PassResult& r) const {
  if (ph.info->one_shot) {
    ph.msg = "solved";
    return true;
  }
  if (opt_.stop == "gradient") {
    if (r.rel_grad <= opt_.stop_tol()) {  // NaN (not tested here) compares false
      ph.msg = "relative gradient " + std::to_string(r.rel_grad) + " <= tol";
      return true;
    }
  } else if (opt_.stop_tol() > 0 && r.rel <= opt_.stop_tol()) {
    ph.msg = "relative improvement " + std::to_string(r.rel) + " <= tol";
    return true;
  }
  if (r.objective <= opt_.target_cost) {  // NaN (not tested) compares false
    ph.msg = "objective " + std::to_string(r.objective) + " <= --target-cost";
    return true;
  }
  if (opt_.grad_tol > 0 && std::isfinite(ph.alg->grad_norm_sq()) && r.gnorm <= opt_.grad_tol) {
    ph.msg = "gradient norm " + std::to_string(r.gnorm) + " <= grad_tol";
    return true;
  }
  return false;
}

void Solver::Run::check_monotone(Phase& ph) {
  const double f = objective_of(*ph.alg);
  // Rounding floor: at an exact fit (sigma = 0) F is ~1e-31 and jitters.
  if (f > ph.prev_obj * (1 + 1e-12) + 1e-24)
    throw Error("MM surrogate increased at iteration " + std::to_string(ph.k) + ": " + std::to_string(ph.prev_obj) +
                " -> " + std::to_string(f));
  ph.prev_obj = f;
}

void Solver::Run::record_start(const Phase& ph) {
  IterationSummary it;
  it.phase = ph.alg->name();
  it.total_iteration = total_it_;
  it.cost = ph.prev_obj;
  it.messages = messages_;
  it.reals = reals_;
  it.elapsed = MPI_Wtime() - t0_;
  metrics_at(ph.alg->positions(), it);
  sum_.history.push_back(it);
}

bool Solver::Run::record(Phase& ph, const PassResult& r) {
  IterationSummary it;
  it.phase = ph.alg->name();
  it.iteration = ph.k;
  it.total_iteration = total_it_;
  // f where the gradient test has just formed it at these positions.
  it.cost = xs_iteration_ == total_it_ && ph.alg->objective_is_ml_cost() ? xs_ml_ : objective_of(*ph.alg);
  it.rel_change = r.rel;
  it.grad_norm = !std::isfinite(ph.alg->grad_norm_sq()) ? NAN : r.has_gnorm ? r.gnorm : grad_norm(ph);
  it.messages = messages_;
  it.reals = reals_;
  it.elapsed = MPI_Wtime() - t0_;
  metrics_at(ph.alg->positions(), it);
  sum_.history.push_back(it);
  bool abort = false;
  for (auto* cb : s_.callbacks_) abort |= (*cb)(it) == CallbackReturn::kAbort;
  return abort;
}

void Solver::Run::checkpoint(const Phase& ph) {
  CheckpointHeader h;
  h.network_fingerprint = ckpt_.network_fingerprint;
  h.options = s_.options_fingerprint();
  h.algorithm = opt_.algorithm;
  h.phase = static_cast<std::int64_t>(ph.index);
  h.phase_algorithm = ph.alg->name();
  h.phase_iteration = ph.k;
  h.total_iteration = total_it_;
  h.messages = messages_;
  h.reals = reals_;
  h.elapsed = MPI_Wtime() - t0_;
  h.ranks = comm_size(comm_);
  h.num_sensors = prob_.num_sensors();
  h.dim = p_;
  write_checkpoint(ckpt_.path, prob_, h, sum_.history, *ph.alg);
  last_ckpt_ = MPI_Wtime();
}

bool Solver::Run::stop(Phase& ph, TerminationType t, std::string msg) {
  ph.term = t;
  ph.msg = std::move(msg);
  stop_all_ = true;
  return false;
}

// The phase's times and result; x_ takes its final positions (the next phase's start).
void Solver::Run::end_phase(Phase& ph) {
  iter_time_ += ph.time;
  stop_time_ += ph.stop_time;
  method_bytes_ += ph.alg->bytes_sent();
  record_time_ += ph.record_time;
  double g = 0;
  MPI_Allreduce(&ph.time, &g, 1, MPI_DOUBLE, MPI_MAX, comm_);
  sum_.phase_iterate_seconds.emplace_back(ph.alg->name(), g);
  if (ph.term == TerminationType::kNoConvergence)
    ph.msg = ph.cap < opt_.max_iter ? "ran its " + std::to_string(ph.cap) + " iterations (--smooth-iter, --settle-iter)"
                                    : "reached --max-iter";
  const auto& xp = ph.alg->positions();
  std::copy(xp.begin(), xp.begin() + std::size_t(prob_.num_owned()) * p_, x_.begin());
  if (ph.info->gap_certificate && find_algorithm(opt_.algorithm)->gap_certificate) {
    xs_iteration_ = -1;
    std::copy(x_.begin(), x_.end(), xs_.begin());
    const std::int64_t b1 = halo_.bytes_sent();
    halo_.exchange(xs_.data(), p_);
    instrumentation_bytes_ += halo_.bytes_sent() - b1;
    const CostTerms c = detail::exact_costs(prob_, xs_.data(), detail::kAllSums);
    sum_.gap_certificate = c.certificate;
    sum_.relaxed_optimum = c.relaxed;
  }
  sum_.final_cost = objective_of(*ph.alg);
  sum_.method_values.clear();
  sum_.method_texts.clear();
  ph.alg->report(&sum_.method_values, &sum_.method_texts);
  sum_.termination = ph.term;
  sum_.message = phases_.size() > 1 ? ph.alg->name() + ": " + ph.msg : ph.msg;
  sum_.converged = ph.term == TerminationType::kConvergence;
}

// Final metrics at the solution, traffic and times over all ranks.
Summary Solver::Run::finish(std::vector<double>* x_out) {
  sum_.iterations = total_it_;
  xs_iteration_ = -1;
  std::copy(x_.begin(), x_.end(), xs_.begin());
  const std::int64_t b0 = halo_.bytes_sent();
  halo_.exchange(xs_.data(), p_);
  sum_.costs = detail::exact_costs(prob_, xs_.data(), detail::kAllSums);
  sum_.errors = evaluate_errors(prob_, xs_.data());
  instrumentation_bytes_ += halo_.bytes_sent() - b0;
  sum_.messages_per_sensor = messages_;
  sum_.reals_per_sensor = reals_;
  long long mine = halo_.bytes_sent() - instrumentation_bytes_ + method_bytes_, all = 0;
  MPI_Allreduce(&mine, &all, 1, MPI_LONG_LONG, MPI_SUM, comm_);
  sum_.mpi_bytes = all;
  sum_.wall_seconds = MPI_Wtime() - t0_;
  double wf = sum_.wall_seconds > 0 ? halo_.wait_seconds() / sum_.wall_seconds : 0, wfm = 0;
  MPI_Allreduce(&wf, &wfm, 1, MPI_DOUBLE, MPI_MAX, comm_);
  sum_.comm_wait_fraction = wfm;
  double it_loc[4] = {iter_time_, iter_wait_, stop_time_, record_time_}, it_max[4];
  MPI_Allreduce(it_loc, it_max, 4, MPI_DOUBLE, MPI_MAX, comm_);
  sum_.iterate_seconds = it_max[0];
  sum_.iterate_wait_seconds = it_max[1];
  sum_.stop_test_seconds = it_max[2];
  sum_.record_seconds = it_max[3];
  if (x_out) *x_out = x_;
  return std::move(sum_);
}

void Solver::Run::metrics_at(const std::vector<double>& x, IterationSummary& it) {
  const std::int64_t b0 = halo_.bytes_sent();
  if (xs_iteration_ == total_it_) {  // the stopping test has just evaluated these positions
    it.ml_cost = xs_ml_;
  } else {
    std::copy(x.begin(), x.begin() + std::size_t(prob_.num_owned()) * p_, xs_.begin());
    halo_.exchange(xs_.data(), p_);
    it.ml_cost = detail::exact_costs(prob_, xs_.data(), detail::kMlSum).ml;
  }
  const ErrorMetrics em = evaluate_errors(prob_, xs_.data());
  it.rmse = em.rmse;
  it.mpe = em.mpe;
  instrumentation_bytes_ += halo_.bytes_sent() - b0;
}

// The method's objective; its halo exchange is instrumentation, not the method's traffic.
double Solver::Run::objective_of(Algorithm& alg) {
  const std::int64_t b0 = halo_.bytes_sent();
  const double f = alg.objective();
  instrumentation_bytes_ += halo_.bytes_sent() - b0;
  return f;
}

}  // namespace snl
