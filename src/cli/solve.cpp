// snl solve: read the network, partition it, run the Solver (with progress
// lines, checkpoints and restarts), write the result file and a JSON summary.
#include <sys/resource.h>

#include <cmath>
#include <cstdio>

#include "cli/cli_util.hpp"
#include "core/json.hpp"
#include "kernels/kernels.hpp"
#include "snl/cli/commands.hpp"
#include "snl/core/memory.hpp"
#include "snl/io/network.hpp"
#include "snl/io/result_io.hpp"
#include "snl/solvers/dv_start.hpp"

namespace snl {

namespace {

using detail::is_root;

// Progress on rank 0 at recorded iterations, at most every `period` seconds.
class ProgressPrinter : public IterationCallback {
 public:
  ProgressPrinter(MPI_Comm comm, double period, std::int64_t max_iter, int phases)
      : root_(is_root(comm)), period_(period), max_iter_(max_iter), phases_(phases) {}
  CallbackReturn operator()(const IterationSummary& s) override {
    if (!root_) return CallbackReturn::kContinue;
    if (s.phase != phase_) {
      phase_ = s.phase;
      ++phase_index_;
      phase_start_ = s.elapsed;
      last_ = -1e300;
      std::fprintf(stderr, "%-10s %10s %14s %14s %11s %11s %9s %9s\n", "phase", "iter", "cost", "ml_cost",
                   "rel_change", "rmse", "elapsed", "eta");
    }
    if (s.elapsed - last_ < period_ && s.iteration != max_iter_) return CallbackReturn::kContinue;
    last_ = s.elapsed;
    const double per_it = s.iteration > 0 ? (s.elapsed - phase_start_) / s.iteration : 0;
    const double eta = per_it * (max_iter_ - s.iteration) + (phases_ - phase_index_) * per_it * max_iter_;
    char rmse[32] = "n/a";  // no truth
    if (std::isfinite(s.rmse)) std::snprintf(rmse, sizeof rmse, "%.4g", s.rmse);
    std::fprintf(stderr, "%-10s %10lld %14.8g %14.8g %11.3e %11s %8.1fs %8.0fs\n", s.phase.c_str(),
                 static_cast<long long>(s.iteration), s.cost, s.ml_cost, s.rel_change, rmse, s.elapsed, eta);
    return CallbackReturn::kContinue;
  }

