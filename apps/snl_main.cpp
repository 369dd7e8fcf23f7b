// snl: sensor network localization. A thin command-line front end: parsing
// here, everything else in libsnl (include/snl/cli/commands.hpp, consensus.hpp); the
// algorithm names and capabilities come from the registry (snl/solvers/registry.hpp).
#include <mpi.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <cstdlib>
#include <algorithm>
#include <map>
#include <string>
#include <vector>

#include "snl/cli/commands.hpp"
#include "snl/cli/consensus.hpp"
#include "snl/io/h5file.hpp"
#include "snl/core/memory.hpp"
#include "snl/core/mpi_util.hpp"

namespace {

// --seed: an unsigned 64-bit integer; a minus sign would wrap around silently.
const CLI::Validator kSeed(
    [](std::string& v) {
      return v.find('-') != std::string::npos ? std::string("must be an integer >= 0, got " + v) : std::string();
    },
    "UINT >= 0");

int fail(MPI_Comm comm, const std::string& msg, int status) {
  if (snl::comm_rank(comm) == 0) std::fprintf(stderr, "snl: error: %s\n", msg.c_str());
  return status;
}

using Info = snl::AlgorithmInfo;

// For the help of an option only some methods honour.
std::string honoured_by(bool Info::*capability) { return "only " + snl::algorithms_with(capability); }

// The subcommands' settings, filled by the parser.
struct Commands {
  snl::GenerateCommand gen;
  std::string anchors = "auto", localizable = "auto";  // parsed into gen.options by parse_generate_choices
  snl::InfoCommand info;
  snl::SolveCommand solve;
  snl::EvalCommand eval;
  snl::ExperimentCommand experiment;
  snl::ImportCommand import;
  snl::ExportCommand export_;
  CLI::App *generate = nullptr, *info_cmd = nullptr, *solve_cmd = nullptr, *eval_cmd = nullptr,
           *experiment_cmd = nullptr, *import_cmd = nullptr, *export_cmd = nullptr;
};

void add_generate(CLI::App& app, Commands& c) {
  CLI::App* g = c.generate = app.add_subcommand("generate", "generate a random geometric network (HDF5)");
  g->add_option("-o,--output", c.gen.output, "output network file")->required();
  g->add_option("--sensors", c.gen.options.sensors, "number of sensors n")->required();
  g->add_option("--dim", c.gen.options.dim, "dimension p (1, 2 or 3)")->capture_default_str();
  g->add_option("--topology", c.gen.options.topology, "random|star (star: 003 Fig. 2, --dim 1 --sensors 1)")
      ->transform(CLI::CheckedTransformer(std::map<std::string, snl::GenerateOptions::Topology>{
          {"random", snl::GenerateOptions::Topology::kRandom}, {"star", snl::GenerateOptions::Topology::kStar}}))
      ->capture_default_str();
  g->add_option("--star-center", c.gen.options.star_center, "star: the hub sensor's true position")
      ->capture_default_str();
  g->add_option("--star-anchors", c.gen.options.star_anchors, "star: anchor positions, comma separated")
      ->delimiter(',')
      ->capture_default_str();
  g->add_option("--avg-degree", c.gen.options.avg_degree,
                "average sensor-sensor degree (default: 16 in 2D, 24 in 3D, docs/generator.md)");
  CLI::Option* sigma =
      g->add_option("--sigma", c.gen.options.sigma, "range noise standard deviation (003 eq. 28)")->capture_default_str();
  g->add_option("--sigma-rel", c.gen.options.sigma_rel, "noise standard deviation relative to the link radius")
      ->excludes(sigma);
  g->add_option("--side", c.gen.options.side,
                "side of the region (default: 1 up to 1000 sensors, then growing at constant density)");
  g->add_option("--anchors", c.anchors, "'auto' (corners + 1% random), 'corners' or a number K of random anchors")
      ->capture_default_str();
  g->add_option("--noise", c.gen.noise.model, "gaussian|multiplicative (sigma_e = sigma * true distance)")
      ->capture_default_str();
  g->add_option("--nlos-fraction", c.gen.noise.nlos_fraction, "share of ranges with a positive NLOS bias")
      ->capture_default_str();
  g->add_option("--nlos-bias", c.gen.noise.nlos_bias, "NLOS bias uniform in [0, B]")->capture_default_str();
  g->add_option("--anchor-radius", c.gen.options.anchor_radius, "anchor link radius (default: sensor radius)");
  g->add_option("--seed", c.gen.options.seed, "random seed")->check(kSeed)->capture_default_str();
  g->add_option("--localizable", c.localizable, "auto|yes|no: redraw until localizable (auto: n <= 20000)")
      ->capture_default_str();
  g->add_option("--max-draws", c.gen.options.max_draws, "redraw limit")->capture_default_str();
  g->add_flag("-q,--quiet", c.gen.quiet, "print nothing on success");
}

void add_info(CLI::App& app, Commands& c) {
  CLI::App* in = c.info_cmd = app.add_subcommand("info", "summarize and validate a network file");
  in->add_option("network", c.info.network, "network file")->required();
  in->add_option("--json", c.info.json, "write a JSON summary");
  in->add_flag("--strict", c.info.strict, "exit non-zero if some sensor cannot be localized");
}

// The options of snl solve; a flat list of options, hence its length.
void add_solve(CLI::App& app, Commands& c) {
  CLI::App* s = c.solve_cmd = app.add_subcommand("solve", "localize the sensors (run under mpirun for parallel runs)");
  s->add_option("network", c.solve.network, "network file")->required();
  s->add_option("-o,--output", c.solve.output, "result file")->required();
  s->add_option("--algorithm", c.solve.solver.algorithm, snl::algorithm_names("|"))->capture_default_str();
  s->add_option("--max-iter", c.solve.solver.max_iter, "iterations per phase")->capture_default_str();
  s->add_option_function<double>(
      "--tol", [&c](const double& v) { c.solve.solver.tol = v; },
      "tolerance of --stop (0: run --max-iter iterations; default 1e-5 with gradient, 1e-6 with papers)");
  CLI::Option* stop = s->add_option("--stop", c.solve.solver.stop,
                                     "stopping rule with --tol: papers (relative change of x) or gradient (relative "
                                     "gradient of the phase's cost; docs/quality.md; esdp-dist: papers)")
                           ->capture_default_str();
  s->parse_complete_callback([&c, stop] {
    // ADMM's iterate minimizes neither f nor f_hat: without --stop it takes the papers' rule.
    const Info* a = snl::find_algorithm(c.solve.solver.algorithm);
    if (!stop->count() && a && a->admm) c.solve.solver.stop = "papers";
  });
  s->add_option("--refine", c.solve.solver.refine, "the pipeline's refinement: auto|mm-accel|mm (auto: mm-accel)")->capture_default_str();
  s->add_option("--grad-tol", c.solve.solver.grad_tol,
                "gradient norm tolerance (0: off; " + honoured_by(&Info::gradient_stop) + ")")
      ->capture_default_str();
  s->add_option("--init", c.solve.init,
                "auto|random|dv or a file with dataset positions [n,p] (auto: dv for dv-pipeline, else random; dv: "
                "multilateration from path distances to the nearest anchors)")
      ->capture_default_str();
  s->add_option("--smooth-iter", c.solve.solver.smooth_iter,
                "dv-pipeline: relaxation iterations between its start and mm-accel")
      ->capture_default_str();
  s->add_option("--settle-iter", c.solve.solver.settle_iter,
                "dv-pipeline: mm-accel iterations before ml-agd (plain l2 model)")
      ->capture_default_str();
  s->add_option("--seed", c.solve.solver.seed, "seed of --init random and of the async activation clock")
      ->check(kSeed)
      ->capture_default_str();
  s->add_option("--partition", c.solve.partition,
                "auto|metis|bfs|parmetis|block (auto: bfs on one node, else parmetis; bfs: breadth-first "
                "bisection by every rank on its block of the graph, faster than metis, with a larger cut)")
      ->capture_default_str();
  s->add_option("--history-every", c.solve.solver.history_every, "record history every K iterations (0: auto)")
      ->capture_default_str();
  s->add_option("--test-every", c.solve.solver.test_every,
                "--stop gradient: test every K iterations (0: auto, 10; from 10,000 sensors 50, growing as the square root of the iterations done)")
      ->capture_default_str();
  s->add_option("--bb-rounds", c.solve.solver.bb_rounds,
                "consensus rounds per BB iteration (" + honoured_by(&Info::consensus_rounds) + ")")
      ->capture_default_str();
  s->add_option("--esdp-rho", c.solve.solver.esdp_rho, "ADMM penalty (" + honoured_by(&Info::admm) + ")")
      ->capture_default_str();
  s->add_option("--temporal-block", c.solve.solver.temporal_block,
                "iterations per pass over memory (same iterates; tests and records at pass ends; " +
                    honoured_by(&Info::temporal_blocking) + ")")
      ->capture_default_str();
  s->add_option("--mode", c.solve.solver.mode,
                "replay|free: replay the sequential activation order bit for bit, or let every rank activate its "
                "own nodes unsynchronised (not reproducible; docs/async.md; " + honoured_by(&Info::free_mode) + ")")
      ->capture_default_str();
  s->add_option("--straggler-delay", c.solve.solver.straggler_delay,
                "test option: one rank sleeps SECONDS per iteration (--mode free: per n_own activations of its own)")
      ->capture_default_str();
  s->add_option("--straggler-rank", c.solve.solver.straggler_rank,
                "the rank --straggler-delay slows (-1: the last)")
      ->capture_default_str();
  s->add_option("--target-cost", c.solve.solver.target_cost,
                "benchmark option: stop once the phase's cost is at or below this (tested with the stopping rule; 0: off)")
      ->capture_default_str();
  s->add_option("--weights", c.solve.solver.weights,
                "file|multiplicative:NF|none: ML weights 1/sigma^2 (auto: file when the network has sigmas; " +
                    honoured_by(&Info::measurement_model) + ")")
      ->capture_default_str();
  s->add_option("--loss", c.solve.solver.loss, "l2|huber:DELTA (" + honoured_by(&Info::measurement_model) + ")")
      ->capture_default_str();
  s->add_option("--json", c.solve.json, "write a JSON summary");
  s->add_option("--checkpoint", c.solve.checkpoint, "write checkpoints to this file (atomically replaced)");
  s->add_option("--checkpoint-every", c.solve.checkpoint_every, "checkpoint every K iterations");
  s->add_option("--checkpoint-seconds", c.solve.checkpoint_seconds, "checkpoint every S seconds of wall clock");
  s->add_option("--restart", c.solve.restart, "resume from a checkpoint (any number of ranks)");
  s->add_option("--progress-seconds", c.solve.progress_seconds, "seconds between progress lines")
      ->capture_default_str();
  s->add_flag("--check-monotone", c.solve.solver.check_monotone, "verify MM's surrogate never increases");
  s->add_flag("--strict", c.solve.strict, "refuse networks with sensors that cannot be localized");
  s->add_flag("-q,--quiet", c.solve.quiet, "no progress output");
}

void add_eval(CLI::App& app, Commands& c) {
  CLI::App* e = c.eval_cmd = app.add_subcommand("eval", "evaluate a result against a network");
  e->add_option("network", c.eval.network, "network file")->required();
  e->add_option("result", c.eval.result, "result file (or any file with positions)")->required();
  e->add_flag("--crlb", c.eval.crlb,
              "also compute the Cramer-Rao lower bound on the anchored rigid part and add the per-sensor "
              "covariances to the result file (group crlb)");
  e->add_option("--sigma", c.eval.sigma,
                "one noise standard deviation for --crlb (default: the network's, per measurement when present)");
  e->add_option("--fim-at", c.eval.fim_at, "--crlb: Fisher information at the true positions or at the estimate")
      ->check(CLI::IsMember({"auto", "truth", "estimate"}))
      ->capture_default_str();
  e->add_flag("--no-covariance", c.eval.no_covariance, "--crlb: leave the result file unchanged");
  e->add_option("--weights", c.eval.weights, "file|multiplicative:NF|none: weights of the ML cost (as snl solve)")
      ->capture_default_str();
  e->add_option("--loss", c.eval.loss, "l2|huber:DELTA: loss of the ML cost (as snl solve)")->capture_default_str();
  e->add_flag("--global-opt", c.eval.global_opt,
              "dim 1: the exact global ML optimum f* by enumeration, and f* - f_hat(RESULT) (003 Table I)");
  e->add_option("--global-opt-max-terms", c.eval.global_opt_max_terms,
                "--global-opt: refuse networks with more measurements (2^T sign patterns)")
      ->capture_default_str();
  e->add_option("--json", c.eval.json, "write a JSON summary");
}

void add_experiment(CLI::App& app, Commands& c) {
  CLI::App* x = c.experiment_cmd = app.add_subcommand("experiment", "Monte Carlo study over noise draws on a fixed network");
  x->add_option("network", c.experiment.network, "network file with truth (fixed geometry)")->required();
  x->add_option("-o,--output", c.experiment.output, "per-trial CSV")->required();
  x->add_option("--trajectory", c.experiment.trajectory, "CSV of ML cost vs communications per run");
  x->add_option("--h5", c.experiment.h5, "HDF5 copy of the per-trial table");
  x->add_option("--sigmas", c.experiment.sigmas, "noise levels")->delimiter(',')->capture_default_str();
  x->add_option("--trials", c.experiment.trials, "noise draws per sigma")->capture_default_str();
  x->add_option("--algorithms", c.experiment.algorithms, "methods (" + snl::algorithm_names(",", "", true) + ")")
      ->delimiter(',')->capture_default_str();
  x->add_option("--budget", c.experiment.budget, "communications (reals per sensor) per refinement")->capture_default_str();
  x->add_option("--relax-tol", c.experiment.relax_tol, "relaxation relative-improvement tolerance")->capture_default_str();
  x->add_option("--relax-max-iter", c.experiment.relax_max_iter, "relaxation iteration limit")->capture_default_str();
  x->add_option("--points", c.experiment.points, "trajectory points per run")->capture_default_str();
  x->add_option("--bb-rounds", c.experiment.bb_rounds, "consensus rounds per BB iteration")->capture_default_str();
  x->add_option("--start", c.experiment.start, "relaxation (refinements from its output) or random (all from one random start)")
      ->capture_default_str();
  x->add_option("--tol", c.experiment.tol, "methods' relative-improvement tolerance (0: whole budget)")->capture_default_str();
  x->add_option("--reach-rel", c.experiment.reach_rel, "relative margin for 'reached the best final cost'")
      ->capture_default_str();
  x->add_option("--seed", c.experiment.seed, "seed of the noise draws and starts")
      ->check(kSeed)
      ->capture_default_str();
  x->add_option("--partition", c.experiment.partition, "auto|metis|bfs|parmetis|block")->capture_default_str();
  x->add_flag("-q,--quiet", c.experiment.quiet, "no progress output");
}

void add_import(CLI::App& app, Commands& c) {
  CLI::App* m = c.import_cmd = app.add_subcommand(
      "import", "network file from text tables (CSV or whitespace-separated; docs/formats.md, Text files)");
  m->add_option("--sensor-edges", c.import.sensor_edges, "rows i,j,range[,sigma]")->required();
  m->add_option("--anchor-edges", c.import.anchor_edges, "rows i,anchor,range[,sigma]")->required();
  m->add_option("--anchors", c.import.anchors, "one anchor position per row (p = 1, 2 or 3 columns)")->required();
  m->add_option("--truth", c.import.truth, "one true position per sensor (optional)");
  m->add_option("-o,--output", c.import.output, "output network file")->required();
  m->add_option("--sensors", c.import.sensors, "number of sensors n (default: truth rows, else largest id + 1)");
  m->add_option("--index-base", c.import.index_base, "first sensor and anchor id in the files: 0 or 1")
      ->check(CLI::IsMember({0, 1}))
      ->capture_default_str();
  m->add_option("--sigma", c.import.sigma, "record the network's noise standard deviation (for eval --crlb)");
  m->add_flag("-q,--quiet", c.import.quiet, "print nothing on success");
}

void add_export(CLI::App& app, Commands& c) {
  CLI::App* x = c.export_cmd = app.add_subcommand("export", "positions of a result as CSV (sensor,x,y[,z])");
  x->add_option("result", c.export_.result, "result file")->required();
  x->add_option("-o,--output", c.export_.output, "output CSV file")->required();
  x->add_option("--network", c.export_.network, "add each sensor's localizability flags (columns flags,localizable)");
  x->add_option("--index-base", c.export_.index_base, "first sensor id written: 0 or 1")
      ->check(CLI::IsMember({0, 1}))
      ->capture_default_str();
  x->add_flag("-q,--quiet", c.export_.quiet, "print nothing on success");
}

// --anchors and --localizable of snl generate, into its options.
void parse_generate_choices(Commands& c) {
  auto& opt = c.gen.options;
  if (c.anchors == "auto") {
    opt.num_random_anchors = snl::kAutoAnchors;
  } else if (c.anchors == "corners") {
    opt.num_random_anchors = 0;
  } else {
    try {
      std::size_t pos = 0;
      opt.num_random_anchors = std::stoi(c.anchors, &pos);
      if (pos != c.anchors.size() || opt.num_random_anchors < 1) throw std::invalid_argument("");
    } catch (const std::exception&) {
      throw snl::Error("--anchors must be 'auto', 'corners' or a positive number, not '" + c.anchors + "'");
    }
  }
  if (c.localizable == "auto")
    opt.localizable = snl::GenerateOptions::Localizable::kAuto;
  else if (c.localizable == "yes")
    opt.localizable = snl::GenerateOptions::Localizable::kYes;
  else if (c.localizable == "no")
    opt.localizable = snl::GenerateOptions::Localizable::kNo;
  else
    throw snl::Error("--localizable must be auto, yes or no");
}

// Runs the chosen subcommand; returns the exit status.
int run_command(Commands& c, MPI_Comm comm) {
  if (*c.generate) {
    parse_generate_choices(c);
    snl::run_generate(c.gen, comm);
  } else if (*c.info_cmd) {
    snl::run_info(c.info, comm);
  } else if (*c.solve_cmd) {
    c.solve.check_monotone_given = c.solve_cmd->count("--check-monotone") > 0;
    return snl::run_solve(c.solve, comm);
  } else if (*c.eval_cmd) {
    snl::run_eval(c.eval, comm);
  } else if (*c.experiment_cmd) {
    snl::run_experiment(c.experiment, comm);
  } else if (*c.import_cmd) {
    snl::run_import(c.import, comm);
  } else if (*c.export_cmd) {
    snl::run_export(c.export_, comm);
  }
  return 0;
}

// Runs a command with every failure turned into one message and an exit status.
template <class Body>
int guarded(MPI_Comm comm, Body&& body) {
  try {
    return body();
  } catch (const snl::UsageError& err) {
    // An option the algorithm cannot honour: refused before anything is read or written.
    return fail(comm, err.what(), snl::kExitUsage);
  } catch (const snl::NumericalFailure& err) {
    // A method found no solution (raised identically on every rank): status 4, no output.
    return fail(comm, err.what(), 4);
  } catch (const snl::Error& err) {
    // snl::Error is raised identically on every rank: one message, clean exit.
    return fail(comm, err.what(), 1);
  } catch (const std::bad_alloc&) {
    // Anything else may be rank-local: never hang the others.
    snl::abort_all(comm, "out of memory");
  } catch (const std::exception& err) {
    snl::abort_all(comm, std::string("internal error: ") + err.what());
  }
  return 1;  // not reached: abort_all does not return
}

}  // namespace

