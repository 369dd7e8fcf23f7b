// Generates a small network with the installed library and solves it on one rank.
#include <mpi.h>

#include <cstdio>

#include "snl/problem/generate.hpp"
#include "snl/solvers/solver.hpp"

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  snl::GenerateOptions g;
  g.sensors = 30;
  g.anchor_radius = 2;
  const snl::Network net = snl::generate_network(g);
  snl::LocalizationProblem prob(MPI_COMM_WORLD, net, snl::PartitionMethod::kBlock, nullptr);
  snl::SolverOptions o;
  o.algorithm = "pipeline";
  const snl::Summary s = snl::Solver(prob, o).solve(snl::random_initial_positions(prob, 1), nullptr);
  std::printf("consumer: %s, rmse %.3g\n", snl::to_string(s.termination), s.errors.rmse);
  MPI_Finalize();
  return s.errors.rmse < 0.05 ? 0 : 1;
}
