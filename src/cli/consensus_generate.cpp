// `snl consensus generate`: a random consensus problem file (docs/consensus.md).
#include <algorithm>
#include <cstdio>
#include <iomanip>
#include <sstream>
#include <string>
#include <vector>

#include "snl/cli/commands.hpp"
#include "snl/cli/consensus.hpp"
#include "snl/core/mpi_util.hpp"

namespace snl {

namespace {

std::string summary_line(const ConsensusGenerateCommand& cmd, const consensus::ProblemData& d,
                         const consensus::GenerateReport& rep, double t_gen, double t_write) {
  const auto E = static_cast<double>(d.edges.size() / 2);
  std::ostringstream os;
  os.precision(4);
  os << "generated " << cmd.output << ": n=" << d.num_nodes << ", " << d.edges.size() / 2
     << " links (average degree " << 2.0 * E / static_cast<double>(d.num_nodes) << ", radius " << rep.radius << ", "
     << rep.geometric_links << " geometric";
  if (cmd.options.hamiltonian) os << ", " << rep.path_links << " from the planted Hamilton path";
  os << ", " << rep.connect_links << " joining " << rep.components << " component(s))"
     << ", family " << consensus::family_name(d.family) << ", dim " << d.dim;
  if (consensus::has_samples(d.family)) os << ", " << d.num_samples() << " samples, lambda " << d.lambda;
  os << ", seed " << cmd.options.seed << std::fixed << std::setprecision(3) << "\ntime: generate " << t_gen
     << " s, write " << t_write << " s";
  return os.str();
}

}  // namespace

void run_consensus_generate(const ConsensusGenerateCommand& cmd, MPI_Comm comm) {
  cmd.options.validate();
  check_output_path(cmd.output, comm);
  std::string summary;
  collective_try(comm, [&] {
    if (comm_rank(comm) != 0) return;
    const double t0 = MPI_Wtime();
    consensus::GenerateReport rep;
    const consensus::ProblemData d = consensus::generate_problem(cmd.options, &rep);
    const double t1 = MPI_Wtime();
    consensus::write_problem(MPI_COMM_SELF, cmd.output, d);
    summary = summary_line(cmd, d, rep, t1 - t0, MPI_Wtime() - t1);
  });
  if (comm_rank(comm) == 0 && !cmd.quiet) std::printf("%s\n", summary.c_str());
}

}  // namespace snl
