#include "snl/solver.hpp"

#include <mpi.h>

#include <algorithm>
#include <cstdio>
#include <sstream>

#include "snl/mpi_util.hpp"

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
  static const char* known[] = {"relaxation", "mm", "pipeline", "bb"};
  if (std::find_if(std::begin(known), std::end(known), [&](const char* k) { return algorithm == k; }) ==
      std::end(known))
    return "unknown --algorithm '" + algorithm + "' (expected relaxation, mm, pipeline or bb)";
  if (max_iter < 0) return "--max-iter must be >= 0";
  if (!(tol >= 0) || !std::isfinite(tol)) return "--tol must be a finite number >= 0";
  if (!(grad_tol >= 0) || !std::isfinite(grad_tol)) return "--grad-tol must be a finite number >= 0";
  if (history_every < 0) return "--history-every must be >= 0";
  if (bb_rounds < 1 || bb_rounds > 10000) return "--bb-rounds must be in [1, 10000]";
  return "";
}

std::string Summary::brief_report() const {
  std::ostringstream os;
  os << "snl " << algorithm << ": " << to_string(termination) << " after " << iterations << " iterations";
  if (!message.empty()) os << " (" << message << ")";
  os.precision(6);
  os << "\n  ML cost " << costs.ml << ", relaxed cost " << costs.relaxed << ", gap certificate (eq. 22) "
     << costs.certificate << ", a-priori bound (eq. 23) " << costs.apriori;
  if (errors.valid) os << "\n  RMSE " << errors.rmse << ", MPE " << errors.mpe;
  os << "\n  communications per sensor: " << messages_per_sensor << " messages, " << reals_per_sensor
     << " reals; MPI bytes " << mpi_bytes << "; " << wall_seconds << " s on " << ranks << " ranks";
  return os.str();
}

Solver::Solver(LocalizationProblem& prob, SolverOptions opt) : prob_(prob), opt_(std::move(opt)) {
  const std::string err = opt_.validate();
  if (!err.empty()) throw Error(err);
}

Summary Solver::solve(const std::vector<double>& x0, std::vector<double>* x_out) {
  MPI_Comm comm = prob_.comm();
  const int p = prob_.dim();
  const double t0 = MPI_Wtime();
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
  double messages = 0, reals = 0;
  std::int64_t total_it = 0;
  bool stop_all = false;
  for (std::size_t ph = 0; ph < phases.size() && !stop_all; ++ph) {
    std::unique_ptr<Algorithm> alg = make_algorithm(phases[ph], prob_, opt_);
    alg->start(x);
    sum.lipschitz = alg->lipschitz();
    const std::int64_t every =
        opt_.history_every > 0 ? opt_.history_every : (opt_.max_iter <= 2000 ? 1 : (opt_.max_iter + 999) / 1000);
    double prev_obj = objective_of(*alg);
    sum.initial_cost = prev_obj;
    {
      IterationSummary it;
      it.phase = alg->name();
      it.iteration = 0;
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
    std::int64_t k = 0;
    while (k < opt_.max_iter) {
      alg->iterate();
      ++k;
      ++total_it;
      messages += alg->messages_per_iteration();
      reals += alg->reals_per_iteration();
      // Stopping quantities: one reduction of three sums.
      double loc[3] = {0, 0, 0}, glob[3];
      alg->change_norms(&loc[0], &loc[1]);
      loc[2] = alg->grad_norm_sq();
      if (!std::isfinite(loc[2])) loc[2] = 0;
      MPI_Allreduce(loc, glob, 3, MPI_DOUBLE, MPI_SUM, comm);
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
        if (f > prev_obj * (1 + 1e-12) + 1e-300)
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
    }
    if (term == TerminationType::kNoConvergence) msg = "reached --max-iter";
    const auto& xp = alg->positions();
    std::copy(xp.begin(), xp.begin() + std::size_t(prob_.num_owned()) * p, x.begin());
    sum.final_cost = objective_of(*alg);
    sum.termination = term;
    sum.message = ph + 1 < phases.size() ? msg : (phases.size() > 1 ? alg->name() + ": " + msg : msg);
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
  if (x_out) *x_out = x;
  return sum;
}

}  // namespace snl
