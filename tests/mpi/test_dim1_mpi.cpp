// One-dimensional networks (p = 1, 003 Fig. 2): every distributed algorithm
// gives bit-identical positions on 1, 2 and 3 ranks; on a collinear 2-D copy
// of the network (second coordinate 0, the same start) each gives the 1-D
// run's coordinates and keeps the second at 0. On the line
// sqrt(z^2 + 0^2) = |z| exactly and every added 0 term is +0.0, so the two runs
// do the same arithmetic: the comparison is exact (bitwise), not a tolerance.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cstring>

#include "snl/problem/metrics.hpp"
#include "solve_helpers.hpp"

using namespace snl;
using snl::test::allgather_positions;
using snl::test::make_network;
using snl::test::run;
using snl::test::slab_of;
using snl::test::world_rank;
using snl::test::world_size;

namespace {

const char* const kAlgorithms[] = {"relaxation", "mm", "mm-accel", "bb", "bb-calafiore", "pipeline", "pm", "async",
                                   "async-exact"};

Network line_network() {
  return make_network({.n = 60, .dim = 1, .radius = 0.08, .anchor_radius = 0.1, .sigma = 0.02, .seed = 5});
}

// The same network in the plane: every point (x, 0).
Network planar_copy(const Network& w) {
  Network p = w;
  p.dim = 2;
  auto widen = [](const std::vector<double>& v) {
    std::vector<double> o;
    for (double x : v) o.insert(o.end(), {x, 0.0});
    return o;
  };
  p.anchors = widen(w.anchors);
  p.truth = widen(w.truth);
  return p;
}

// Positions (global order) after `iters` iterations of `alg` from x0 (global order).
std::vector<double> run_from(MPI_Comm comm, const Network& whole, const std::string& alg, int iters,
                             const std::vector<double>& x0) {
  LocalizationProblem prob(comm, slab_of(whole, comm), PartitionMethod::kBlock, nullptr);
  SolverOptions opt;
  opt.algorithm = alg;
  opt.max_iter = iters;
  opt.tol = 0;
  opt.history_every = 1000000;
  Solver solver(prob, opt);
  std::vector<double> x;
  solver.solve(prob.file_rows_to_owned(x0, 0, whole.dim), &x);
  return allgather_positions(prob, x);
}

}  // namespace

TEST(Dim1, BitIdenticalForOneTwoThreeRanks) {
  const Network w = line_network();
  for (const char* alg : kAlgorithms) {
    const auto ref = run(MPI_COMM_SELF, w, alg, 40);
    ASSERT_EQ(ref.size(), std::size_t(w.num_sensors));
    for (int k = 2; k <= world_size(); ++k) {
      MPI_Comm sub;
      MPI_Comm_split(MPI_COMM_WORLD, world_rank() < k ? 0 : MPI_UNDEFINED, world_rank(), &sub);
      if (sub == MPI_COMM_NULL) continue;
      const auto x = run(sub, w, alg, 40);
      ASSERT_EQ(x.size(), ref.size());
      EXPECT_EQ(0, std::memcmp(x.data(), ref.data(), x.size() * sizeof(double))) << alg << " differs on " << k << " ranks";
      MPI_Comm_free(&sub);
    }
  }
}

TEST(Dim1, CollinearPlanarRunGivesTheSameCoordinates) {
  const Network w = line_network(), p = planar_copy(w);
  std::vector<double> x0(std::size_t(w.num_sensors)), x0p;
  for (std::size_t i = 0; i < x0.size(); ++i) x0[i] = w.truth[i] + 0.05 * ((i * 7) % 5 - 2.0);  // a perturbed start
  for (double v : x0) x0p.insert(x0p.end(), {v, 0.0});
  for (const char* alg : kAlgorithms) {
    const auto a = run_from(MPI_COMM_WORLD, w, alg, 60, x0);
    const auto b = run_from(MPI_COMM_WORLD, p, alg, 60, x0p);
    ASSERT_EQ(b.size(), 2 * a.size());
    int moved = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      EXPECT_EQ(a[i], b[2 * i]) << alg << ": sensor " << i << " first coordinate";
      EXPECT_EQ(0.0, b[2 * i + 1]) << alg << ": sensor " << i << " left the line";
      moved += a[i] != x0[i];
    }
    EXPECT_GT(moved, 0) << alg << " did not move";
  }
}
