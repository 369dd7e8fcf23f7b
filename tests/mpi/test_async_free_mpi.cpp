// 003's asynchronous method run for real (async / async-exact --mode free,
// src/solvers/async.cpp, FreeHalo in src/graph/free_halo.cpp; docs/async.md):
// every rank activates its own nodes on its own clock, so the iterates are not
// reproducible, but the run must reach the relaxation's optimum (the cost of
// the synchronous relaxation run to a tight tolerance) on any number of ranks,
// 2D and 3D; --max-iter counts n_own activations per rank; a run stopped
// after a checkpoint and restarted from it reaches the same optimum.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "solve_helpers.hpp"

using namespace snl;
using snl::test::make_network;
using snl::test::merged;
using snl::test::NetSpec;
using snl::test::solve_outcome;
using snl::test::world_rank;
using snl::test::world_size;

namespace {

// f_hat at the relaxation's optimum: Nesterov's synchronous method to a tight tolerance.
double relaxation_optimum(const Network& w) {
  SolverOptions opt;
  opt.algorithm = "relaxation";
  opt.tol = 1e-9;
  opt.max_iter = 400000;
  opt.history_every = 500;  // the gradient test's interval too
  const auto o = solve_outcome(MPI_COMM_WORLD, w, opt);
  EXPECT_TRUE(o.s.converged) << o.s.message;
  if (world_rank() == 0)
    std::printf("relaxation: f_hat %.12g, %lld iterations, %.2f s (%s)\n", o.s.costs.relaxed,
                static_cast<long long>(o.s.iterations), o.s.wall_seconds, o.s.message.c_str());
  return o.s.costs.relaxed;
}

SolverOptions free_options(const std::string& alg) {
  SolverOptions opt;
  opt.algorithm = alg;
  opt.mode = "free";
  opt.tol = 1e-6;
  opt.max_iter = 300000;  // per rank: a rank descheduled for long may leave another to race ahead
  return opt;
}

struct Case {
  NetSpec spec;
  const char* alg;
};

// Well-connected small networks (the inexact step 1/L is slow on sparse ones).
const Case kCases[] = {
    {{.n = 160, .dim = 2, .radius = 0.3, .anchor_radius = 0.45, .sigma = 0.05, .seed = 11}, "async"},
    {{.n = 160, .dim = 2, .radius = 0.3, .anchor_radius = 0.45, .sigma = 0.05, .seed = 11}, "async-exact"},
    {{.n = 80, .dim = 3, .radius = 0.55, .anchor_radius = 0.75, .sigma = 0.05, .seed = 12}, "async"},
    {{.n = 80, .dim = 3, .radius = 0.55, .anchor_radius = 0.75, .sigma = 0.05, .seed = 12}, "async-exact"},
};

}  // namespace

TEST(AsyncFree, ReachesTheRelaxationOptimum) {
  const NetSpec* last = nullptr;
  double fstar = 0;
  for (const Case& c : kCases) {
    const Network w = merged(make_network(c.spec));
    if (!last || last->n != c.spec.n || last->dim != c.spec.dim) fstar = relaxation_optimum(w);
    last = &c.spec;
    const auto o = solve_outcome(MPI_COMM_WORLD, w, free_options(c.alg));
    const std::string what = std::string(c.alg) + " --mode free, dim " + std::to_string(c.spec.dim) + ", " +
                             std::to_string(world_size()) + " ranks";
    // Stopped by the tolerance (its own estimate, confirmed by the Solver's exact test), not by --max-iter.
    EXPECT_TRUE(o.s.converged) << what << ": " << o.s.message;
    EXPECT_LT(o.s.iterations, 300000) << what;
    EXPECT_NEAR(o.s.costs.relaxed, fstar, 1e-6 * fstar) << what << " (relaxation: " << fstar << ")";
    // More than one rank: boundary rows went between them.
    if (world_size() > 1) EXPECT_GT(o.s.mpi_bytes, 0) << what;
    if (world_rank() == 0)
      std::printf("%s: f_hat %.12g (relaxation %.12g), %lld iterations, %.2f s\n", what.c_str(), o.s.costs.relaxed,
                  fstar, static_cast<long long>(o.s.iterations), o.s.wall_seconds);
  }
}

