#pragma once
// The subcommands of the `snl` executable, as library functions so that the
// app stays thin and tests can call them. Each is collective over `comm` and
// throws snl::Error (identical on every rank) on failure.
#include <mpi.h>

#include <cstdint>
#include <string>
#include <vector>

#include "snl/problem/generate.hpp"
#include "snl/problem/noise.hpp"
#include "snl/solvers/solver.hpp"

namespace snl {

/// An option the command cannot honour (e.g. --grad-tol for a method without
/// a gradient-norm stop): a command-line usage error, exit status kExitUsage.
class UsageError : public Error {
 public:
  using Error::Error;
};
constexpr int kExitUsage = 2;

struct GenerateCommand {
  std::string output;
  GenerateOptions options;
  NoiseOptions noise;  ///< --noise, --nlos-fraction, --nlos-bias
  bool quiet = false;
};
void run_generate(const GenerateCommand& cmd, MPI_Comm comm);

struct InfoCommand {
  std::string network;
  std::string json;  ///< optional summary file
  bool strict = false;  ///< non-zero exit if some sensor cannot be localized
};
void run_info(const InfoCommand& cmd, MPI_Comm comm);

struct SolveCommand {
  std::string network;
  std::string output;
  /// auto (dv for dv-pipeline, else random), random, dv (dv_start.hpp), or a file with dataset `positions`
  std::string init = "auto";
  std::string json;
  std::string partition = "auto";  ///< bfs on one node, parmetis across nodes
  SolverOptions solver;
  std::string checkpoint;               ///< --checkpoint CKPT.h5
  std::int64_t checkpoint_every = 0;    ///< --checkpoint-every K (iterations)
  double checkpoint_seconds = 0;        ///< --checkpoint-seconds S (wall clock)
  std::string restart;                  ///< --restart CKPT.h5
  bool quiet = false;
  bool strict = false;  ///< refuse networks with unlocalizable sensors
  /// --check-monotone was on the command line (solver.check_monotone is also on by default in debug builds)
  bool check_monotone_given = false;
  double progress_seconds = 2.0;
};
/// Returns the process exit status (0 on success).
int run_solve(const SolveCommand& cmd, MPI_Comm comm);

struct EvalCommand {
  std::string network;
  std::string result;
  bool crlb = false;
  double sigma = -1;  ///< < 0: the network's sigmas (per measurement when present)
  std::string json;
  /// Where the Fisher information is evaluated: "truth", "estimate", or "auto"
  /// (the true positions when the network has them, else the estimate).
  std::string fim_at = "auto";
  bool no_covariance = false;  ///< do not add the per-sensor covariances to the result file
  std::string weights = "auto", loss = "l2";  ///< the ML cost's model, as snl solve --weights/--loss
  /// dim 1: the exact global ML optimum f* (global_1d.hpp) and f* - f_hat(RESULT),
  /// the true gap of 003 Table I when RESULT minimizes f_hat.
  bool global_opt = false;
  int global_opt_max_terms = 26;
};
void run_eval(const EvalCommand& cmd, MPI_Comm comm);

struct ExperimentCommand {
  std::string network;            ///< fixed geometry (truth, edges, anchors)
  std::string output;             ///< tidy per-trial CSV
  std::string trajectory;         ///< optional CSV: ML cost vs communications
  std::string h5;                 ///< optional HDF5 copy of the per-trial table
  std::vector<double> sigmas = {0.01, 0.05, 0.1};
  int trials = 100;
  std::vector<std::string> algorithms = {"mm", "bb"};  ///< single-phase names of the registry
  double budget = 20000;          ///< reals per sensor for each refinement method
  double relax_tol = 1e-6;        ///< relaxation stopping rule (003, Sec. V)
  std::int64_t relax_max_iter = 100000;
  std::int64_t points = 200;      ///< trajectory points per run
  int bb_rounds = 20;
  double reach_rel = 1e-3;        ///< "reached the best cost" = within this relative margin
  std::string start = "relaxation";  ///< methods start from the relaxation's output, or from random
  double tol = 0;                 ///< methods' relative-improvement tolerance (0: spend the whole budget)
  std::uint64_t seed = 1;
  std::string partition = "auto";  ///< bfs on one node, parmetis across nodes
  bool quiet = false;
};
/// Monte Carlo study over noise draws (issue: experiment driver). Collective.
void run_experiment(const ExperimentCommand& cmd, MPI_Comm comm);

struct ImportCommand {
  std::string sensor_edges;  ///< rows i,j,range[,sigma]
  std::string anchor_edges;  ///< rows i,anchor,range[,sigma]
  std::string anchors;       ///< one anchor position per row (p columns)
  std::string truth;         ///< optional: one true position per sensor
  std::string output;        ///< network file
  std::int64_t sensors = 0;  ///< n (0: truth rows, else largest sensor id + 1)
  int index_base = 0;        ///< ids in the files start at 0 or 1
  double sigma = -1;         ///< network noise standard deviation (< 0: unknown)
  bool quiet = false;
};
/// A network file from text tables (docs/formats.md, "Text files"). Collective.
void run_import(const ImportCommand& cmd, MPI_Comm comm);

struct ExportCommand {
  std::string result;   ///< result file (or any file with positions and the result attributes)
  std::string output;   ///< CSV
  std::string network;  ///< optional: adds each sensor's localizability flags
  int index_base = 0;   ///< first sensor id written
  bool quiet = false;
};
/// A result's positions as CSV. Collective.
void run_export(const ExportCommand& cmd, MPI_Comm comm);

/// A file a command reads or writes besides the output being checked: its role
/// ("the network", "--json") and its path ("" = not given).
struct OtherFile {
  std::string role, path;
};
/// Checks on rank 0 that `path` can be created (its directory exists and is
/// writable) and names none of `others` (the command's inputs and its other
/// outputs: the same path, or the same file under another name); every rank
/// throws the same error otherwise.
void check_output_path(const std::string& path, MPI_Comm comm, const std::vector<OtherFile>& others = {});

}  // namespace snl
