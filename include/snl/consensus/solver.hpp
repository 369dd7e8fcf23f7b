#pragma once
// Distributed solvers of seed 001 (docs/distributed-newton.md): the distributed Newton
// method on the BFS spanning tree (001 Alg. 2) or on a Hamilton path (Alg. 1),
// with the dual solved by Wei-Ozdaglar-Jadbabaie's matrix splitting or exactly by
// two tree sweeps; the paper's baselines (distributed subgradient,
// Nedic-Ozdaglar; incremental, Ram-Nedic-Veeravalli); and `central`, the damped
// Newton method on F that gives the x* every method is measured against.
#include <mpi.h>

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "snl/consensus/problem.hpp"

namespace snl::consensus {

enum class Method { kNewtonTree, kNewtonPath, kSubgradient, kIncremental, kCentral };
enum class DualSolver { kNone, kSplitting, kExact, kCg };
/// Primal step of Newton and central: Armijo backtracking on F (the default),
/// or the papers' damped step b / (theta + 1) (1 once theta < 1/4).
enum class StepRule { kNone, kArmijo, kDamped };
const char* method_name(Method m);
const char* dual_name(DualSolver d);  ///< "none" | "splitting" | "exact" | "cg"
const char* step_rule_name(StepRule s);  ///< "none" | "armijo" | "damped"

/// Command-line options. Those left unset take the method's default; validate()
/// refuses non-positive values and an option the method cannot honour.
struct SolveOptions {
  std::string method = "newton-tree";       ///< newton-tree|newton-path|subgradient|incremental|central
  std::optional<std::string> dual;          ///< cg|splitting|exact (Newton only); default cg
  std::optional<std::int64_t> max_iter;     ///< primal iterations; default 100 (Newton, central), 1000 (baselines)
  std::optional<std::int64_t> dual_max_iter;  ///< dual iterations per Newton step (cg, splitting); default 10000
  std::optional<double> tol;       ///< Newton, central: decrement theta <= tol (default 1e-10); baselines: the
                                   ///< running average's largest change in one iteration, max_p |xhat_p(k) -
                                   ///< xhat_p(k-1)|, <= tol (a rule the nodes can apply; default 0: run max_iter)
  std::optional<double> oracle_tol;  ///< baselines: error of the running average against the oracle x* <= oracle_tol
                                     ///< (no node knows x*: a yardstick for experiments; default 0: off)
  std::optional<double> dual_tol;  ///< splitting ends when max|w(t+1) - w(t)| <= dual_tol max|w(t+1)|; cg: the
                                   ///< floor of its forcing term (||r|| <= max(dual_tol, min(0.1, theta_prev)) ||rhs||);
                                   ///< default 1e-12
  std::optional<double> step;      ///< baselines' alpha0 in alpha_k = alpha0 / sqrt(k + 1); default 0.1
  std::optional<std::string> step_rule;  ///< Newton, central: armijo (default) | damped
  std::optional<double> damping;   ///< damped rule: b of b / (theta + 1) when theta >= 1/4; default 0.9
  std::string partition = "metis"; ///< metis|block

