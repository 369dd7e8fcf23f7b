#pragma once
// The `snl consensus ...` subcommands (docs/consensus.md) as library functions.
// Each is collective over `comm`.
#include <mpi.h>

#include <string>
#include <vector>

#include "snl/consensus/problem.hpp"

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

/// `snl consensus generate ARGS...`: parses `args` (the words after
/// "generate"), runs, and reports errors on rank 0 as one "snl: error: ..." line.
/// Returns the exit status: 0 success (or --help), 2 bad options, 1 failure.
int consensus_generate_main(const std::vector<std::string>& args, MPI_Comm comm);

}  // namespace snl
