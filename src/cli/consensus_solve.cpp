// `snl consensus solve`: the distributed solvers of seed 001 on a problem file
// (docs/distributed-newton.md): result file snl-consensus-result, --json summary,
// progress on rank 0, checkpoints and stop signals as `snl solve`.
#include <cmath>
#include <cstdio>
#include <sstream>

#include "core/json.hpp"
#include "snl/cli/commands.hpp"
#include "snl/cli/consensus.hpp"
#include "snl/core/mpi_util.hpp"
#include "snl/io/h5file.hpp"
#include "snl/core/stop_signal.hpp"

namespace snl {

namespace {

// Progress on rank 0 at most every `period` seconds (and at the last record).
class Progress {
 public:
  Progress(MPI_Comm comm, double period, std::int64_t max_iter, bool quiet)
      : on_(comm_rank(comm) == 0 && !quiet), period_(period), max_iter_(max_iter) {}
  void operator()(const consensus::HistoryRecord& r) {
    if (!on_) return;
    if (!header_) {
      header_ = true;
      std::fprintf(stderr, "%10s %10s %16s %12s %12s %12s %9s\n", "iter", "dual_iter", "F(avg)", "max_err",
                   "decrement", "msgs/node", "elapsed");
    }
    if (r.elapsed - last_ < period_ && r.iteration != max_iter_ && r.iteration != 0) return;
    last_ = r.elapsed;
    // The baselines have no Newton decrement: n/a rather than nan.
    char dec[32] = "n/a", err[32] = "n/a";
    if (std::isfinite(r.decrement)) std::snprintf(dec, sizeof dec, "%.4e", r.decrement);
    if (std::isfinite(r.max_abs_error)) std::snprintf(err, sizeof err, "%.4e", r.max_abs_error);
    std::fprintf(stderr, "%10lld %10lld %16.10g %12s %12s %12.6g %8.1fs\n", static_cast<long long>(r.iteration),
                 static_cast<long long>(r.dual_iterations), r.objective, err, dec, r.messages, r.elapsed);
  }