// The options of `snl consensus generate|import|solve` (docs/consensus.md). They live
// here, beside the other subcommands' options, so that CLI11 (header-only) is
// compiled in one translation unit.
namespace snl {
namespace {

int consensus_generate_main(const std::vector<std::string>& args, MPI_Comm comm) {
  const bool root = comm_rank(comm) == 0;
  ConsensusGenerateCommand cmd;
  std::string family = "exp";
  CLI::App app{"generate a random consensus problem (HDF5, format snl-consensus)", "snl consensus generate"};
  app.add_option("-o,--output", cmd.output, "output problem file")->required();
  app.add_option("--nodes", cmd.options.nodes, "number of nodes n")->required();
  app.add_option("--avg-degree", cmd.options.avg_degree, "average degree of the random geometric graph")
      ->capture_default_str();
  app.add_option("--family", family, "exp|quadratic|logistic|least_squares")->capture_default_str();
  app.add_option("--dim", cmd.options.dim, "size q of x (1 for exp)")->capture_default_str();
  app.add_flag("--hamiltonian", cmd.options.hamiltonian, "plant a Hamilton path (stored in truth_path)");
  app.add_option("--seed", cmd.options.seed, "random seed")->check(kSeed)->capture_default_str();
  app.add_option("--samples-per-node", cmd.options.samples_per_node,
                 "logistic, least_squares: samples owned by each node")
      ->capture_default_str();
  app.add_option("--lambda", cmd.options.lambda, "logistic, least_squares: regularisation weight (> 0)")
      ->capture_default_str();
  app.add_flag("-q,--quiet", cmd.quiet, "print nothing on success");

  // Bad options (exit 2): parse errors, unknown family, option rules.
  try {
    std::vector<std::string> rev(args.rbegin(), args.rend());  // CLI11 takes them reversed
    app.parse(rev);
    if (family != "exp" && family != "quadratic" && family != "logistic" && family != "least_squares")
      throw Error("--family must be exp, quadratic, logistic or least_squares (got '" + family + "')");
    cmd.options.family = consensus::parse_family(family);
    cmd.options.validate();
  } catch (const CLI::CallForHelp&) {
    if (root) std::printf("%s", app.help().c_str());
    return 0;
  } catch (const CLI::ParseError& e) {
    if (root) std::fprintf(stderr, "snl: error: %s (see snl consensus generate --help)\n", e.what());
    return 2;
  } catch (const Error& e) {
    if (root) std::fprintf(stderr, "snl: error: %s\n", e.what());
    return 2;
  }
  try {
    run_consensus_generate(cmd, comm);
  } catch (const Error& e) {
    if (root) std::fprintf(stderr, "snl: error: %s\n", e.what());
    return 1;
  }
  return 0;
}

int consensus_import_main(const std::vector<std::string>& args, MPI_Comm comm) {
  const bool root = comm_rank(comm) == 0;
  ConsensusImportCommand cmd;
  CLI::App app{"build a consensus problem file (snl-consensus) from CSV tables of samples and links",
               "snl consensus import"};
  app.add_option("--samples", cmd.samples,
                 "CSV with a header row: a node id column, feature columns, a label (logistic: +1/-1) or target "
                 "(least_squares) column")
      ->required();
  app.add_option("--edges", cmd.edges, "CSV of links: two node ids per row (a header row is optional)")->required();
  app.add_option("-o,--output", cmd.output, "output problem file")->required();
  app.add_option("--family", cmd.family, "logistic|least_squares")->required();
  app.add_option("--lambda", cmd.lambda, "regularisation weight (> 0)")->capture_default_str();
  app.add_option("--nodes", cmd.nodes, "number of nodes n (default: the largest node id + 1)");
  app.add_option("--node-column", cmd.node_column, "header name of the node id column (default: the first)");
  app.add_option("--label-column", cmd.label_column, "header name of the label/target column (default: the last)");
  app.add_flag("-q,--quiet", cmd.quiet, "print nothing on success");
  try {
    std::vector<std::string> rev(args.rbegin(), args.rend());  // CLI11 takes them reversed
    app.parse(rev);
  } catch (const CLI::CallForHelp&) {
    if (root) std::printf("%s", app.help().c_str());
    return 0;
  } catch (const CLI::ParseError& e) {
    if (root) std::fprintf(stderr, "snl: error: %s (see snl consensus import --help)\n", e.what());
    return 2;
  }
  try {
    run_consensus_import(cmd, comm);
  } catch (const UsageError& e) {
    if (root) std::fprintf(stderr, "snl: error: %s\n", e.what());
    return 2;
  } catch (const Error& e) {
    if (root) std::fprintf(stderr, "snl: error: %s\n", e.what());
    return 1;
  }
  return 0;
}

int consensus_solve_main(const std::vector<std::string>& args, MPI_Comm comm) {
  const bool root = comm_rank(comm) == 0;
  ConsensusSolveCommand cmd;
  auto& o = cmd.solver;
  std::string dual;
  std::int64_t max_iter = 0, dual_max_iter = 0;
  double tol = 0, oracle_tol = 0, dual_tol = 0, damping = 0;
  std::string step;
  CLI::App app{"solve a consensus problem with a distributed method (run under mpirun)", "snl consensus solve"};
  app.add_option("problem", cmd.problem, "problem file (snl-consensus)")->required();
  app.add_option("-o,--output", cmd.output, "result file (snl-consensus-result)")->required();
  app.add_option("--method", o.method, "newton-tree|newton-path|subgradient|incremental|central")
      ->capture_default_str();
  auto* o_dual = app.add_option("--dual", dual, "Newton's dual solver: cg (default: preconditioned CG, one-hop messages), splitting (001's) or exact "
                                "(tree sweeps)");
  auto* o_max = app.add_option("--max-iter", max_iter, "primal iterations (default 100; baselines 1000)");
  auto* o_dmax = app.add_option("--dual-max-iter", dual_max_iter, "cg, splitting: dual iterations per Newton step (default 10000)");
  auto* o_tol = app.add_option("--tol", tol,
                               "Newton/central: stop when the decrement <= tol (default 1e-10); baselines: when the "
                               "running average's largest change in one iteration, max over nodes of "
                               "|xhat_p(k) - xhat_p(k-1)|, <= tol (default 0: run --max-iter)");
  auto* o_otol = app.add_option("--oracle-tol", oracle_tol,
                                "baselines: stop when the running average's max error against the oracle x* <= "
                                "oracle-tol (no node knows x*; default 0: off)");
  auto* o_dtol = app.add_option("--dual-tol", dual_tol,
                                "splitting: stop when max|w(t+1)-w(t)| <= dual-tol max|w(t+1)|; cg: the floor of the "
                                "forcing term eta in ||r|| <= eta ||r(0)|| (default 1e-12)");
  auto* o_step = app.add_option("--step", step,
                                "newton-tree, newton-path, central: armijo (default: backtracking on F, one "
                                "convergecast of F per trial) or damped (b/(theta+1)); subgradient, incremental: "
                                "a number alpha0 of the step alpha0/sqrt(k+1) (default 0.1)");
  auto* o_damping = app.add_option("--damping", damping, "--step damped: b in (0, 1) (default 0.9)");
  app.add_option("--partition", o.partition, "metis|block")->capture_default_str();
  app.add_option("--json", cmd.json, "write a JSON summary");
  app.add_option("--checkpoint", cmd.checkpoint, "write checkpoints to this file (atomically replaced)");
  app.add_option("--checkpoint-every", cmd.checkpoint_every, "checkpoint every K primal iterations");
  app.add_option("--restart", cmd.restart, "resume from a checkpoint (any number of ranks)");
  app.add_option("--progress-seconds", cmd.progress_seconds, "seconds between progress lines")->capture_default_str();
  app.add_flag("-q,--quiet", cmd.quiet, "no progress output");
  try {
    std::vector<std::string> rev(args.rbegin(), args.rend());  // CLI11 takes them reversed
    app.parse(rev);
    if (o_dual->count()) o.dual = dual;
    if (o_max->count()) o.max_iter = max_iter;
    if (o_dmax->count()) o.dual_max_iter = dual_max_iter;
    if (o_tol->count()) o.tol = tol;
    if (o_otol->count()) o.oracle_tol = oracle_tol;
    if (o_dtol->count()) o.dual_tol = dual_tol;
    if (o_step->count()) {
      char* end = nullptr;
      const double a = std::strtod(step.c_str(), &end);
      if (!step.empty() && end && *end == '\0')
        o.step = a;
      else
        o.step_rule = step;
    }
    if (o_damping->count()) o.damping = damping;
    const std::string bad = o.validate();
    if (!bad.empty()) throw Error(bad);
  } catch (const CLI::CallForHelp&) {
    if (root) std::printf("%s", app.help().c_str());
    return 0;
  } catch (const CLI::ParseError& e) {
    if (root) std::fprintf(stderr, "snl: error: %s (see snl consensus solve --help)\n", e.what());
    return 2;
  } catch (const Error& e) {
    if (root) std::fprintf(stderr, "snl: error: %s\n", e.what());
    return 2;
  }
  try {
    return run_consensus_solve(cmd, comm);
  } catch (const Error& e) {
    if (root) std::fprintf(stderr, "snl: error: %s\n", e.what());
    return 1;
  }
}

}  // namespace
}  // namespace snl

