#pragma once
// The one list of methods: every --algorithm value with its file code, its
// factory and what it can honour. The CLI help and checks, SolverOptions::validate,
// the Solver's phases, the experiment driver, checkpoints and histories all read
// this table, so a method is added in one place (plus its own .cpp file).
#include <memory>
#include <string>
#include <vector>

namespace snl {

class Algorithm;
class LocalizationProblem;
struct SolverOptions;

enum class AlgorithmId { kRelaxation, kMM, kPipeline, kBB, kPM, kAsync, kAsyncExact, kMMAccel, kSdp, kEsdp, kEdm, kBBCalafiore, kEsdpDist, kDvPipeline, kMlAgd };

struct AlgorithmInfo {
  AlgorithmId id;
  const char* name;  ///< --algorithm value, Algorithm::name(), history phase name
  /// Code in history, checkpoint and experiment files; -1 for the pipeline,
  /// which files record as its phases.
  int code;
  /// Builds the method; nullptr for the pipeline (the Solver runs its phases).
  std::unique_ptr<Algorithm> (*make)(LocalizationProblem&, const SolverOptions&);
  /// The phases the Solver runs, in order (a method alone is its own phase).
  std::vector<AlgorithmId> phases;
  // Capabilities: what lets the CLI refuse an option a method cannot honour.
  bool synchronous;        ///< every node updates from the previous iterate (else sequential semantics)
  bool temporal_blocking;  ///< honours --temporal-block (iterate_levels runs several iterations per pass)
  bool gradient_stop;      ///< computes a gradient norm, so --grad-tol can stop it (pipeline: relaxation phase)
  bool consensus_rounds;   ///< honours --bb-rounds (consensus rounds per iteration)
  bool monotone_surrogate; ///< --check-monotone verifies its objective (the MM surrogate) never increases
  bool gap_certificate;    ///< where it ends, the 003 eq. 22 certificate is valid (a minimizer of f_hat)
  bool measurement_model = false;  ///< honours --weights and --loss (weights.hpp)
  /// Solved in one step (the centralized SDP relaxations): the Solver stops after
  /// its first iteration; --tol, --max-iter, --init FILE and checkpoints are refused.
  bool one_shot = false;
  /// An ADMM method: honours --esdp-rho (its penalty) and stops only by --stop papers.
  bool admm = false;
  /// Honours --mode free (async, async-exact: ranks activate their own nodes unsynchronised).
  bool free_mode = false;
};

/// Every method, in the order of the CLI help.
const std::vector<AlgorithmInfo>& algorithm_registry();
/// The entry of `name`; nullptr if there is none.
const AlgorithmInfo* find_algorithm(const std::string& name);
const AlgorithmInfo& algorithm_info(AlgorithmId id);

/// The names joined by `sep`, the last one by `last_sep` ("" = sep);
/// single_phase_only leaves out the pipeline (the experiment's --algorithms).
std::string algorithm_names(const std::string& sep, const std::string& last_sep = "",
                            bool single_phase_only = false);

/// The names of the methods with a capability, e.g. algorithms_with(&AlgorithmInfo::gradient_stop), joined by ", ".
std::string algorithms_with(bool AlgorithmInfo::*capability);

/// Numeric codes of the algorithms in history/checkpoint/experiment files:
/// 0=relaxation 1=mm 2=bb 3=pm 4=async 5=async-exact 6=mm-accel 7=sdp 8=esdp 10=bb-calafiore 11=edm 12=esdp-dist
/// 13=ml-agd
/// (9 for anything else).
int algorithm_code(const std::string& name);
const char* algorithm_name(int code);  ///< inverse of algorithm_code ("?" if unknown)
/// "0=relaxation 1=mm ...": the legend written next to the codes in files.
std::string algorithm_codes_legend();

/// Factory: every method but the pipeline. Throws snl::Error for an unknown name.
std::unique_ptr<Algorithm> make_algorithm(AlgorithmId id, LocalizationProblem& prob, const SolverOptions& opt);
std::unique_ptr<Algorithm> make_algorithm(const std::string& name, LocalizationProblem& prob,
                                          const SolverOptions& opt);

}  // namespace snl
