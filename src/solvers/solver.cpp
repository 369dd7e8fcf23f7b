#include "snl/solvers/solver.hpp"

#include <mpi.h>

#include <algorithm>
#include <cstdlib>
#include <iterator>
#include <cstdio>
#include <sstream>

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

namespace {
const char* const kAlgorithmNames[] = {"relaxation", "mm", "bb", "pm", "async", "async-exact"};
}  // namespace

int algorithm_code(const std::string& name) {
  for (int c = 0; c < 6; ++c)
    if (name == kAlgorithmNames[c]) return c;
  return 9;
}

const char* algorithm_name(int code) { return code >= 0 && code < 6 ? kAlgorithmNames[code] : "?"; }

std::string SolverOptions::validate() const {
  static const char* known[] = {"relaxation", "mm", "pipeline", "bb", "pm", "async", "async-exact"};
  if (std::find_if(std::begin(known), std::end(known), [&](const char* k) { return algorithm == k; }) ==
      std::end(known))
    return "unknown --algorithm '" + algorithm + "' (expected relaxation, mm, pipeline, bb, pm, async or async-exact)";
  if (max_iter < 0) return "--max-iter must be >= 0";
  if (!(tol >= 0) || !std::isfinite(tol)) return "--tol must be a finite number >= 0";
  if (!(grad_tol >= 0) || !std::isfinite(grad_tol)) return "--grad-tol must be a finite number >= 0";
  if (history_every < 0) return "--history-every must be >= 0";
  if (bb_rounds < 1 || bb_rounds > 10000) return "--bb-rounds must be in [1, 10000]";
  if (temporal_block < 1 || temporal_block > 64) return "--temporal-block must be in [1, 64]";
  return "";
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

Solver::Solver(LocalizationProblem& prob, SolverOptions opt) : prob_(prob), opt_(std::move(opt)) {
  const std::string err = opt_.validate();
  if (!err.empty()) throw Error(err);
}

namespace {



// History as columns (checkpoints) and back.
const char* kHistoryColumns[] = {"phase",     "iteration", "total_iteration", "cost",  "ml_cost", "rel_change",
                                 "grad_norm", "rmse",      "mpe",             "messages", "reals", "elapsed"};

std::vector<double> history_column(const std::vector<IterationSummary>& h, int c) {
  std::vector<double> v;
  v.reserve(h.size());
  for (const auto& it : h) {
    const double vals[] = {double(algorithm_code(it.phase)), double(it.iteration), double(it.total_iteration), it.cost,
                           it.ml_cost, it.rel_change, it.grad_norm, it.rmse, it.mpe, it.messages, it.reals,
                           it.elapsed};
    v.push_back(vals[c]);
  }
  return v;
}

}  // namespace

std::string Solver::options_fingerprint() const {
  std::ostringstream os;
  os.precision(17);
  os << opt_.algorithm << "|max_iter=" << opt_.max_iter << "|tol=" << opt_.tol << "|grad_tol=" << opt_.grad_tol
     << "|history_every=" << opt_.history_every << "|bb_rounds=" << opt_.bb_rounds;
  // Only when on, so that earlier checkpoints still match.
  if (opt_.temporal_block != 1) os << "|temporal_block=" << opt_.temporal_block;
  return os.str();
}

Summary Solver::solve(const std::vector<double>& x0, std::vector<double>* x_out) {
  MPI_Comm comm = prob_.comm();
  const int p = prob_.dim();
  const bool root = comm_rank(comm) == 0;
  double t0 = MPI_Wtime();
  HaloPlan& halo = prob_.graph().halo();
  halo.reset_counters();
  std::int64_t instrumentation_bytes = 0;

  Summary sum;
  sum.algorithm = opt_.algorithm;
  sum.ranks = comm_size(comm);
  std::vector<std::string> phases;
  if (opt_.algorithm == "pipeline")
    phases = {"relaxation", "mm"};
  else
    phases = {opt_.algorithm};

  // Scratch for metrics: a local array whose ghost rows the metrics exchange.
  std::vector<double> xs(std::size_t(prob_.num_local()) * p, 0.0);
  auto metrics_at = [&](const std::vector<double>& x, IterationSummary& it) {
    const std::int64_t b0 = halo.bytes_sent();
    std::copy(x.begin(), x.begin() + std::size_t(prob_.num_owned()) * p, xs.begin());
    halo.exchange(xs.data(), p);
    it.ml_cost = evaluate_costs(prob_, xs.data()).ml;
    const ErrorMetrics em = evaluate_errors(prob_, xs.data());
    it.rmse = em.rmse;
    it.mpe = em.mpe;
    instrumentation_bytes += halo.bytes_sent() - b0;
  };
  auto objective_of = [&](Algorithm& alg) {
    const std::int64_t b0 = halo.bytes_sent();
    const double f = alg.objective();
    instrumentation_bytes += halo.bytes_sent() - b0;
    return f;
  };

  std::vector<double> x = x0;
  x.resize(std::size_t(prob_.num_owned()) * p);
  double messages = 0, reals = 0;
  std::int64_t total_it = 0;
  std::size_t first_phase = 0;
  std::int64_t resume_k = -1;  // >= 0: resume phase first_phase at this iteration

  // ---- restart: verify the checkpoint matches this network and these options.
  std::unique_ptr<H5File> restart_file;
  if (!ckpt_.restart.empty()) {
    restart_file = std::make_unique<H5File>(ckpt_.restart, comm, H5File::Mode::kRead);
    H5File& f = *restart_file;
    const std::string what = ckpt_.restart + ": ";
    if (!f.has_attr("format") || f.attr_string("format") != "snl-checkpoint")
      throw Error(what + "not an snl checkpoint (attribute format != snl-checkpoint)");
    if (f.attr_int("version") != 1) throw Error(what + "unsupported checkpoint version");
    if (f.attr_string("network_fingerprint") != ckpt_.network_fingerprint)
      throw Error(what + "checkpoint of another network (fingerprint " + f.attr_string("network_fingerprint") +
                  ", this network " + ckpt_.network_fingerprint + ")");
    if (f.attr_string("options") != options_fingerprint())
      throw Error(what + "checkpoint of incompatible options (" + f.attr_string("options") + "; now " +
                  options_fingerprint() + ")");
    first_phase = static_cast<std::size_t>(f.attr_int("phase"));
    resume_k = f.attr_int("phase_iteration");
    total_it = f.attr_int("total_iteration");
    messages = f.attr_double("messages");
    reals = f.attr_double("reals");
    t0 -= f.attr_double("elapsed");
    if (first_phase >= phases.size() || resume_k < 0 || resume_k > opt_.max_iter)
      throw Error(what + "checkpoint state out of range");
    std::vector<std::vector<double>> cols;
    const auto len = f.shape("history/phase");
    for (const char* c : kHistoryColumns) {
      cols.push_back(f.read_rows_double(std::string("history/") + c, 0, len.empty() ? 0 : len[0]));
      if (cols.back().size() != cols.front().size()) throw Error(what + "malformed history");
    }
    for (std::size_t r = 0; r < cols[0].size(); ++r) {
      IterationSummary it;
      it.phase = algorithm_name(static_cast<int>(cols[0][r]));
      it.iteration = static_cast<std::int64_t>(cols[1][r]);
      it.total_iteration = static_cast<std::int64_t>(cols[2][r]);
      it.cost = cols[3][r];
      it.ml_cost = cols[4][r];
      it.rel_change = cols[5][r];
      it.grad_norm = cols[6][r];
      it.rmse = cols[7][r];
      it.mpe = cols[8][r];
      it.messages = cols[9][r];
      it.reals = cols[10][r];
      it.elapsed = cols[11][r];
      sum.history.push_back(it);
    }
  }

  static const double delay = [] {
    const char* d = std::getenv("SNL_TEST_CHECKPOINT_DELAY");  // test hook: a slow checkpoint write
    return d ? std::atof(d) : 0.0;
  }();
  double last_ckpt = MPI_Wtime();
  auto write_checkpoint = [&](const Algorithm& alg, std::size_t ph, std::int64_t k) {
    H5File f(ckpt_.path, comm, H5File::Mode::kCreate);
    f.set_attr("format", std::string("snl-checkpoint"));
    f.set_attr("version", std::int64_t(1));
    f.set_attr("network_fingerprint", ckpt_.network_fingerprint);
    f.set_attr("options", options_fingerprint());
    f.set_attr("algorithm", opt_.algorithm);
    f.set_attr("phase", std::int64_t(ph));
    f.set_attr("phase_algorithm", alg.name());
    f.set_attr("phase_iteration", k);
    f.set_attr("total_iteration", total_it);
    f.set_attr("messages", messages);
    f.set_attr("reals", reals);
    f.set_attr("elapsed", MPI_Wtime() - t0);
    f.set_attr("ranks", std::int64_t(comm_size(comm)));
    f.set_attr("num_sensors", std::int64_t(prob_.num_sensors()));
    f.set_attr("dim", std::int64_t(p));
    for (int c = 0; c < static_cast<int>(std::size(kHistoryColumns)); ++c)
      f.write_replicated(std::string("history/") + kHistoryColumns[c], history_column(sum.history, c));
    StateWriter w(f, prob_);
    alg.save(w);
    if (delay > 0) {
      MPI_Barrier(comm);
      const double until = MPI_Wtime() + delay;
      while (MPI_Wtime() < until) {
      }
    }
    f.commit();
    last_ckpt = MPI_Wtime();
  };
  const bool checkpointing = !ckpt_.path.empty();

  bool stop_all = false;
  double iter_time = 0, iter_wait = 0;
  for (std::size_t ph = first_phase; ph < phases.size() && !stop_all; ++ph) {
    std::unique_ptr<Algorithm> alg = make_algorithm(phases[ph], prob_, opt_);
    alg->start(x);
    {
      long long b = alg->memory_bytes(), all = 0;
      MPI_Allreduce(&b, &all, 1, MPI_LONG_LONG, MPI_SUM, comm);
      sum.algorithm_state_bytes = std::max<std::int64_t>(sum.algorithm_state_bytes, all);
      double tb = alg->traffic_bytes_per_iteration(), tb_all = 0;
      MPI_Allreduce(&tb, &tb_all, 1, MPI_DOUBLE, MPI_SUM, comm);
      sum.phase_traffic_bytes.emplace_back(phases[ph], tb_all);
    }
    double phase_time = 0;
    std::int64_t k = 0;
    if (restart_file && ph == first_phase) {
      alg->load(StateReader(*restart_file, prob_));
      k = resume_k;
      restart_file.reset();
    }
    sum.lipschitz = alg->lipschitz();
    // Auto: every iteration for small runs; about 1000 records per phase for
    // long ones; at least every 10 iterations on large networks, where a
    // record (an extra exchange and two reductions) costs about an iteration.
    std::int64_t every = opt_.history_every;
    if (every <= 0) {
      every = opt_.max_iter <= 2000 ? 1 : (opt_.max_iter + 999) / 1000;
      if (prob_.num_sensors() > 100000) every = std::max<std::int64_t>(every, 10);
    }
    // Temporal blocking: passes of up to `block` iterations, ending at every
    // record and checkpoint iteration (so these see the same iterates); the
    // automatic record interval becomes a multiple of the pass.
    const std::int64_t block = std::max(1, std::min(opt_.temporal_block, alg->max_levels()));
    if (opt_.history_every <= 0) every = (every + block - 1) / block * block;
    double prev_obj = objective_of(*alg);
    if (k == 0) {
      sum.initial_cost = prev_obj;
      IterationSummary it;
      it.phase = alg->name();
      it.total_iteration = total_it;
      it.cost = prev_obj;
      it.messages = messages;
      it.reals = reals;
      it.elapsed = MPI_Wtime() - t0;
      metrics_at(alg->positions(), it);
      sum.history.push_back(it);
    }
    TerminationType term = TerminationType::kNoConvergence;
    std::string msg;
    while (k < opt_.max_iter) {
      std::int64_t n = std::min({block, opt_.max_iter - k, every - k % every});  // iterations in this pass
      if (checkpointing && ckpt_.every > 0) n = std::min(n, ckpt_.every - k % ckpt_.every);
      const double w0 = halo.wait_seconds(), ti = MPI_Wtime();
      // A rank-local failure (std::bad_alloc) while the others wait in the
      // iteration's collectives cannot be agreed on: it aborts every rank.
      abort_on_local_failure(comm, "iteration", [&] {
        for (std::int64_t i = 1; i <= n; ++i) test_fail_point("solve", total_it + i);  // fault-injection tests
        alg->iterate_levels(static_cast<int>(n));
      });
      const double dt = MPI_Wtime() - ti;
      phase_time += dt;
      iter_wait += halo.wait_seconds() - w0;
      k += n;
      total_it += n;
      for (std::int64_t i = 0; i < n; ++i) {  // summed as one iteration at a time
        messages += alg->messages_per_iteration();
        reals += alg->reals_per_iteration();
      }
      // One reduction per pass: stopping sums, and flags every rank must
      // agree on (a stop signal on any rank; rank 0's checkpoint clock).
      double loc[5] = {0, 0, 0, 0, 0}, glob[5];
      alg->change_norms(&loc[0], &loc[1]);
      loc[2] = alg->grad_norm_sq();
      if (!std::isfinite(loc[2])) loc[2] = 0;
      loc[3] = (ckpt_.stop_on_signal && stop_signal_received()) ? 1 : 0;
      loc[4] = (root && checkpointing && ckpt_.seconds > 0 && MPI_Wtime() - last_ckpt >= ckpt_.seconds) ? 1 : 0;
      MPI_Allreduce(loc, glob, 3, MPI_DOUBLE, MPI_SUM, comm);
      MPI_Allreduce(loc + 3, glob + 3, 2, MPI_DOUBLE, MPI_MAX, comm);
      const double rel = glob[1] > 0 ? std::sqrt(glob[0] / glob[1]) : std::sqrt(glob[0]);
      const double gnorm = std::sqrt(glob[2]);
      if (!std::isfinite(glob[0]) || !std::isfinite(glob[1])) {
        term = TerminationType::kFailure;
        msg = "non-finite iterate";
        stop_all = true;
        break;
      }
      bool converged = false;
      if (opt_.tol > 0 && rel <= opt_.tol) {
        converged = true;
        msg = "relative improvement " + std::to_string(rel) + " <= tol";
      } else if (opt_.grad_tol > 0 && std::isfinite(alg->grad_norm_sq()) && gnorm <= opt_.grad_tol) {
        converged = true;
        msg = "gradient norm " + std::to_string(gnorm) + " <= grad_tol";
      }
      if (opt_.check_monotone && alg->name() == "mm") {
        const double f = objective_of(*alg);
        // Rounding floor: at an exact fit (sigma = 0) F is ~1e-31 and jitters.
        if (f > prev_obj * (1 + 1e-12) + 1e-24)
          throw Error("MM surrogate increased at iteration " + std::to_string(k) + ": " + std::to_string(prev_obj) +
                      " -> " + std::to_string(f));
        prev_obj = f;
      }
      const bool last = converged || k == opt_.max_iter;
      if (k % every == 0 || last) {
        IterationSummary it;
        it.phase = alg->name();
        it.iteration = k;
        it.total_iteration = total_it;
        it.cost = objective_of(*alg);
        it.rel_change = rel;
        it.grad_norm = std::isfinite(alg->grad_norm_sq()) ? gnorm : NAN;
        it.messages = messages;
        it.reals = reals;
        it.elapsed = MPI_Wtime() - t0;
        metrics_at(alg->positions(), it);
        sum.history.push_back(it);
        bool abort = false;
        for (auto* cb : callbacks_) abort |= (*cb)(it) == CallbackReturn::kAbort;
        if (abort) {
          term = TerminationType::kUserAbort;
          msg = "stopped by a callback";
          stop_all = true;
          break;
        }
      }
      if (converged) {
        term = TerminationType::kConvergence;
        break;
      }
      // Checkpoint only while the phase goes on, so a resume never repeats a stop.
      const bool signalled = glob[3] > 0;
      if (checkpointing && !last &&
          (signalled || glob[4] > 0 || (ckpt_.every > 0 && k % ckpt_.every == 0)))
        write_checkpoint(*alg, ph, k);
      if (signalled) {
        term = TerminationType::kSignal;
        msg = checkpointing ? "stopped by a signal; checkpoint written to " + ckpt_.path
                            : "stopped by a signal (no --checkpoint given)";
        stop_all = true;
        break;
      }
    }
    iter_time += phase_time;
    {
      double g = 0;
      MPI_Allreduce(&phase_time, &g, 1, MPI_DOUBLE, MPI_MAX, comm);
      sum.phase_iterate_seconds.emplace_back(alg->name(), g);
    }
    if (term == TerminationType::kNoConvergence) msg = "reached --max-iter";
    const auto& xp = alg->positions();
    std::copy(xp.begin(), xp.begin() + std::size_t(prob_.num_owned()) * p, x.begin());
    if (alg->name() == "relaxation") {
      std::copy(x.begin(), x.end(), xs.begin());
      const std::int64_t b1 = halo.bytes_sent();
      halo.exchange(xs.data(), p);
      instrumentation_bytes += halo.bytes_sent() - b1;
      const CostTerms c = evaluate_costs(prob_, xs.data());
      sum.gap_certificate = c.certificate;
      sum.relaxed_optimum = c.relaxed;
    }
    sum.final_cost = objective_of(*alg);
    sum.termination = term;
    sum.message = phases.size() > 1 ? alg->name() + ": " + msg : msg;
    sum.converged = term == TerminationType::kConvergence;
  }
  sum.iterations = total_it;

  // Final metrics at the solution.
  std::copy(x.begin(), x.end(), xs.begin());
  const std::int64_t b0 = halo.bytes_sent();
  halo.exchange(xs.data(), p);
  sum.costs = evaluate_costs(prob_, xs.data());
  sum.errors = evaluate_errors(prob_, xs.data());
  instrumentation_bytes += halo.bytes_sent() - b0;
  sum.messages_per_sensor = messages;
  sum.reals_per_sensor = reals;
  long long mine = halo.bytes_sent() - instrumentation_bytes, all = 0;
  MPI_Allreduce(&mine, &all, 1, MPI_LONG_LONG, MPI_SUM, comm);
  sum.mpi_bytes = all;
  sum.wall_seconds = MPI_Wtime() - t0;
  double wf = sum.wall_seconds > 0 ? halo.wait_seconds() / sum.wall_seconds : 0, wfm = 0;
  MPI_Allreduce(&wf, &wfm, 1, MPI_DOUBLE, MPI_MAX, comm);
  sum.comm_wait_fraction = wfm;
  double it_loc[2] = {iter_time, iter_wait}, it_max[2];
  MPI_Allreduce(it_loc, it_max, 2, MPI_DOUBLE, MPI_MAX, comm);
  sum.iterate_seconds = it_max[0];
  sum.iterate_wait_seconds = it_max[1];
  if (x_out) *x_out = x;
  return sum;
}

}  // namespace snl
