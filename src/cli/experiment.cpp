// Monte Carlo driver: a fixed network geometry, many noise draws per sigma,
// the relaxation (003) to its stopping rule, then each refinement method
// (MM of 000, the BB baseline) from the relaxation output under a budget of
// communications. One tidy CSV row per (sigma, trial, algorithm).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <tuple>
#include <sstream>

#include "core/json.hpp"
#include "snl/cli/commands.hpp"
#include "snl/core/mpi_util.hpp"
#include "snl/core/random.hpp"
#include "snl/io/h5file.hpp"
#include "snl/io/network.hpp"

namespace snl {

namespace {

struct Row {
  double sigma;
  int trial;
  std::string algorithm;
  std::int64_t iterations;
  double messages, reals, ml_start, ml, rmse, mpe;
  double fhat, objective;  ///< f_hat (003 eq. 6) at the final point; the method's own objective there
};

struct Agg {
  double mpe = 0, rmse2 = 0, ml = 0, reals = 0;
  int count = 0, worse = 0;
  double reach_reals = 0;  // communications to come within reach_rel of the best final cost
  int reach_count = 0, reach_trials = 0;
};

std::string csv_num(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.10g", v);
  return b;
}

using Trajectories = std::map<std::tuple<std::size_t, int, std::string>, std::vector<std::pair<double, double>>>;
using Aggregates = std::map<std::pair<double, std::string>, Agg>;

// Everything the trials produce: one row per (sigma, trial, algorithm); each
// run's (reals, ML cost) trajectory; the trajectory CSV (when asked for).
struct Study {
  std::vector<Row> rows;
  Trajectories trajectories;
  std::ostringstream traj;
};

void check_experiment_command(const ExperimentCommand& cmd, MPI_Comm comm) {
  if (cmd.trials < 1) throw Error("--trials must be >= 1");
  if (cmd.sigmas.empty()) throw Error("--sigmas needs at least one value");
  for (double s : cmd.sigmas)
    if (!(s >= 0) || !std::isfinite(s)) throw Error("--sigmas must be finite and >= 0");
  if (!(cmd.budget > 0)) throw Error("--budget must be > 0");
  for (const auto& a : cmd.algorithms)
    if (!find_algorithm(a) || find_algorithm(a)->phases.size() != 1)
      throw Error("--algorithms takes " + algorithm_names(", ", "", true));
  for (const auto& a : cmd.algorithms)
    if (find_algorithm(a)->one_shot)
      throw Error("--algorithms " + a + ": a centralized relaxation has no communications to budget (run it with snl solve)");
  if (cmd.start != "relaxation" && cmd.start != "random") throw Error("--start must be relaxation or random");
  // The relaxation rows are the starting points: a second run labelled the
  // same would be mixed into the same aggregate row (twice the trials).
  if (cmd.start == "relaxation" &&
      std::count(cmd.algorithms.begin(), cmd.algorithms.end(), algorithm_info(AlgorithmId::kRelaxation).name))
    throw Error("--algorithms relaxation needs --start random (with --start relaxation it is the starting point)");
  if (!(cmd.tol >= 0)) throw Error("--tol must be >= 0");
  check_output_path(cmd.output, comm, {{"the network", cmd.network}});
  if (!cmd.trajectory.empty())
    check_output_path(cmd.trajectory, comm, {{"the network", cmd.network}, {"the output", cmd.output}});
  if (!cmd.h5.empty())
    check_output_path(cmd.h5, comm, {{"the network", cmd.network}, {"the output", cmd.output},
                                     {"--trajectory", cmd.trajectory}});
}

std::unique_ptr<LocalizationProblem> load_geometry(const ExperimentCommand& cmd, MPI_Comm comm) {
  Network slab = read_network(cmd.network, comm);
  if (!slab.has_truth) throw Error(cmd.network + ": the experiment needs true positions (dataset truth)");
  if (slab.num_anchors() == 0) throw Error(cmd.network + ": the network has no anchors");
  std::unique_ptr<LocalizationProblem> prob;
  collective_try(comm, [&] {
    prob = std::make_unique<LocalizationProblem>(comm, slab, parse_partition_method(cmd.partition), nullptr);
  });
  return prob;
}

// One refinement method from xr under the communications budget.
void run_method(const ExperimentCommand& cmd, LocalizationProblem& prob, std::size_t si, int t, std::uint64_t key,
                const std::string& alg, const std::vector<double>& xr, double ml_start, Study& study) {
  const double sigma = cmd.sigmas[si];
  const AlgorithmInfo& info = *find_algorithm(alg);
  SolverOptions o;
  o.algorithm = alg;
  o.stop = "papers";  // the papers' experiments, with their rule
  o.tol = cmd.tol;
  o.seed = key;
  if (info.consensus_rounds) o.bb_rounds = cmd.bb_rounds;
  // Reals per sensor per iteration (Algorithm::reals_per_iteration): p, plus 2 per consensus round.
  // esdp-dist: p + 1 (x_i and Y_ii).
  const double per_it = info.consensus_rounds ? prob.dim() + 2.0 * cmd.bb_rounds : prob.dim() + (info.admm ? 1.0 : 0.0);
  o.max_iter = static_cast<std::int64_t>(std::floor(cmd.budget / per_it));
  o.history_every = std::max<std::int64_t>(1, o.max_iter / std::max<std::int64_t>(1, cmd.points));
  std::vector<double> x;
  Summary s = Solver(prob, o).solve(xr, &x);
  const double start_ml = cmd.start == "relaxation" ? ml_start : s.history.front().ml_cost;
  study.rows.push_back({sigma, t, alg, s.iterations, s.messages_per_sensor, s.reals_per_sensor, start_ml,
                        s.costs.ml, s.errors.rmse, s.errors.mpe, s.costs.relaxed, s.final_cost});
  if (!cmd.trajectory.empty())
    for (const auto& h : s.history)
      study.traj << csv_num(sigma) << ',' << t << ',' << alg << ',' << csv_num(h.reals) << ',' << csv_num(h.ml_cost)
                 << ',' << csv_num(h.mpe) << '\n';
  // Keep the trajectory for the "communications to reach the best cost" statistic.
  std::vector<std::pair<double, double>> tr;
  for (const auto& h : s.history) tr.emplace_back(h.reals, h.ml_cost);
  study.trajectories[{si, t, alg}] = std::move(tr);
}

// One noise draw: the relaxation to its stopping rule from a random start
// (--start relaxation), then every method.
void run_trial(const ExperimentCommand& cmd, LocalizationProblem& prob, std::size_t si, int t, Study& study) {
  const double sigma = cmd.sigmas[si];
  const std::uint64_t key = mix64(cmd.seed ^ mix64(si * 1000003ULL + static_cast<std::uint64_t>(t)));
  prob.resample_ranges(sigma, key);
  const char* const relaxation = algorithm_info(AlgorithmId::kRelaxation).name;
  SolverOptions ro;
  ro.algorithm = relaxation;
  ro.stop = "papers";
  ro.tol = cmd.relax_tol;
  ro.max_iter = cmd.relax_max_iter;
  ro.history_every = cmd.relax_max_iter + 1;
  ro.seed = key;
  std::vector<double> xr = random_initial_positions(prob, key);
  double ml_start = NAN;
  if (cmd.start == "relaxation") {
    Summary rs = Solver(prob, ro).solve(std::vector<double>(xr), &xr);
    study.rows.push_back({sigma, t, relaxation, rs.iterations, rs.messages_per_sensor, rs.reals_per_sensor,
                          rs.costs.ml, rs.costs.ml, rs.errors.rmse, rs.errors.mpe, rs.costs.relaxed, rs.final_cost});
    ml_start = rs.costs.ml;
  }
  for (const auto& alg : cmd.algorithms) run_method(cmd, prob, si, t, key, alg, xr, ml_start, study);
}

// Aggregates per (sigma, algorithm). Per trial, "best" is the lowest final
// ML cost over the refinements; each method's communications to come within
// cmd.reach_rel of it measure speed (both methods usually reach the same
// local minimum, one of them a little more precisely).
Aggregates aggregate(const ExperimentCommand& cmd, const Study& study) {
  Aggregates agg;
  for (const auto& r : study.rows) {
    auto& a = agg[{r.sigma, r.algorithm}];
    a.mpe += r.mpe;
    a.rmse2 += r.rmse * r.rmse;
    a.ml += r.ml;
    a.reals += r.reals;
    a.count += 1;
    if (r.ml > r.ml_start) a.worse += 1;
  }
  const Trajectories& trajectories = study.trajectories;
  for (std::size_t si = 0; si < cmd.sigmas.size(); ++si)
    for (int t = 0; t < cmd.trials; ++t) {
      double best = INFINITY;
      for (const auto& alg : cmd.algorithms) {
        auto it = trajectories.find({si, t, alg});
        if (it != trajectories.end() && !it->second.empty()) best = std::min(best, it->second.back().second);
      }
      for (const auto& alg : cmd.algorithms) {
        auto it = trajectories.find({si, t, alg});
        if (it == trajectories.end()) continue;
        auto& a = agg[{cmd.sigmas[si], alg}];
        a.reach_trials += 1;
        for (const auto& [reals, ml] : it->second)
          if (ml <= best * (1 + cmd.reach_rel)) {
            a.reach_reals += reals;
            a.reach_count += 1;
            break;
          }
      }
    }
  return agg;
}

// The per-trial CSV and the trajectory CSV (rank 0), the HDF5 table (collective).
void write_tables(const ExperimentCommand& cmd, const Study& study, MPI_Comm comm) {
  const std::vector<Row>& rows = study.rows;
  std::ostringstream csv;
  csv << "sigma,trial,algorithm,iterations,messages_per_sensor,reals_per_sensor,ml_cost_start,ml_cost,rmse,mpe,fhat,objective\n";
  for (const auto& r : rows)
    csv << csv_num(r.sigma) << ',' << r.trial << ',' << r.algorithm << ',' << r.iterations << ','
        << csv_num(r.messages) << ',' << csv_num(r.reals) << ',' << csv_num(r.ml_start) << ',' << csv_num(r.ml)
        << ',' << csv_num(r.rmse) << ',' << csv_num(r.mpe) << ',' << csv_num(r.fhat) << ',' << csv_num(r.objective)
        << '\n';
  std::string err;
  if (comm_rank(comm) == 0) {
    try {
      write_text_atomic(cmd.output, csv.str());
      if (!cmd.trajectory.empty()) write_text_atomic(cmd.trajectory, study.traj.str());
    } catch (const std::exception& e) {
      err = e.what();
    }
  }
  agree(comm, err);
  if (cmd.h5.empty()) return;
  H5File f(cmd.h5, comm, H5File::Mode::kCreate);
  f.set_attr("format", std::string("snl-experiment"));
  f.set_attr("network", cmd.network);
  f.set_attr("algorithms", algorithm_codes_legend());
  auto col = [&](const char* name, auto get) {
    std::vector<double> v;
    for (const auto& r : rows) v.push_back(get(r));
    f.write_replicated(name, v);
  };
  col("sigma", [](const Row& r) { return r.sigma; });
  col("trial", [](const Row& r) { return double(r.trial); });
  col("algorithm", [](const Row& r) { return double(algorithm_code(r.algorithm)); });
  col("iterations", [](const Row& r) { return double(r.iterations); });
  col("reals_per_sensor", [](const Row& r) { return r.reals; });
  col("ml_cost_start", [](const Row& r) { return r.ml_start; });
  col("ml_cost", [](const Row& r) { return r.ml; });
  col("rmse", [](const Row& r) { return r.rmse; });
  col("mpe", [](const Row& r) { return r.mpe; });
  col("fhat", [](const Row& r) { return r.fhat; });
  col("objective", [](const Row& r) { return r.objective; });
  f.commit();
}

void print_aggregates(const Aggregates& agg) {
  std::printf("%-7s %-11s %7s %11s %11s %13s %13s %8s %s\n", "sigma", "algorithm", "trials", "MPE", "RMSE",
              "mean ML cost", "reals/sensor", "worse", "reals to within reach_rel of the best final cost");
  for (const auto& [k, a] : agg) {
    std::string reach;
    if (a.reach_trials > 0)
      reach = (a.reach_count ? csv_num(a.reach_reals / a.reach_count) : std::string("n/a")) + " (reached in " +
              std::to_string(a.reach_count) + "/" + std::to_string(a.reach_trials) + " trials)";
    std::printf("%-7g %-11s %7d %11.5g %11.5g %13.6g %13.6g %8d %s\n", k.first, k.second.c_str(), a.count,
                a.mpe / a.count, std::sqrt(a.rmse2 / a.count), a.ml / a.count, a.reals / a.count, a.worse,
                reach.c_str());
  }
}

}  // namespace

void run_experiment(const ExperimentCommand& cmd, MPI_Comm comm) {
  check_experiment_command(cmd, comm);
  const bool root = comm_rank(comm) == 0;
  std::unique_ptr<LocalizationProblem> prob = load_geometry(cmd, comm);
  Study study;
  study.traj << "sigma,trial,algorithm,reals_per_sensor,ml_cost,mpe\n";
  for (std::size_t si = 0; si < cmd.sigmas.size(); ++si)
    for (int t = 0; t < cmd.trials; ++t) {
      run_trial(cmd, *prob, si, t, study);
      if (root && !cmd.quiet && (t + 1) % 10 == 0)
        std::fprintf(stderr, "sigma %g: %d/%d trials\n", cmd.sigmas[si], t + 1, cmd.trials);
    }
  const Aggregates agg = aggregate(cmd, study);
  study.trajectories.clear();
  write_tables(cmd, study, comm);
  if (root) print_aggregates(agg);
}

}  // namespace snl
