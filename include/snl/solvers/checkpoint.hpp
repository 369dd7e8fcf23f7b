#pragma once
// Algorithm state in global order, so a checkpoint written on P ranks resumes
// on any number of ranks. Node rows are stored in sensor order; per-edge data
// as (i, j, values) records with i < j, each edge once; per-anchor-edge data as
// (i, k, values) records. Layout in docs/formats.md.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "snl/core/stop_signal.hpp"
#include "snl/io/h5file.hpp"
#include "snl/problem/problem.hpp"
#include "snl/solvers/history.hpp"

namespace snl {

class StateWriter {
 public:
  StateWriter(H5File& file, const LocalizationProblem& prob, std::string prefix = "state/")
      : f_(file), prob_(prob), prefix_(std::move(prefix)) {}
  void scalar(const std::string& name, double v);
  /// Owned rows (local order), `width` doubles each.
  void node_rows(const std::string& name, const double* owned, int width);
  /// One row per adjacency entry (graph CSR order); the copy held by the
  /// smaller-id end is stored (both ends hold identical values).
  void edge_rows(const std::string& name, const double* per_entry, int width);
  /// The same, with value c of CSR entry e of owned node v given by get(v, e,
  /// c) (for state kept in another layout: no copy of it is made).
  void edge_rows(const std::string& name, int width,
                 const std::function<double(LocalId, std::int64_t, int)>& get);
  /// One row per anchor measurement of owned nodes (anchor CSR order).
  void anchor_rows(const std::string& name, const double* per_entry, int width);

 private:
  H5File& f_;
  const LocalizationProblem& prob_;
  std::string prefix_;
};

class StateReader {
 public:
  StateReader(const H5File& file, const LocalizationProblem& prob, std::string prefix = "state/")
      : f_(file), prob_(prob), prefix_(std::move(prefix)) {}
  double scalar(const std::string& name) const;
  void node_rows(const std::string& name, double* owned, int width) const;
  void edge_rows(const std::string& name, double* per_entry, int width) const;
  /// The same, handing value c of CSR entry e of owned node v to set(v, e, c, value).
  void edge_rows(const std::string& name, int width,
                 const std::function<void(LocalId, std::int64_t, int, double)>& set) const;
  void anchor_rows(const std::string& name, double* per_entry, int width) const;

 private:
  const H5File& f_;
  const LocalizationProblem& prob_;
  std::string prefix_;
};

class Algorithm;
struct SolverOptions;

/// What a checkpoint must match to be resumed, as "algorithm|key=value|...":
/// every option that changes the iterates or the iteration at which a phase
/// stops, so that a resumed run ends with the uninterrupted run's bytes.
///   --algorithm        the state's layout and the phases
///   --max-iter         where a phase ends (the pipeline's MM starts there), the
///                      pass boundaries and, with --history-every 0, the history spacing
///   --tol, --grad-tol  where a phase stops (the pipeline's MM starts there)
///   --history-every    which iterations are recorded; with --temporal-block, the pass boundaries
///   --bb-rounds        BB's iterates
///   --temporal-block   where tolerances are tested (pass ends); only when not 1
///   --stop             where a phase stops; only when not papers
///   --refine           the pipeline's second phase; only when not mm
///   --seed             async and async-exact only: their activation sequence is a
///                      function of (seed, activation count)
/// Need not match: --partition and the number of ranks (results are
/// partition-independent), --init and --seed of other methods (the checkpoint
/// holds the iterates; the start is not read), --check-monotone, output options.
std::string checkpoint_options(const SolverOptions& opt);

/// The root attributes of a checkpoint file (layout in docs/formats.md):
/// where the run stands, and what it must match to be resumed.
struct CheckpointHeader {
  std::string network_fingerprint;  ///< network_fingerprint() of the input
  std::string options;              ///< Solver::options_fingerprint()
  std::string algorithm;            ///< --algorithm
  std::int64_t phase = 0;           ///< index of the phase in the algorithm's phases
  std::string phase_algorithm;      ///< that phase's method
  std::int64_t phase_iteration = 0, total_iteration = 0;
  double messages = 0, reals = 0;   ///< cumulative per sensor
  double elapsed = 0;               ///< seconds of the run so far
  std::int64_t ranks = 0, num_sensors = 0, dim = 0;
};

/// Collective: writes a checkpoint (header, history, the algorithm's state)
/// to `path`, atomically replacing it.
void write_checkpoint(const std::string& path, const LocalizationProblem& prob, const CheckpointHeader& header,
                      const std::vector<IterationSummary>& history, const Algorithm& alg);

/// Checks that `f` is a checkpoint of the network and options given
/// (checkpoint_options()) and returns its header; throws snl::Error (the same
/// on every rank, naming the first option that differs) otherwise.
CheckpointHeader read_checkpoint_header(const H5File& f, const std::string& network_fingerprint,
                                        const std::string& options);
/// The history a checkpoint holds.
std::vector<IterationSummary> read_checkpoint_history(const H5File& f);

/// Order-independent 64-bit fingerprint of a network slab's content
/// (collective: identical for any number of ranks), as 16 hex digits.
std::string network_fingerprint(const Network& slab, MPI_Comm comm);

}  // namespace snl
