// The Barzilai-Borwein baseline (src/solvers/bb.cpp) against its serial
// reference twin (tests/reference/bb.hpp, written from algorithms.md): the same
// positions after K iterations on any number of ranks, for the default T = 20
// consensus rounds and for a short T whose estimates differ node by node.
#include <gtest/gtest.h>
#include <mpi.h>

#include "reference/bb.hpp"
#include "solve_helpers.hpp"

using namespace snl;
using snl::test::allgather_positions;
using snl::test::make_network;
using snl::test::merged;
using snl::test::slab_of;

namespace {

std::vector<double> run_bb(const Network& w, int iters, int rounds, std::vector<double>* x0) {
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  SolverOptions opt;
  opt.algorithm = "bb";
  opt.max_iter = iters;
  opt.tol = 0;
  opt.bb_rounds = rounds;
  opt.history_every = 1000000;
  Solver solver(prob, opt);
  const auto start = random_initial_positions(prob, 3);
  *x0 = allgather_positions(prob, start);
  std::vector<double> x;
  solver.solve(start, &x);
  return allgather_positions(prob, x);
}

void expect_matches(const snl::test::NetSpec& spec, int iters, int rounds) {
  const Network w = make_network(spec);
  std::vector<double> x0;
  const auto x = run_bb(w, iters, rounds, &x0);
  const auto xr = reference::bb(merged(w), x0, iters, rounds);
  ASSERT_EQ(x.size(), xr.size());
  double moved = 0;
  for (std::size_t t = 0; t < x.size(); ++t) {
    EXPECT_NEAR(x[t], xr[t], 1e-12) << "coordinate " << t << ", T = " << rounds;
    moved = std::max(moved, std::abs(x[t] - x0[t]));
  }
  EXPECT_GT(moved, 1e-3);  // the comparison is not between two unmoved starts
}

TEST(BBReference, DefaultRounds2D) {
  expect_matches({.n = 50, .dim = 2, .radius = 0.3, .anchor_radius = 0.3, .sigma = 0.02, .duplicates = true}, 30, 20);
}

TEST(BBReference, FewRoundsLocalEstimates) {
  // T = 2: far from the average, every node takes its own step.
  expect_matches({.n = 50, .dim = 2, .radius = 0.3, .anchor_radius = 0.3, .sigma = 0.02}, 30, 2);
}

TEST(BBReference, ThreeDimensions) {
  expect_matches({.n = 40, .dim = 3, .radius = 0.45, .anchor_radius = 0.45, .sigma = 0.02, .seed = 9}, 25, 5);
}

}  // namespace
