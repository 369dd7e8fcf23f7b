// snl: sensor network localization. A thin command-line front end: parsing
// here, everything else in libsnl (include/snl/commands.hpp).
#include <mpi.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <cstdlib>
#include <algorithm>
#include <string>
#include <vector>

#include "snl/cli/commands.hpp"
#include "snl/cli/consensus.hpp"
#include "snl/io/h5file.hpp"
#include "snl/core/mpi_util.hpp"

namespace {

int fail(MPI_Comm comm, const std::string& msg, int status) {
  if (snl::comm_rank(comm) == 0) std::fprintf(stderr, "snl: error: %s\n", msg.c_str());
  return status;
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  MPI_Comm comm = MPI_COMM_WORLD;
  snl::h5_quiet();
  const bool root = snl::comm_rank(comm) == 0;

  CLI::App app{"snl: cooperative sensor network localization from noisy ranges (MPI-parallel)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "snl 0.1.0");

  snl::GenerateCommand gen;
  std::string anchors = "corners", localizable = "auto";
  auto* g = app.add_subcommand("generate", "generate a random geometric network (HDF5)");
  g->add_option("-o,--output", gen.output, "output network file")->required();
  g->add_option("--sensors", gen.options.sensors, "number of sensors n")->required();
  g->add_option("--dim", gen.options.dim, "dimension p (2 or 3)")->capture_default_str();
  g->add_option("--avg-degree", gen.options.avg_degree, "average sensor-sensor degree")->capture_default_str();
  g->add_option("--sigma", gen.options.sigma, "range noise standard deviation (003 eq. 28)")->capture_default_str();
  g->add_option("--anchors", anchors, "'corners' or a number K of random anchors")->capture_default_str();
  g->add_option("--anchor-radius", gen.options.anchor_radius, "anchor link radius (default: sensor radius)");
  g->add_option("--seed", gen.options.seed, "random seed")->capture_default_str();
  g->add_option("--localizable", localizable, "auto|yes|no: redraw until localizable (auto: n <= 20000)")
      ->capture_default_str();
  g->add_option("--max-draws", gen.options.max_draws, "redraw limit")->capture_default_str();
  g->add_flag("-q,--quiet", gen.quiet, "print nothing on success");

  snl::InfoCommand info;
  auto* in = app.add_subcommand("info", "summarize and validate a network file");
  in->add_option("network", info.network, "network file")->required();
  in->add_option("--json", info.json, "write a JSON summary");
  in->add_flag("--strict", info.strict, "exit non-zero if some sensor cannot be localized");

  snl::SolveCommand solve;
  auto* s = app.add_subcommand("solve", "localize the sensors (run under mpirun for parallel runs)");
  s->add_option("network", solve.network, "network file")->required();
  s->add_option("-o,--output", solve.output, "result file")->required();
  s->add_option("--algorithm", solve.solver.algorithm, "relaxation|mm|pipeline|bb|pm|async|async-exact")->capture_default_str();
  s->add_option("--max-iter", solve.solver.max_iter, "iterations per phase")->capture_default_str();
  s->add_option("--tol", solve.solver.tol, "relative improvement tolerance (0: run --max-iter iterations)")
      ->capture_default_str();
  s->add_option("--grad-tol", solve.solver.grad_tol, "gradient norm tolerance (0: off)")->capture_default_str();
  s->add_option("--init", solve.init, "'random' or a file with dataset positions [n,p]")->capture_default_str();
  s->add_option("--seed", solve.solver.seed, "seed of --init random and of the async activation clock")->capture_default_str();
  s->add_option("--partition", solve.partition, "metis|block")->capture_default_str();
  s->add_option("--history-every", solve.solver.history_every, "record history every K iterations (0: auto)")
      ->capture_default_str();
  s->add_option("--bb-rounds", solve.solver.bb_rounds, "consensus rounds per BB iteration")->capture_default_str();
  s->add_option("--temporal-block", solve.solver.temporal_block,
                "relaxation/MM iterations per pass over memory (same iterates; tests and records at pass ends)")
      ->capture_default_str();
  s->add_option("--json", solve.json, "write a JSON summary");
  s->add_option("--checkpoint", solve.checkpoint, "write checkpoints to this file (atomically replaced)");
  s->add_option("--checkpoint-every", solve.checkpoint_every, "checkpoint every K iterations");
  s->add_option("--checkpoint-seconds", solve.checkpoint_seconds, "checkpoint every S seconds of wall clock");
  s->add_option("--restart", solve.restart, "resume from a checkpoint (any number of ranks)");
  s->add_option("--progress-seconds", solve.progress_seconds, "seconds between progress lines")
      ->capture_default_str();
  s->add_flag("--check-monotone", solve.solver.check_monotone, "verify MM's surrogate never increases");
  s->add_flag("--strict", solve.strict, "refuse networks with sensors that cannot be localized");
  s->add_flag("-q,--quiet", solve.quiet, "no progress output");

  snl::EvalCommand ev;
  auto* e = app.add_subcommand("eval", "evaluate a result against a network");
  e->add_option("network", ev.network, "network file")->required();
  e->add_option("result", ev.result, "result file (or any file with positions)")->required();
  e->add_flag("--crlb", ev.crlb, "also compute the Cramer-Rao lower bound (n <= 20000)");
  e->add_option("--sigma", ev.sigma, "noise standard deviation for --crlb (default: the network's)");
  e->add_option("--json", ev.json, "write a JSON summary");

  snl::ExperimentCommand ex;
  auto* x = app.add_subcommand("experiment", "Monte Carlo study over noise draws on a fixed network");
  x->add_option("network", ex.network, "network file with truth (fixed geometry)")->required();
  x->add_option("-o,--output", ex.output, "per-trial CSV")->required();
  x->add_option("--trajectory", ex.trajectory, "CSV of ML cost vs communications per run");
  x->add_option("--h5", ex.h5, "HDF5 copy of the per-trial table");
  x->add_option("--sigmas", ex.sigmas, "noise levels")->delimiter(',')->capture_default_str();
  x->add_option("--trials", ex.trials, "noise draws per sigma")->capture_default_str();
  x->add_option("--algorithms", ex.algorithms, "methods (relaxation,mm,bb,pm,async,async-exact)")
      ->delimiter(',')->capture_default_str();
  x->add_option("--budget", ex.budget, "communications (reals per sensor) per refinement")->capture_default_str();
  x->add_option("--relax-tol", ex.relax_tol, "relaxation relative-improvement tolerance")->capture_default_str();
  x->add_option("--relax-max-iter", ex.relax_max_iter, "relaxation iteration limit")->capture_default_str();
  x->add_option("--points", ex.points, "trajectory points per run")->capture_default_str();
  x->add_option("--bb-rounds", ex.bb_rounds, "consensus rounds per BB iteration")->capture_default_str();
  x->add_option("--start", ex.start, "relaxation (refinements from its output) or random (all from one random start)")
      ->capture_default_str();
  x->add_option("--tol", ex.tol, "methods' relative-improvement tolerance (0: whole budget)")->capture_default_str();
  x->add_option("--reach-rel", ex.reach_rel, "relative margin for 'reached the best final cost'")
      ->capture_default_str();
  x->add_option("--seed", ex.seed, "seed of the noise draws and starts")->capture_default_str();
  x->add_option("--partition", ex.partition, "metis|block")->capture_default_str();
  x->add_flag("-q,--quiet", ex.quiet, "no progress output");

  // `snl consensus generate|solve ...` (seed 001) parse their own options.
  app.add_subcommand("consensus", "consensus optimisation (seed 001): snl consensus generate|solve --help")
      ->allow_extras()
      ->prefix_command();
  if (argc >= 2 && std::string(argv[1]) == "consensus") {
    const std::string which = argc >= 3 ? argv[2] : "";
    const std::vector<std::string> rest(argv + std::min(argc, 3), argv + argc);
    int status = 0;
    try {
      if (which == "generate")
        status = snl::consensus_generate_main(rest, comm);
      else if (which == "solve")
        status = snl::consensus_solve_main(rest, comm);
      else {
        if (root)
          std::fprintf(stderr, "usage: snl consensus generate|solve ... (see snl consensus solve --help)%s\n",
                       which.empty() || which == "--help" || which == "-h" ? "" : ("; unknown '" + which + "'").c_str());
        status = which == "--help" || which == "-h" ? 0 : 2;
      }
    } catch (const snl::Error& err) {
      status = fail(comm, err.what(), 1);
    } catch (const std::bad_alloc&) {
      snl::abort_all(comm, "out of memory");
    } catch (const std::exception& err) {
      snl::abort_all(comm, std::string("internal error: ") + err.what());
    }
    int unclean = snl::h5_close_failed() ? 1 : 0, any_unclean = 0;
    MPI_Allreduce(&unclean, &any_unclean, 1, MPI_INT, MPI_MAX, comm);
    if (any_unclean) {
      std::fflush(nullptr);
      std::_Exit(status);
    }
    MPI_Finalize();
    return status;
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& err) {
    int status = 0;
    if (root)
      status = app.exit(err);
    else
      status = err.get_exit_code();
    MPI_Finalize();
    return status;
  }

  int status = 0;
  try {
    if (*g) {
      if (anchors == "corners")
        gen.options.num_random_anchors = 0;
      else {
        try {
          std::size_t pos = 0;
          gen.options.num_random_anchors = std::stoi(anchors, &pos);
          if (pos != anchors.size() || gen.options.num_random_anchors < 1) throw std::invalid_argument("");
        } catch (const std::exception&) {
          throw snl::Error("--anchors must be 'corners' or a positive number, not '" + anchors + "'");
        }
      }
      if (localizable == "auto")
        gen.options.localizable = snl::GenerateOptions::Localizable::kAuto;
      else if (localizable == "yes")
        gen.options.localizable = snl::GenerateOptions::Localizable::kYes;
      else if (localizable == "no")
        gen.options.localizable = snl::GenerateOptions::Localizable::kNo;
      else
        throw snl::Error("--localizable must be auto, yes or no");
      snl::run_generate(gen, comm);
    } else if (*in) {
      snl::run_info(info, comm);
    } else if (*s) {
      status = snl::run_solve(solve, comm);
    } else if (*e) {
      snl::run_eval(ev, comm);
    } else if (*x) {
      snl::run_experiment(ex, comm);
    }
  } catch (const snl::Error& err) {
    // snl::Error is raised identically on every rank: one message, clean exit.
    status = fail(comm, err.what(), 1);
  } catch (const std::bad_alloc&) {
    // Anything else may be rank-local: never hang the others.
    snl::abort_all(comm, "out of memory");
  } catch (const std::exception& err) {
    snl::abort_all(comm, std::string("internal error: ") + err.what());
  }
  // After a failed H5Fclose (disk full) HDF5 would crash in its shutdown inside
  // MPI_Finalize (snl::h5_close_failed): then every rank leaves without it, with
  // the status already decided (the error was reported above).
  int unclean = snl::h5_close_failed() ? 1 : 0, any_unclean = 0;
  MPI_Allreduce(&unclean, &any_unclean, 1, MPI_INT, MPI_MAX, comm);
  if (any_unclean) {
    std::fflush(nullptr);
    std::_Exit(status);
  }
  MPI_Finalize();
  return status;
}