  /// "" when valid, else one message naming the option.
  std::string validate() const;
  Method method_kind() const;      ///< after validate()
  DualSolver dual_kind() const;    ///< kNone for the methods without a dual
  StepRule step_kind() const;      ///< kNone for the baselines
  double damping_b() const;
  std::int64_t max_iterations() const;
  std::int64_t dual_max_iterations() const;
  double tolerance() const;
  double dual_tolerance() const;
  double step0() const;
  /// The options a checkpoint must match to be resumed (all but max_iter, tol, partition).
  std::string checkpoint_key() const;
};

/// One history record (after primal iteration `iteration`; 0 is the start).
struct HistoryRecord {
  std::int64_t iteration = 0;
  std::int64_t dual_iterations = 0;  ///< cumulative
  double max_abs_error = 0;          ///< max_p max_k |x_pk - x*_k|
  double objective = 0;              ///< F at the nodes' average
  double messages = 0;               ///< per node, cumulative
  double reals = 0;                  ///< per node, cumulative
  double avg_max_abs_error = 0;      ///< running averages (subgradient, incremental); NaN otherwise
  double avg_objective = 0;          ///< F at the nodes' average of the running averages; NaN otherwise
  double decrement = 0;              ///< Newton decrement theta of the step taken (Newton, central); NaN otherwise
  double step = 0;                   ///< primal step size used
  std::int64_t line_search_trials = 0;  ///< cumulative trial points of the Armijo rule (each one convergecast of F)
  double elapsed = 0;                ///< seconds since the solve began
};

/// The history columns of a result (the file's history/ datasets, snl.consensus's
/// history), in file order; each reads one field of a record as a double.
struct HistoryColumn {
  const char* name;
  double (*get)(const HistoryRecord&);
};
const std::vector<HistoryColumn>& history_columns();

struct SolveSummary {
  std::string method, dual, step_rule;
  std::int64_t iterations = 0, dual_iterations = 0, line_search_trials = 0;
  std::string termination;  ///< CONVERGENCE | NO_CONVERGENCE | SIGNAL | FAILURE
  std::string message;
  bool converged = false;
  double max_abs_error = 0, objective = 0, messages_per_node = 0, reals_per_node = 0;
  double wall_seconds = 0;
  int ranks = 1;
  std::vector<double> x_star;  ///< [q] the reference optimum (central_optimum)
  bool x_star_converged = false;  ///< false: x_star is not trusted and every error is NaN
  std::int64_t x_star_iterations = 0;
  double x_star_decrement = 0;    ///< the reference's last Newton decrement
  std::vector<HistoryRecord> history;
  std::string partition;       ///< what was used
  std::int32_t tree_depth = 0; ///< depth of the tree the method used (0 if none)
};

/// Checkpointing as in `snl solve`: a checkpoint every `every` primal
/// iterations and when a stop signal arrives (SIGTERM, SIGUSR1), written
/// atomically; a restart resumes bit-identically on any number of ranks.
struct CheckpointSettings {
  std::string path;
  std::int64_t every = 0;
  std::string restart;
  bool stop_on_signal = false;
};

using RecordCallback = std::function<void(const HistoryRecord&)>;

/// Collective. Solves `data` (validated, identical on every rank). On return
/// `x_rows` holds on rank 0 every node's copy of x in node order ([n * q]),
/// empty elsewhere. Throws snl::Error (on every rank) for invalid options.
SolveSummary solve(MPI_Comm comm, const ProblemData& data, const SolveOptions& options,
                   const CheckpointSettings& checkpoint, const RecordCallback& on_record,
                   std::vector<double>* x_rows);

/// The reference optimum x* and whether it was reached.
struct Optimum {
  std::vector<double> x;  ///< [q]
  bool converged = false;
  std::int64_t iterations = 0;
  double decrement = 0;   ///< Newton decrement theta at x
};

/// x* by Newton's method with Armijo backtracking on F, global sums in node
/// order (collective; the same bits on any number of ranks). Converged when
/// the decrement theta is <= 1e-12, or when it stops decreasing once below
/// 1e-8 (1 + |F|)^(1/2) (Newton's quadratic phase has reached F's rounding
/// level); not converged after `max_iterations` or on a numerical failure.
Optimum central_optimum(MPI_Comm comm, const ProblemData& data, std::int64_t max_iterations = 1000);

/// For tests: one Newton step of newton-tree/newton-path from the node copies
/// `x_rows` (node order, on every rank, warm start w = 0); returns the link
/// duals w in node order on every rank (row of the root, or of path[0], zero)
/// and the dual iterations it took.
std::vector<double> newton_dual(MPI_Comm comm, const ProblemData& data, const SolveOptions& options,
                                const std::vector<double>& x_rows, std::int64_t* dual_iterations = nullptr);

/// Order-independent 64-bit fingerprint of a problem (16 hex digits).
std::string problem_fingerprint(const ProblemData& data);

}  // namespace snl::consensus