namespace {

// `snl consensus generate|import|solve ...` (seed 001): those commands parse their own
// options; failures become one message and an exit status, as every command.
int run_consensus(int argc, char** argv, MPI_Comm comm) {
  const bool root = snl::comm_rank(comm) == 0;
  const std::string which = argc >= 3 ? argv[2] : "";
  const std::vector<std::string> rest(argv + std::min(argc, 3), argv + argc);
  return guarded(comm, [&] {
    if (which == "generate") return snl::consensus_generate_main(rest, comm);
    if (which == "solve") return snl::consensus_solve_main(rest, comm);
    if (which == "import") return snl::consensus_import_main(rest, comm);
    if (which == "--help" || which == "-h") {
      if (root)
        std::printf(
            "snl consensus: distributed consensus optimisation, min_x sum_p f_p(x) over a network (seed 001;\n"
            "docs/distributed-newton.md)\n\n"
            "usage: snl consensus COMMAND [OPTIONS]\n\n"
            "commands:\n"
            "  generate  write a random problem (exp, quadratic, logistic or least_squares) to an HDF5 file\n"
            "  import    build a problem file (logistic or least_squares) from CSV tables of samples and links\n"
            "  solve     solve a problem file under mpirun: distributed Newton (newton-tree, newton-path),\n"
            "            the baselines (subgradient, incremental) or central\n\n"
            "each command's options: snl consensus COMMAND --help\n");
      return 0;
    }
    if (root)
      std::fprintf(stderr, "snl: error: %s (see snl consensus --help)\n",
                   which.empty() ? "a command is needed: snl consensus generate|import|solve ..."
                                 : ("unknown consensus command '" + which + "'; expected generate, import or solve")
                                       .c_str());
    return snl::kExitUsage;
  });
}

}  // namespace