 private:
  bool on_;
  double period_;
  std::int64_t max_iter_;
  bool header_ = false;
  double last_ = -1e300;
};

void write_consensus_result(const ConsensusSolveCommand& cmd, MPI_Comm comm, const consensus::ProblemData& d,
                            const consensus::SolveSummary& s, const std::vector<double>& x_rows) {
  H5File f(cmd.output, comm, H5File::Mode::kCreate);
  f.set_attr("format", std::string("snl-consensus-result"));
  f.set_attr("version", std::int64_t{1});
  f.set_attr("num_nodes", std::int64_t{d.num_nodes});
  f.set_attr("dim", std::int64_t{d.dim});
  f.set_attr("method", s.method);
  f.set_attr("dual", s.dual);
  f.set_attr("step_rule", s.step_rule);
  f.set_attr("iterations", s.iterations);
  f.set_attr("line_search_trials", s.line_search_trials);
  f.set_attr("dual_iterations", s.dual_iterations);
  f.set_attr("termination", s.termination);
  f.set_attr("converged", std::int64_t{s.converged ? 1 : 0});
  f.set_attr("x_star", s.x_star);
  f.set_attr("x_star_converged", std::int64_t{s.x_star_converged ? 1 : 0});
  f.set_attr("x_star_decrement", s.x_star_decrement);
  f.set_attr("max_abs_error", s.max_abs_error);
  f.set_attr("F", s.objective);
  f.set_attr("messages_per_node", s.messages_per_node);
  f.set_attr("reals_per_node", s.reals_per_node);
  f.set_attr("partition", s.partition);
  f.set_attr("problem", cmd.problem);
  const bool root = comm_rank(comm) == 0;
  f.write_rows("x", static_cast<std::uint64_t>(d.num_nodes), static_cast<std::uint64_t>(d.dim), 0, x_rows.data(),
               root ? static_cast<std::uint64_t>(d.num_nodes) : 0);
  for (const consensus::HistoryColumn& c : consensus::history_columns()) {
    std::vector<double> v;
    for (const auto& r : s.history) v.push_back(c.get(r));
    f.write_replicated(std::string("history/") + c.name, v);
  }
  f.commit();
}

std::string json_summary(const consensus::SolveSummary& s) {
  JsonObject j;
  j.add("method", s.method)
      .add("dual", s.dual)
      .add("step_rule", s.step_rule)
      .add("iterations", s.iterations)
      .add("dual_iterations", s.dual_iterations)
      .add("line_search_trials", s.line_search_trials)
      .add("termination", s.termination)
      .add_bool("converged", s.converged)
      .add("max_abs_error", s.max_abs_error)
      .add("F", s.objective)
      .add("messages_per_node", s.messages_per_node)
      .add("reals_per_node", s.reals_per_node)
      .add("wall_seconds", s.wall_seconds)
      .add("ranks", s.ranks)
      .add("partition", s.partition)
      .add("tree_depth", static_cast<std::int64_t>(s.tree_depth))
      .add_bool("x_star_converged", s.x_star_converged)
      .add("x_star_iterations", s.x_star_iterations)
      .add("x_star_decrement", s.x_star_decrement);
  for (std::size_t k = 0; k < s.x_star.size(); ++k) j.add("x_star_" + std::to_string(k), s.x_star[k]);
  return j.str();
}

}  // namespace

int run_consensus_solve(const ConsensusSolveCommand& cmd, MPI_Comm comm) {
  const std::string bad = cmd.solver.validate();
  if (!bad.empty()) throw Error(bad);
  if (cmd.checkpoint_every < 0) throw UsageError("--checkpoint-every must be >= 0");
  if (cmd.checkpoint_every > 0 && cmd.checkpoint.empty()) throw UsageError("--checkpoint-every needs --checkpoint FILE");
  check_output_path(cmd.output, comm, {{"the problem", cmd.problem}, {"--restart", cmd.restart}});
  if (!cmd.json.empty())
    check_output_path(cmd.json, comm, {{"the problem", cmd.problem}, {"--restart", cmd.restart}, {"the output", cmd.output}});
  if (!cmd.checkpoint.empty()) {
    check_output_path(cmd.checkpoint, comm, {{"the problem", cmd.problem}, {"the output", cmd.output}, {"--json", cmd.json}});
    install_stop_signal_handlers();
  }
  const bool talk = comm_rank(comm) == 0 && !cmd.quiet;
  const consensus::ProblemData data = consensus::read_problem(comm, cmd.problem);
  if (cmd.solver.method_kind() == consensus::Method::kNewtonPath && data.truth_path.empty())
    throw Error(cmd.problem + ": --method newton-path needs a Hamilton path and the problem has none (no dataset "
                "truth_path; generate one with --hamiltonian, or use --method newton-tree)");
  if (talk)
    std::fprintf(stderr, "snl consensus solve: n=%lld q=%d, %lld links, family %s, method %s%s%s on %d ranks\n",
                 static_cast<long long>(data.num_nodes), data.dim, static_cast<long long>(data.edges.size() / 2),
                 consensus::family_name(data.family), cmd.solver.method.c_str(),
                 cmd.solver.dual_kind() == consensus::DualSolver::kNone ? "" : ", dual ",
                 cmd.solver.dual_kind() == consensus::DualSolver::kNone ? ""
                                                                         : consensus::dual_name(cmd.solver.dual_kind()),
                 comm_size(comm));
  Progress progress(comm, cmd.progress_seconds, cmd.solver.max_iterations(), cmd.quiet);
  consensus::CheckpointSettings ck;
  ck.path = cmd.checkpoint;
  ck.every = cmd.checkpoint_every;
  ck.restart = cmd.restart;
  ck.stop_on_signal = !cmd.checkpoint.empty();
  std::vector<double> x_rows;
  const consensus::SolveSummary s =
      consensus::solve(comm, data, cmd.solver, ck, [&](const consensus::HistoryRecord& r) { progress(r); }, &x_rows);
  // Errors against an x* that is not the optimum would mislead: none is reported (NaN, null in JSON).
  if (comm_rank(comm) == 0 && !s.x_star_converged)
    std::fprintf(stderr,
                 "snl: warning: the reference optimum x* did not converge (Newton decrement %.3e after %lld "
                 "iterations); errors against x* are not reported\n",
                 s.x_star_decrement, static_cast<long long>(s.x_star_iterations));
  if (s.termination == "SIGNAL") {
    if (talk) std::fprintf(stderr, "snl consensus solve: %s; resume with --restart %s\n", s.message.c_str(),
                           cmd.checkpoint.c_str());
    return kExitCheckpointed;
  }
  write_consensus_result(cmd, comm, data, s, x_rows);
  if (!cmd.json.empty()) {
    std::string err;
    if (comm_rank(comm) == 0) {
      try {
        write_text_atomic(cmd.json, json_summary(s));
      } catch (const std::exception& e) {
        err = e.what();
      }
    }
    agree(comm, err);
  }
  if (talk) {
    char err[64];
    if (s.x_star_converged)
      std::snprintf(err, sizeof err, "%.3e", s.max_abs_error);
    else
      std::snprintf(err, sizeof err, "not known");
    std::fprintf(stderr,
                 "snl consensus %s (dual %s, step %s): %s after %lld iterations (%lld dual, %lld line-search "
                 "trials)%s%s\n  max_p |x_p - x*| = %s, F(avg) = %.12g; per node %.6g messages, %.6g reals; "
                 "%.3f s on %d ranks\n",
                 s.method.c_str(), s.dual.c_str(), s.step_rule.c_str(), s.termination.c_str(),
                 static_cast<long long>(s.iterations), static_cast<long long>(s.dual_iterations),
                 static_cast<long long>(s.line_search_trials), s.message.empty() ? "" : ": ", s.message.c_str(), err,
                 s.objective, s.messages_per_node, s.reals_per_node, s.wall_seconds, s.ranks);
  }
  return s.termination == "FAILURE" ? 4 : 0;
}

}  // namespace snl
