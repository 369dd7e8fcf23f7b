// `snl consensus generate`: a random consensus problem file (docs/consensus.md).
#include <CLI/CLI.hpp>
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
  if (d.family == consensus::Family::kLogistic) os << ", " << d.num_samples() << " samples, lambda " << d.lambda;
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

int consensus_generate_main(const std::vector<std::string>& args, MPI_Comm comm) {
  const bool root = comm_rank(comm) == 0;
  ConsensusGenerateCommand cmd;
  std::string family = "exp";
  CLI::App app{"generate a random consensus problem (HDF5, format snl-consensus)", "snl consensus generate"};
  app.add_option("-o,--output", cmd.output, "output problem file")->required();
  app.add_option("--nodes", cmd.options.nodes, "number of nodes n")->required();
  app.add_option("--avg-degree", cmd.options.avg_degree, "average degree of the random geometric graph")
      ->capture_default_str();
  app.add_option("--family", family, "exp|quadratic|logistic")->capture_default_str();
  app.add_option("--dim", cmd.options.dim, "size q of x (1 for exp)")->capture_default_str();
  app.add_flag("--hamiltonian", cmd.options.hamiltonian, "plant a Hamilton path (stored in truth_path)");
  app.add_option("--seed", cmd.options.seed, "random seed")->capture_default_str();
  app.add_option("--samples-per-node", cmd.options.samples_per_node, "logistic: samples owned by each node")
      ->capture_default_str();
  app.add_option("--lambda", cmd.options.lambda, "logistic: regularisation weight (> 0)")->capture_default_str();
  app.add_flag("-q,--quiet", cmd.quiet, "print nothing on success");

  // Bad options (exit 2): parse errors, unknown family, option rules.
  try {
    std::vector<std::string> rev(args.rbegin(), args.rend());  // CLI11 takes them reversed
    app.parse(rev);
    if (family != "exp" && family != "quadratic" && family != "logistic")
      throw Error("--family must be exp, quadratic or logistic (got '" + family + "')");
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

}  // namespace snl
