// 003 Table I / Fig. 2 in one process (repro/repro_003_table1.sh builds and
// runs it): per noise draw t = 1..TRIALS, the star of `snl generate --dim 1
// --topology star --sensors 1 --sigma 0.25 --seed t`, the relaxation as
// `snl solve --algorithm relaxation --seed t --tol 1e-12 --max-iter 100000`
// does it, and what `snl eval --global-opt` reports. One CSV row per trial on
// standard output. The same library calls as the CLI, without its three
// process start-ups per trial (minutes on a loaded machine).
#include <mpi.h>

#include <cstdio>
#include <cstdlib>

#include "snl/problem/generate.hpp"
#include "snl/problem/global_1d.hpp"
#include "snl/problem/metrics.hpp"
#include "snl/solvers/solver.hpp"

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  const int trials = argc > 1 ? std::atoi(argv[1]) : 500;
  std::printf("trial,f_star,f_hat,true_gap,gap_certificate,apriori_bound,f_at_x_hat,x_hat,x_star,iterations,r1,r2,r3\n");
  for (int t = 1; t <= trials; ++t) {
    snl::GenerateOptions g;
    g.dim = 1;
    g.sensors = 1;
    g.topology = snl::GenerateOptions::Topology::kStar;
    g.sigma = 0.25;
    g.seed = static_cast<std::uint64_t>(t);
    const snl::Network net = snl::generate_network(g);
    snl::LocalizationProblem prob(MPI_COMM_SELF, net, snl::PartitionMethod::kBlock, nullptr);
    snl::SolverOptions so;
    so.algorithm = "relaxation";
    so.tol = 1e-12;
    so.max_iter = 100000;
    so.seed = static_cast<std::uint64_t>(t);
    so.history_every = 1000000;
    snl::Solver solver(prob, so);
    std::vector<double> x;
    const auto sum = solver.solve(snl::random_initial_positions(prob, so.seed), &x);
    const snl::CostTerms c = snl::evaluate_costs(prob, x.data());
    const snl::GlobalOptimum1D opt = snl::global_ml_optimum_1d(net);
    std::printf("%d,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%lld,%.17g,%.17g,%.17g\n", t, opt.cost, c.relaxed,
                opt.cost - c.relaxed, c.certificate, c.apriori, c.ml, x[0], opt.positions[0],
                static_cast<long long>(sum.iterations), net.anchor_ranges[0], net.anchor_ranges[1], net.anchor_ranges[2]);
  }
  MPI_Finalize();
  return 0;
}
