#pragma once
// One record of a run's history (what iteration callbacks see), and the one
// table of its columns that checkpoints and result files are written and read
// with (the table is defined next to the checkpoint code, checkpoint.cpp).
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace snl {

/// What an iteration callback (and the history) sees.
struct IterationSummary {
  std::string phase;             ///< algorithm of the current phase
  std::int64_t iteration = 0;    ///< within the phase
  std::int64_t total_iteration = 0;
  double cost = NAN;             ///< the cost the phase's algorithm minimizes
  double ml_cost = NAN;          ///< f(x), comparable across algorithms
  double rel_change = NAN;       ///< ||x(k)-x(k-1)|| / ||x(k)||
  double grad_norm = NAN;
  double rmse = NAN, mpe = NAN;  ///< when truth is known
  double messages = 0;           ///< cumulative messages per sensor (all phases)
  double reals = 0;              ///< cumulative reals per sensor (all phases)
  double elapsed = 0;            ///< seconds since solve() began
};

/// A history column: dataset history/<name> of checkpoints, history/<result_name>
/// of result files (docs/formats.md); the phase is stored as its algorithm code.
struct HistoryColumn {
  const char* name;
  const char* result_name;
  bool needs_truth;  ///< result files hold it only when the network has truth (rmse, mpe)
  double (*get)(const IterationSummary&);
  void (*set)(IterationSummary&, double);
};

/// Every column, in the order of result files.
const std::vector<HistoryColumn>& history_columns();

/// Column c of the history, as written to files.
std::vector<double> history_column(const std::vector<IterationSummary>& h, const HistoryColumn& c);

}  // namespace snl