 private:
  bool root_;
  double period_;
  std::int64_t max_iter_;
  int phases_;
  std::string phase_;
  int phase_index_ = 0;
  double phase_start_ = 0, last_ = -1e300;
};

// The partitioned problem and what setting it up reported.
struct LoadedProblem {
  std::unique_ptr<LocalizationProblem> prob;
  ProblemReport rep;
  std::string fingerprint;   // network_fingerprint() of the input (checkpoints)
  double t_read = 0, t_setup = 0;  // MPI_Wtime() after reading, after setting up
};

// What the run starts from: "restart" (a checkpoint), "dv", "random" (--init
// auto resolved: dv for dv-pipeline, else random) or "file" (--init FILE).
std::string start_kind(const SolveCommand& cmd) {
  if (!cmd.restart.empty()) return "restart";
  if (cmd.init == "dv" || cmd.init == "random") return cmd.init;
  if (cmd.init != "auto") return "file";
  const AlgorithmInfo* a = find_algorithm(cmd.solver.algorithm);
  return a && a->id == AlgorithmId::kDvPipeline ? "dv" : "random";
}

// Before any work: options the algorithm cannot honour (a usage error), then
// the other options and every output path. Nothing is read or written yet.
PartitionMethod check_solve_command(const SolveCommand& cmd, MPI_Comm comm) {
  const std::string unsupported = cmd.solver.unsupported_option();
  if (!unsupported.empty()) throw UsageError(unsupported);
  // Only an explicit flag: its default is on in debug builds, for every method.
  const AlgorithmInfo* alg = find_algorithm(cmd.solver.algorithm);
  if (cmd.check_monotone_given && alg && !alg->monotone_surrogate)
    throw UsageError("--check-monotone is not honoured by --algorithm " + cmd.solver.algorithm + " (only by " +
                     algorithms_with(&AlgorithmInfo::monotone_surrogate) + "); leave it out");
  const bool init_given = cmd.init != "random" && cmd.init != "auto";
  if (alg && alg->one_shot && (init_given || !cmd.checkpoint.empty() || !cmd.restart.empty()))
    throw UsageError(std::string(init_given ? "--init" : "--checkpoint/--restart") +
                     " is not honoured by --algorithm " + cmd.solver.algorithm +
                     " (a convex relaxation solved once: it needs no start and has no iterations to resume)");
  const std::string bad = cmd.solver.validate();
  if (!bad.empty()) throw Error(bad);
  const PartitionMethod pm = parse_partition_method(cmd.partition);
  const std::string init_file = cmd.init == "auto" || cmd.init == "random" || cmd.init == "dv" ? "" : cmd.init;
  check_output_path(cmd.output, comm, {{"the network", cmd.network}, {"--init", init_file}, {"--restart", cmd.restart}});
  if (!cmd.json.empty())
    check_output_path(cmd.json, comm, {{"the network", cmd.network}, {"--init", init_file}, {"--restart", cmd.restart},
                                       {"the output", cmd.output}});
  if (cmd.checkpoint_every < 0 || !(cmd.checkpoint_seconds >= 0))
    throw UsageError("--checkpoint-every and --checkpoint-seconds must be >= 0");
  if ((cmd.checkpoint_every > 0 || cmd.checkpoint_seconds > 0) && cmd.checkpoint.empty())
    throw UsageError("--checkpoint-every/--checkpoint-seconds need --checkpoint FILE");
  if (!cmd.checkpoint.empty())  // --restart may name it: the run resumes from it and replaces it
    check_output_path(cmd.checkpoint, comm, {{"the network", cmd.network}, {"--init", init_file},
                                             {"the output", cmd.output}, {"--json", cmd.json}});
  return pm;
}

void print_problem_report(const LocalizationProblem& prob, const ProblemReport& rep, MPI_Comm comm) {
  std::fprintf(stderr,
               "snl solve: n=%lld m=%lld p=%d, %lld sensor pairs, %lld anchor pairs (%lld+%lld duplicate rows "
               "merged)\n",
               static_cast<long long>(prob.num_sensors()), static_cast<long long>(prob.num_anchors()), prob.dim(),
               static_cast<long long>(rep.num_sensor_edges), static_cast<long long>(rep.num_anchor_edges),
               static_cast<long long>(rep.merged.merged_sensor_pairs),
               static_cast<long long>(rep.merged.merged_anchor_pairs));
  std::fprintf(stderr, "partition: %s on %d ranks, edge cut %lld, imbalance %.3f, ghosts %lld (max %lld/rank)%s%s\n",
               rep.partition.method.c_str(), comm_size(comm), static_cast<long long>(rep.partition.edge_cut),
               rep.partition.imbalance, static_cast<long long>(rep.partition.total_ghosts),
               static_cast<long long>(rep.partition.max_ghosts), rep.partition.note.empty() ? "" : "; ",
               rep.partition.note.c_str());
  if (rep.unlocalizable > 0) {
    std::string ids;
    for (auto g : rep.unlocalizable_sample) ids += " " + std::to_string(g);
    std::fprintf(stderr,
                 "warning: %lld sensors cannot be localized (%lld in components without anchors, %lld with fewer "
                 "than p+1 measurements); e.g.%s%s. Metrics count them apart (rmse_localizable).\n",
                 static_cast<long long>(rep.unlocalizable), static_cast<long long>(rep.unanchored),
                 static_cast<long long>(rep.few_measurements), ids.c_str(),
                 rep.unlocalizable > static_cast<GlobalId>(rep.unlocalizable_sample.size()) ? " ..." : "");
  }
  // Before any iteration: a run that cannot place most sensors says so, and what to change.
  if (2 * rep.unlocalizable > prob.num_sensors())
    std::fprintf(stderr,
                 "warning: most sensors (%lld of %lld) cannot be localized (%lld without anchors in their component, "
                 "%lld with too few measurements, the rest flagged by the file, e.g. flexible); the solve will not "
                 "place them. Regenerate with more anchors (snl generate --anchors auto or K) or a higher average "
                 "degree (--avg-degree; the default is localizable, docs/generator.md).\n",
                 static_cast<long long>(rep.unlocalizable), static_cast<long long>(prob.num_sensors()),
                 static_cast<long long>(rep.unanchored), static_cast<long long>(rep.few_measurements));
}

// After a run stopped by --max-iter with a tolerance set: how far from it, and what to change.
void report_iteration_cap(const SolveCommand& cmd, const Summary& s) {
  const double tol = cmd.solver.stop_tol();
  if (s.termination != TerminationType::kNoConvergence || !(tol > 0) || s.history.empty()) return;
  const IterationSummary& last = s.history.back();
  std::fprintf(stderr, "snl solve: the %s phase stopped at --max-iter %lld ", last.phase.c_str(),
               static_cast<long long>(cmd.solver.max_iter));
  if (cmd.solver.stop == "papers" && std::isfinite(last.rel_change) && last.rel_change > 0)
    std::fprintf(stderr, "with relative change %.3g, %.3g times --tol %.3g", last.rel_change, last.rel_change / tol,
                 tol);
  else
    std::fprintf(stderr, "before its stopping rule (--stop %s, --tol %.3g) was met", cmd.solver.stop.c_str(), tol);
  std::fprintf(stderr,
               ". To converge, raise --max-iter (or resume with --checkpoint/--restart), or loosen --tol; if many "
               "sensors cannot be localized (see above), fix the network instead.\n");
}

// Reads the network and partitions it over the ranks.
LoadedProblem load_problem(const SolveCommand& cmd, PartitionMethod pm, bool talk, MPI_Comm comm) {
  LoadedProblem lp;
  Network slab = read_network(cmd.network, comm);
  if (slab.num_anchors() == 0) throw Error(cmd.network + ": the network has no anchors; positions are not determined");
  lp.t_read = MPI_Wtime();
  lp.fingerprint = network_fingerprint(slab, comm);
  collective_try(comm, [&] { lp.prob = std::make_unique<LocalizationProblem>(comm, std::move(slab), pm, &lp.rep); });
  slab = Network();  // the problem holds what it needs
  lp.t_setup = MPI_Wtime();
  if (talk) print_problem_report(*lp.prob, lp.rep, comm);
  if (cmd.strict && lp.rep.unlocalizable > 0)
    throw Error(cmd.network + ": " + std::to_string(lp.rep.unlocalizable) + " sensors cannot be localized (--strict)");
  return lp;
}


// --init random or dv, a positions file, or (with --restart) a placeholder the checkpoint replaces.
std::vector<double> initial_positions(const SolveCommand& cmd, LocalizationProblem& prob, DvStartReport* dv,
                                      bool talk, MPI_Comm comm) {
  const std::string start = start_kind(cmd);
  if (start == "restart") return std::vector<double>(std::size_t(prob.num_owned()) * prob.dim(), 0.0);
  if (start == "random") return random_initial_positions(prob, cmd.solver.seed);
  if (start == "dv") {
    std::vector<double> x = dv_initial_positions(prob, cmd.solver.seed, dv);
    if (talk)
      std::fprintf(stderr,
                   "start: distance-vector multilateration, %lld rounds, path correction %.4f, %lld sensors without "
                   "an anchor path, %.3f s\n",
                   static_cast<long long>(dv->rounds), dv->correction, static_cast<long long>(dv->without_anchor),
                   dv->seconds);
    return x;
  }
  GlobalId b, e;
  block_range(prob.num_sensors(), comm_size(comm), comm_rank(comm), b, e);
  const auto rows = read_positions(cmd.init, comm, prob.num_sensors(), prob.dim(), b, e - b);
  return prob.file_rows_to_owned(rows, b, prob.dim());
}

// With --restart: checks the checkpoint against this network and these options
// (as the Solver does, before any work) and says where the run resumes.
void report_restart(const SolveCommand& cmd, const LoadedProblem& lp, bool talk, MPI_Comm comm) {
  if (cmd.restart.empty()) return;
  const H5File f(cmd.restart, comm, H5File::Mode::kRead);
  const CheckpointHeader h = read_checkpoint_header(
      f, lp.fingerprint,
      checkpoint_options(cmd.solver.resolved()));
  if (talk)
    std::fprintf(stderr, "snl solve: resuming from %s at %s iteration %lld (total iteration %lld)\n",
                 cmd.restart.c_str(), h.phase_algorithm.c_str(), static_cast<long long>(h.phase_iteration),
                 static_cast<long long>(h.total_iteration));
}

Summary run_solver(const SolveCommand& cmd, LoadedProblem& lp, const std::vector<double>& x0,
                   std::vector<double>* x, MPI_Comm comm) {
  Solver solver(*lp.prob, cmd.solver);
  ProgressPrinter progress(comm, cmd.progress_seconds, cmd.solver.max_iter,
                           static_cast<int>(find_algorithm(cmd.solver.algorithm)->phases.size()));
  if (!cmd.quiet) solver.add_callback(&progress);
  CheckpointConfig cc;
  cc.path = cmd.checkpoint;
  cc.every = cmd.checkpoint_every;
  cc.seconds = cmd.checkpoint_seconds;
  cc.restart = cmd.restart;
  cc.network_fingerprint = lp.fingerprint;
  cc.stop_on_signal = !cmd.checkpoint.empty();
  solver.set_checkpointing(cc);
  return solver.solve(x0, x);
}

// Positions back in file order, the history columns, summary attributes.
void write_result_file(const SolveCommand& cmd, const LoadedProblem& lp, const Summary& s,
                       const std::vector<double>& x, MPI_Comm comm) {
  const LocalizationProblem& prob = *lp.prob;
  ResultFile r;
  r.algorithm = cmd.solver.algorithm;
  r.iterations = s.iterations;
  r.converged = s.converged;
  r.dim = prob.dim();
  r.num_sensors = prob.num_sensors();
  r.positions = prob.owned_to_file_rows(x.data(), prob.dim(), &r.row_offset);
  for (const HistoryColumn& c : history_columns())
    if (s.errors.valid || !c.needs_truth) r.history.emplace_back(c.result_name, history_column(s.history, c));
  r.string_attrs = {{"termination", to_string(s.termination)},
                    {"message", s.message},
                    {"network", cmd.network},
                    {"partition", lp.rep.partition.method},
                    {"history_phase_codes", algorithm_codes_legend()}};
  r.double_attrs = {{"ml_cost", s.costs.ml},
                    {"relaxed_cost", s.costs.relaxed},
                    {"gap_certificate", s.gap_certificate},
                    {"apriori_bound", s.costs.apriori},
                    {"messages_per_sensor", s.messages_per_sensor},
                    {"reals_per_sensor", s.reals_per_sensor},
                    {"mpi_bytes", double(s.mpi_bytes)},
                    {"wall_seconds", s.wall_seconds},
                    {"ranks", double(s.ranks)},
                    {"seed", double(cmd.solver.seed)},
                    {"temporal_block", double(cmd.solver.temporal_block)},
                    {"lipschitz", s.lipschitz}};
  if (s.errors.valid) {
    r.double_attrs.push_back({"rmse", s.errors.rmse});
    r.double_attrs.push_back({"mpe", s.errors.mpe});
  }
  r.double_attrs.insert(r.double_attrs.end(), s.method_values.begin(), s.method_values.end());
  r.string_attrs.insert(r.string_attrs.end(), s.method_texts.begin(), s.method_texts.end());
  write_result(cmd.output, comm, r);
}

// MPI_Wtime() at the steps of run_solve.
struct SolveTimes {
  double start, read, setup, solve, write;
};

// Performance report (docs/performance.md): peak RSS of every rank (the METIS
// graph on rank 0 included), halo volume, bytes of the problem; sums and maxima over ranks.
struct MemoryTotals {
  long long tot[4], mx[4];  // peak RSS, halo nodes sent per iteration, problem bytes, owned nodes
  /// Per rank (on rank 0), in rank order: peak RSS, problem bytes, owned
  /// sensors, then the setup accounting (ProblemReport::setup_bytes).
  std::vector<std::pair<std::string, std::vector<std::int64_t>>> per_rank;
};

MemoryTotals memory_totals(const LocalizationProblem& prob, const ProblemReport& rep, MPI_Comm comm) {
  struct rusage ru;
  getrusage(RUSAGE_SELF, &ru);
  long long loc[4] = {static_cast<long long>(ru.ru_maxrss) * 1024,  // Linux: KiB
                      static_cast<long long>(prob.graph().halo().send_volume()),
                      static_cast<long long>(prob.memory_bytes()), static_cast<long long>(prob.num_owned())};
  MemoryTotals m;
  MPI_Allreduce(loc, m.tot, 4, MPI_LONG_LONG, MPI_SUM, comm);
  MPI_Allreduce(loc, m.mx, 4, MPI_LONG_LONG, MPI_MAX, comm);
  std::vector<std::pair<std::string, std::int64_t>> mine = {
      {"peak_rss_bytes", loc[0]}, {"problem_bytes", loc[2]}, {"memory_owned_sensors", loc[3]}};
  for (const auto& sb : rep.setup_bytes) mine.emplace_back("setup_" + sb.first + "_bytes", sb.second);
  std::vector<std::int64_t> vals(mine.size()), all(mine.size() * comm_size(comm));
  for (std::size_t k = 0; k < mine.size(); ++k) vals[k] = mine[k].second;
  MPI_Gather(vals.data(), static_cast<int>(vals.size()), MPI_INT64_T, all.data(), static_cast<int>(vals.size()),
             MPI_INT64_T, 0, comm);
  for (std::size_t k = 0; k < mine.size(); ++k) {
    std::vector<std::int64_t> col(comm_size(comm));
    for (int r = 0; r < comm_size(comm); ++r) col[r] = all[r * mine.size() + k];
    m.per_rank.emplace_back(mine[k].first + "_per_rank", std::move(col));
  }
  return m;
}

// The --json summary, keys in their established order; a flat list of keys, hence its length.
std::string json_summary(const SolveCommand& cmd, const LoadedProblem& lp, const Summary& s, const DvStartReport& dv,
                         const SolveTimes& t, const MemoryTotals& m) {
  const LocalizationProblem& prob = *lp.prob;
  const ProblemReport& rep = lp.rep;
  const double n_sens = static_cast<double>(prob.num_sensors());
  const std::int64_t iters = s.iterations;
  JsonObject j;
  j.add("algorithm", cmd.solver.algorithm)
      .add("iterations", static_cast<std::int64_t>(s.iterations))
      .add_bool("converged", s.converged)
      .add("termination", to_string(s.termination))
      .add("message", s.message)
      .add("ml_cost", s.costs.ml)
      .add("relaxed_cost", s.costs.relaxed)
      .add("gap_certificate", s.gap_certificate)
      .add("relaxed_optimum", s.relaxed_optimum)
      .add("apriori_bound", s.costs.apriori)
      .add("communications_per_sensor", s.messages_per_sensor)
      .add("reals_per_sensor", s.reals_per_sensor)
      .add("mpi_bytes", static_cast<std::int64_t>(s.mpi_bytes))
      .add("comm_wait_fraction", s.comm_wait_fraction)
      .add("wall_seconds", t.write - t.start)
      .add("solve_seconds", s.wall_seconds)
      .add("read_seconds", t.read - t.start)
      .add("setup_seconds", t.setup - t.read)
      .add("write_seconds", t.write - t.solve)
      .add("ranks", s.ranks)
      .add("num_sensors", static_cast<std::int64_t>(prob.num_sensors()))
      .add("num_anchors", static_cast<std::int64_t>(prob.num_anchors()))
      .add("sensor_pairs", static_cast<std::int64_t>(rep.num_sensor_edges))
      .add("anchor_pairs", static_cast<std::int64_t>(rep.num_anchor_edges))
      .add("partition", rep.partition.method)
      .add("edge_cut", static_cast<std::int64_t>(rep.partition.edge_cut))
      .add("ghosts", static_cast<std::int64_t>(rep.partition.total_ghosts))
      .add("unlocalizable_sensors", static_cast<std::int64_t>(rep.unlocalizable))
      .add("lipschitz", s.lipschitz)
      .add("iterate_seconds", s.iterate_seconds)
      .add("seconds_per_iteration", iters > 0 ? s.iterate_seconds / double(iters) : 0.0)
      .add("stop_test_seconds", s.stop_test_seconds)
      .add("record_seconds", s.record_seconds)
      .add("gradient_tests", s.gradient_tests)
      .add("gradient_tests_bounded", s.gradient_tests_bounded)
      .add("iterate_wait_fraction", s.iterate_seconds > 0 ? s.iterate_wait_seconds / s.iterate_seconds : 0.0)
      .add("peak_rss_bytes_total", static_cast<std::int64_t>(m.tot[0]))
      .add("peak_rss_bytes_max", static_cast<std::int64_t>(m.mx[0]))
      .add("max_owned", static_cast<std::int64_t>(m.mx[3]))
      .add("max_ghosts", static_cast<std::int64_t>(rep.partition.max_ghosts))
      .add("halo_nodes_sent_per_iteration", static_cast<std::int64_t>(m.tot[1]))
      .add("halo_bytes_per_iteration", static_cast<std::int64_t>(m.tot[1]) * prob.dim() * std::int64_t(sizeof(double)))
      .add("problem_bytes", static_cast<std::int64_t>(m.tot[2]))
      .add("algorithm_state_bytes", static_cast<std::int64_t>(s.algorithm_state_bytes))
      .add("state_bytes_per_sensor", (double(m.tot[2]) + double(s.algorithm_state_bytes)) / n_sens)
      .add("local_order", default_local_ordering() == LocalOrdering::kRcm ? "rcm" : "gid")
      .add("allocator", allocator_mode());
  for (const auto& ph : s.phase_iterate_seconds) j.add(ph.first + "_iterate_seconds", ph.second);
  for (const auto& ph : s.phase_traffic_bytes)
    if (std::isfinite(ph.second)) j.add(ph.first + "_traffic_bytes_per_iteration", ph.second);
  j.add("start", start_kind(cmd));
  if (start_kind(cmd) == "dv")
    j.add("start_seconds", dv.seconds)
        .add("start_rounds", dv.rounds)
        .add("start_correction", dv.correction)
        .add("start_paths_seconds", dv.paths_seconds)
        .add("start_correction_seconds", dv.correction_seconds)
        .add("start_multilateration_seconds", dv.multilateration_seconds)
        .add("start_mpi_bytes", dv.mpi_bytes)
        .add("start_without_anchor", static_cast<std::int64_t>(dv.without_anchor));
  j.add("simd", detail::simd_name());
  j.add("temporal_block", cmd.solver.temporal_block);
  for (const auto& ph : rep.setup_phases) j.add("setup_" + ph.first + "_seconds", ph.second);
  for (const auto& pr : m.per_rank) j.add_array(pr.first, pr.second);
  if (s.errors.valid) {
    j.add("rmse", s.errors.rmse).add("mpe", s.errors.mpe);
    j.add("rmse_localizable", s.errors.rmse_localizable).add("mpe_localizable", s.errors.mpe_localizable);
    if (!std::isfinite(s.errors.rmse_localizable))  // null above: over an empty set
      j.add("localizable_metrics_reason", "no sensor can be localized");
  }
  for (const auto& v : s.method_values) j.add(v.first, v.second);
  for (const auto& v : s.method_texts) j.add(v.first, v.second);
  return j.str();
}

}  // namespace

int run_solve(const SolveCommand& cmd, MPI_Comm comm) {
  const PartitionMethod pm = check_solve_command(cmd, comm);
  if (!cmd.checkpoint.empty()) install_stop_signal_handlers();
  const bool talk = is_root(comm) && !cmd.quiet;
  SolveTimes t{};
  t.start = MPI_Wtime();
  LoadedProblem lp = load_problem(cmd, pm, talk, comm);
  t.read = lp.t_read;
  t.setup = lp.t_setup;
  report_restart(cmd, lp, talk, comm);
  DvStartReport dv;
  const std::vector<double> x0 = initial_positions(cmd, *lp.prob, &dv, talk, comm);
  std::vector<double> x;
  const Summary s = run_solver(cmd, lp, x0, &x, comm);
  t.solve = MPI_Wtime();
  if (s.termination == TerminationType::kSignal) {
    if (talk)
      std::fprintf(stderr, "snl solve: %s; resume with --restart %s\n", s.message.c_str(), cmd.checkpoint.c_str());
    return kExitCheckpointed;
  }
  write_result_file(cmd, lp, s, x, comm);
  t.write = MPI_Wtime();
  if (!cmd.json.empty())
    detail::write_text_on_root(cmd.json, json_summary(cmd, lp, s, dv, t, memory_totals(*lp.prob, lp.rep, comm)),
                               comm);
  if (talk) std::fprintf(stderr, "%s\n", s.brief_report().c_str());
  if (talk) report_iteration_cap(cmd, s);
  return s.termination == TerminationType::kFailure ? 4 : 0;
}

}  // namespace snl