int main(int argc, char** argv) {
  snl::tune_allocator(argv);  // may re-execute the program (snl/core/memory.hpp)
  MPI_Init(&argc, &argv);
  MPI_Comm comm = MPI_COMM_WORLD;
  snl::h5_quiet();
  const bool root = snl::comm_rank(comm) == 0;
  if (const char* why = snl::allocator_choice_error()) {
    if (root) std::fprintf(stderr, "snl: error: %s, not '%s'\n", why, std::getenv("SNL_MALLOC"));
    MPI_Finalize();
    return snl::kExitUsage;
  }

  CLI::App app{"snl: cooperative sensor network localization from noisy ranges (MPI-parallel)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "snl 0.1.0");
  Commands c;
  add_generate(app, c);
  add_info(app, c);
  add_solve(app, c);
  add_eval(app, c);
  add_experiment(app, c);
  add_import(app, c);
  add_export(app, c);

  // `snl consensus generate|import|solve ...` (seed 001) parse their own options.
  app.add_subcommand("consensus", "consensus optimisation (seed 001): snl consensus generate|import|solve --help")
      ->allow_extras()
      ->prefix_command();
  int status = 0;
  if (argc >= 2 && std::string(argv[1]) == "consensus") {
    status = run_consensus(argc, argv, comm);
  } else {
    try {
      app.parse(argc, argv);
    } catch (const CLI::ParseError& err) {
      // --help and --version exit 0; every parse error is a usage error (status 2).
      const int code = root ? app.exit(err) : err.get_exit_code();
      MPI_Finalize();
      return code == 0 ? 0 : snl::kExitUsage;
    }
    status = guarded(comm, [&] { return run_command(c, comm); });
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
