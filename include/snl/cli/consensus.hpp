#pragma once
// The `snl consensus ...` subcommands (docs/consensus.md) as library functions.
// Each is collective over `comm`.
#include <mpi.h>

#include <cstdint>
#include <string>
#include <vector>

#include "snl/consensus/problem.hpp"
#include "snl/consensus/solver.hpp"

namespace snl {

// ---- generate (problem side) ----
struct ConsensusGenerateCommand {
  std::string output;
  consensus::GenerateOptions options;
  bool quiet = false;
};
/// Generates a problem and writes it atomically (an existing output is replaced
/// only on success). Throws snl::Error (identical on every rank) on failure.
void run_consensus_generate(const ConsensusGenerateCommand& cmd, MPI_Comm comm);

// ---- import (problem side) ----
struct ConsensusImportCommand {
  std::string samples;       ///< CSV: header, then node id, features, label (or target) per row
  std::string edges;         ///< CSV: two node ids per row (header optional)
  std::string output;
  std::string family;        ///< logistic | least_squares
  double lambda = 1.0;       ///< > 0
  GlobalId nodes = 0;        ///< n; 0: the largest node id in either file + 1
  std::string node_column;   ///< header name of the node id column ("": the first)
  std::string label_column;  ///< header name of the label column ("": the last)
  bool quiet = false;
};
/// Builds a problem file from the two CSV files and writes it atomically. Throws
/// snl::UsageError for options that cannot be honoured (exit 2) and snl::Error
/// naming the file and line for bad data (exit 1); identical on every rank.
void run_consensus_import(const ConsensusImportCommand& cmd, MPI_Comm comm);

// ---- solve (solver side) ----
struct ConsensusSolveCommand {
  std::string problem;
  std::string output;
  std::string json;
  consensus::SolveOptions solver;
  std::string checkpoint;             ///< --checkpoint CKPT.h5
  std::int64_t checkpoint_every = 0;  ///< --checkpoint-every K (primal iterations)
  std::string restart;                ///< --restart CKPT.h5
  bool quiet = false;
  double progress_seconds = 2.0;
};
/// Returns the process exit status (0 on success, 3 when stopped by a signal
/// after writing a checkpoint, 4 on a numerical failure). Throws snl::Error
/// (identical on every rank) on bad input, with no output touched.
int run_consensus_solve(const ConsensusSolveCommand& cmd, MPI_Comm comm);

}  // namespace snl
