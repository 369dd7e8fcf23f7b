// snl generate: a random geometric network (on rank 0), written to HDF5.
#include <sstream>

#include "cli/cli_util.hpp"
#include "snl/cli/commands.hpp"
#include "snl/io/network.hpp"
#include "snl/problem/analysis.hpp"
#include "snl/problem/noise.hpp"

namespace snl {

using detail::fmt;
using detail::is_root;

void run_generate(const GenerateCommand& cmd, MPI_Comm comm) {
  const std::string bad = cmd.options.validate();
  if (!bad.empty()) throw Error(bad);
  const std::string bad_noise = cmd.noise.validate();
  if (!bad_noise.empty()) throw Error(bad_noise);
  check_output_path(cmd.output, comm);
  std::string summary, warning;
  collective_try(comm, [&] {
    if (!is_root(comm)) return;
    const double t0 = MPI_Wtime();
    GenerateReport rep;
    Network net = generate_network(cmd.options, &rep);
    if (cmd.noise.changes_network()) apply_noise_model(net, cmd.noise, cmd.options.sigma, rep.draw_seed);
    const double t1 = MPI_Wtime();
    write_network(cmd.output, net);
    const double t2 = MPI_Wtime();
    std::ostringstream os;
    os << "generated " << cmd.output << ": n=" << net.num_sensors << " m=" << net.num_anchors() << " p=" << net.dim
       << ", " << net.local_sensor_edges() << " sensor pairs (average degree " << fmt(rep.achieved_avg_degree, 4)
       << ", radius " << fmt(rep.radius, 5) << "), " << net.local_anchor_edges() << " anchor pairs (radius "
       << fmt(rep.anchor_radius, 5) << "), region side " << fmt(rep.side, 5) << ", sigma " << fmt(rep.sigma, 5);
    if (rep.radius > 0) os << " (" << fmt(rep.sigma / rep.radius, 3) << " of the radius)";
    os << ", seed " << cmd.options.seed << "\n"
       << "draws: " << rep.draws << "\n"
       << rep.localizability.summary() << "\n"
       << "time: generate " << fmt(t1 - t0, 3) << " s, write " << fmt(t2 - t1, 3) << " s";
    summary = os.str();
    warning = rep.warning;
  });
  if (is_root(comm) && !cmd.quiet) std::printf("%s\n", summary.c_str());
  // Also under --quiet: a network that cannot be localized is never written silently.
  if (is_root(comm) && !warning.empty()) std::fprintf(stderr, "snl: %s\n", warning.c_str());
}

}  // namespace snl