// --max-iter K: every rank does K n_own activations (no tolerance): K iterations reported, no convergence.
TEST(AsyncFree, MaxIterCountsEpochsPerRank) {
  const Network w = merged(make_network({.n = 90, .dim = 2, .radius = 0.3, .anchor_radius = 0.4, .sigma = 0.05}));
  SolverOptions opt = free_options("async");
  opt.tol = 0;
  opt.max_iter = 37;
  const auto o = solve_outcome(MPI_COMM_WORLD, w, opt);
  EXPECT_EQ(o.s.iterations, 37);
  EXPECT_EQ(o.s.termination, TerminationType::kNoConvergence) << o.s.message;
  // The positions moved from the start (the activations ran) and are finite.
  for (double v : o.x) ASSERT_TRUE(std::isfinite(v));
  EXPECT_LT(o.s.costs.relaxed, o.s.initial_cost);
}

namespace {
// Stops the run at its first record at or after iteration `at` (a checkpoint was written before).
struct StopAt : IterationCallback {
  std::int64_t at;
  explicit StopAt(std::int64_t a) : at(a) {}
  CallbackReturn operator()(const IterationSummary& s) override {
    return s.total_iteration >= at ? CallbackReturn::kAbort : CallbackReturn::kContinue;
  }
};
}  // namespace

// A free run checkpointed at iteration 300 and stopped at 600; restarted from
// the checkpoint (every rank's state written after the ranks agreed to stop
// and drained their messages), it goes on to the relaxation's optimum.
TEST(AsyncFree, RestartFromACheckpointReachesTheOptimum) {
  const Network w = merged(make_network(kCases[0].spec));
  const double fstar = relaxation_optimum(w);
  const std::string path =
      std::string(SNL_BINARY_DIR) + "/async_free_ckpt_np" + std::to_string(world_size()) + ".h5";
  SolverOptions opt = free_options("async");
  opt.history_every = 600;
  CheckpointConfig ck;
  ck.path = path;
  ck.every = 300;
  ck.network_fingerprint = "test";
  Summary first;
  {
    LocalizationProblem prob(MPI_COMM_WORLD, snl::test::slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
    Solver solver(prob, opt);
    solver.set_checkpointing(ck);
    StopAt stop(600);
    solver.add_callback(&stop);
    first = solver.solve(random_initial_positions(prob, 3), nullptr);
  }
  ASSERT_EQ(first.termination, TerminationType::kUserAbort) << first.message;
  EXPECT_EQ(first.iterations, 600);
  EXPECT_GT(std::fabs(first.costs.relaxed - fstar), 1e-6 * fstar) << "stopped too late to test the restart";
  // Restart on the same ranks (with a different rank count it works the same: the state is per node).
  CheckpointConfig rs;
  rs.restart = path;
  rs.network_fingerprint = "test";
  LocalizationProblem prob(MPI_COMM_WORLD, snl::test::slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  Solver solver(prob, opt);
  solver.set_checkpointing(rs);
  const Summary s = solver.solve(random_initial_positions(prob, 99), nullptr);
  EXPECT_TRUE(s.converged) << s.message;
  EXPECT_GT(s.iterations, 300);
  // Resumed (not restarted from the random start): the first record is the checkpoint's history.
  ASSERT_FALSE(s.history.empty());
  EXPECT_EQ(s.history.front().total_iteration, 0);
  EXPECT_EQ(s.history.back().total_iteration, s.iterations);
  EXPECT_NEAR(s.costs.relaxed, fstar, 1e-6 * fstar);
  MPI_Barrier(MPI_COMM_WORLD);
  if (world_rank() == 0) std::remove(path.c_str());
}

// The options free mode cannot honour are refused through the registry.
TEST(AsyncFree, ModeIsRefusedWhereNotHonoured) {
  SolverOptions opt;
  opt.algorithm = "relaxation";
  opt.mode = "free";
  EXPECT_NE(opt.validate().find("--mode is not honoured by --algorithm relaxation (only by async, async-exact)"),
            std::string::npos)
      << opt.validate();
  opt.algorithm = "async";
  EXPECT_EQ(opt.validate(), "");
  opt.mode = "fast";
  EXPECT_NE(opt.validate().find("unknown --mode 'fast'"), std::string::npos) << opt.validate();
  opt.mode = "free";
  opt.straggler_delay = -1;
  EXPECT_NE(opt.validate().find("--straggler-delay"), std::string::npos);
}
