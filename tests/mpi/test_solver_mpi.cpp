// The solver driver (src/solvers/solver.cpp): bit-identical positions of every
// algorithm for 1, 2 and 3 ranks (sub-communicators of this run), metis, bfs,
// parmetis and block partitions, SIMD and scalar kernels; the stopping rule and history;
// option validation.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <cstring>

#include "kernels/kernels.hpp"
#include "snl/problem/generate.hpp"
#include "solve_helpers.hpp"

using namespace snl;
using snl::test::allgather_positions;
using snl::test::make_network;
using snl::test::merged;
using snl::test::NetSpec;
using snl::test::run;
using snl::test::slab_of;
using snl::test::world_rank;
using snl::test::world_size;

TEST(Determinism, BitIdenticalForOneTwoThreeRanks) {
  const Network w = make_network({.n = 120, .dim = 2, .radius = 0.2, .anchor_radius = 0.3, .sigma = 0.05});
  for (const char* alg : {"relaxation", "mm", "mm-accel", "ml-agd", "dv-pipeline", "bb", "bb-calafiore", "pipeline",
                          "pm", "async", "async-exact", "esdp-dist"}) {
    for (PartitionMethod pm : {PartitionMethod::kMetis, PartitionMethod::kBfs, PartitionMethod::kBlock}) {
      const auto ref = run(MPI_COMM_SELF, w, alg, 40, pm);
      {  // the portable scalar kernels give the same bits as the SIMD ones
        const bool had = detail::set_simd_enabled(false);
        const auto scalar = run(MPI_COMM_SELF, w, alg, 40, pm);
        detail::set_simd_enabled(had);
        EXPECT_EQ(0, std::memcmp(scalar.data(), ref.data(), ref.size() * sizeof(double)))
            << alg << ": scalar kernels differ from SIMD";
      }
      for (int k = 2; k <= world_size(); ++k) {
        MPI_Comm sub;
        MPI_Comm_split(MPI_COMM_WORLD, world_rank() < k ? 0 : MPI_UNDEFINED, world_rank(), &sub);
        if (sub == MPI_COMM_NULL) continue;
        const auto x = run(sub, w, alg, 40, pm);
        ASSERT_EQ(x.size(), ref.size());
        EXPECT_EQ(0, std::memcmp(x.data(), ref.data(), x.size() * sizeof(double)))
            << alg << " differs on " << k << " ranks";
        MPI_Comm_free(&sub);
      }
    }
  }
}

// The ParMETIS partition (PT-Scotch's, which may differ between runs) gives
// the same bits as METIS on one rank: the iterates do not depend on the partition.
TEST(Determinism, ParMetisPartitionGivesMetisBits) {
  if (!parmetis_available()) GTEST_SKIP() << "built without PT-Scotch's ParMETIS interface";
  const Network w = make_network({.n = 120, .dim = 2, .radius = 0.2, .anchor_radius = 0.3, .sigma = 0.05});
  const std::vector<std::string> algs = {"pipeline", "mm", "async-exact"};
  std::vector<std::vector<double>> ref;
  for (const auto& alg : algs) ref.push_back(run(MPI_COMM_SELF, w, alg, 40, PartitionMethod::kMetis));
  for (int k = 2; k <= world_size(); ++k) {
    MPI_Comm sub;
    MPI_Comm_split(MPI_COMM_WORLD, world_rank() < k ? 0 : MPI_UNDEFINED, world_rank(), &sub);
    if (sub == MPI_COMM_NULL) continue;
    ProblemReport rep;  // one partition per rank count (PT-Scotch is the slow part)
    LocalizationProblem prob(sub, slab_of(w, sub), PartitionMethod::kParMetis, &rep);
    EXPECT_EQ(rep.partition.method, "parmetis") << rep.partition.note;
    for (std::size_t a = 0; a < algs.size(); ++a) {
      SolverOptions opt;
      opt.algorithm = algs[a];
      opt.max_iter = 40;
      opt.tol = 0;
      opt.history_every = 1000000;
      Solver solver(prob, opt);
      std::vector<double> x;
      solver.solve(random_initial_positions(prob, 3), &x);
      const auto xg = allgather_positions(prob, x);
      ASSERT_EQ(xg.size(), ref[a].size());
      EXPECT_EQ(0, std::memcmp(xg.data(), ref[a].data(), xg.size() * sizeof(double)))
          << algs[a] << " with parmetis on " << k << " ranks differs from metis on one";
    }
    MPI_Comm_free(&sub);
  }
}

TEST(Solver, StopsOnRelativeImprovementAndRecordsHistory) {
  const Network w = make_network({.n = 50, .dim = 2, .radius = 0.3, .anchor_radius = 0.3, .sigma = 0.01});
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  SolverOptions opt;
  opt.algorithm = "pipeline";
  opt.max_iter = 100000;
  opt.stop = "papers";  // the relative-improvement rule, tested here
  opt.refine = "mm";
  opt.tol = 1e-6;
  opt.history_every = 1;  // every iteration's rel_change on record
  Solver solver(prob, opt);
  const Summary s = solver.solve(random_initial_positions(prob, 1), nullptr);
  EXPECT_EQ(s.termination, TerminationType::kConvergence);
  ASSERT_GE(s.history.size(), 3u);
  // Each phase stops at its first iteration with rel_change <= tol, well
  // before max_iter; the phases' iterations add up to the total.
  std::int64_t total = 0, missed = 0;
  for (std::size_t t = 0; t < s.history.size(); ++t) {
    const IterationSummary& h = s.history[t];
    if (h.iteration == 0) continue;  // a phase's starting point (rel_change NaN)
    if (t + 1 == s.history.size() || s.history[t + 1].iteration == 0) {
      EXPECT_LE(h.rel_change, *opt.tol) << h.phase;
      EXPECT_LT(h.iteration, opt.max_iter) << h.phase;
      total += h.iteration;
    } else {
      missed += h.rel_change <= *opt.tol;  // the phase should have stopped here
    }
  }
  EXPECT_EQ(missed, 0) << "iterations that met the stopping rule without stopping";
  EXPECT_EQ(s.iterations, total);
  EXPECT_EQ(s.history.front().phase, "relaxation");
  EXPECT_EQ(s.history.back().phase, "mm");
  for (std::size_t t = 1; t < s.history.size(); ++t) EXPECT_GE(s.history[t].reals, s.history[t - 1].reals);
  EXPECT_DOUBLE_EQ(s.reals_per_sensor, 2.0 * s.iterations);
  // MM refines the relaxation: the ML cost does not go up in the MM phase.
  double ml_relax = 0;
  for (const auto& h : s.history)
    if (h.phase == "relaxation") ml_relax = h.ml_cost;
  EXPECT_LE(s.costs.ml, ml_relax * (1 + 1e-12));
  EXPECT_TRUE(s.errors.valid);
  EXPECT_LT(s.errors.rmse, 0.05);
}

// From 10,000 sensors (the smallest such network here) the automatic
// gradient-test interval grows with the
// iterations k done, 50 floor(sqrt(2 T k) / 50) with T = 7 for the relaxation,
// and the automatic records fall on every second test: the history's rows
// show the schedule. An explicit --test-every keeps it fixed.
TEST(Solver, LargeNetworksSpaceTheirTestsAsTheSquareRootOfTheIterations) {
  GenerateOptions g;
  g.sensors = 10000;
  g.avg_degree = 6;
  const Network whole = generate_network(g);
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(whole, MPI_COMM_WORLD), PartitionMethod::kBfs, nullptr);
  std::int64_t tests = 0;
  auto records = [&](std::int64_t test_every) {
    SolverOptions opt;
    opt.algorithm = "relaxation";
    opt.max_iter = 1100;
    opt.tol = 1e-12;  // tested, never met
    opt.test_every = test_every;
    Solver solver(prob, opt);
    std::vector<std::int64_t> its;
    const Summary s = solver.solve(random_initial_positions(prob, 3), nullptr);
    for (const auto& h : s.history) its.push_back(h.iteration);
    tests = s.gradient_tests;
    return its;
  };
  std::vector<std::int64_t> grown, fixed;
  for (std::int64_t k = 0; k <= 1100; k += 50) {
    const std::int64_t interval = std::max<std::int64_t>(50, 50 * std::int64_t(std::sqrt(14.0 * double(k)) / 50));
    if (k % (2 * interval) == 0 || k == 1100) grown.push_back(k);
    if (k % 100 == 0 || k == 1100) fixed.push_back(k);
  }
  // 100 apart up to 800; 200 apart from there (the interval is 100 from k = 715).
  ASSERT_EQ(grown, (std::vector<std::int64_t>{0, 100, 200, 300, 400, 500, 600, 700, 800, 1000, 1100}));
  EXPECT_EQ(records(0), grown);
  EXPECT_EQ(tests, 14 + 4);  // 50, 100, ..., 700; 800, 900, 1000, 1100
  EXPECT_EQ(records(50), fixed);
  EXPECT_EQ(tests, 22);
}

// A network scaled to 1e155 (a node's |x|^2 overflows to +inf) stops with a
// failure at the same iteration on any number of ranks: the per-pass check
// (records are rare here) reads the methods' own sums, not decisive there,
// and every rank then forms the exact ones.
TEST(Solver, OverflowStopsEveryRankAtTheSameIteration) {
  Network w = make_network({.n = 120, .dim = 2, .radius = 0.2, .anchor_radius = 0.3, .sigma = 0.05});
  for (auto* v : {&w.sensor_ranges, &w.anchor_ranges, &w.anchors, &w.truth})
    for (auto& r : *v) r *= 1e155;
  for (const char* alg : {"relaxation", "mm", "mm-accel"}) {
    std::int64_t first = -1;
    for (int k = 1; k <= world_size(); ++k) {
      MPI_Comm sub;
      MPI_Comm_split(MPI_COMM_WORLD, world_rank() < k ? 0 : MPI_UNDEFINED, world_rank(), &sub);
      if (sub == MPI_COMM_NULL) continue;
      SolverOptions opt;
      opt.algorithm = alg;
      opt.max_iter = 200;
      opt.history_every = 1000;  // no record, so no exact sums, before max_iter
      const snl::test::Outcome o = snl::test::solve_outcome(sub, w, opt);
      EXPECT_EQ(o.s.termination, TerminationType::kFailure) << alg << " on " << k << " ranks: " << o.s.message;
      EXPECT_EQ(o.s.message, "non-finite iterate") << alg;
      EXPECT_LT(o.s.iterations, opt.max_iter) << alg;
      if (first < 0) first = o.s.iterations;
      EXPECT_EQ(o.s.iterations, first) << alg << " on " << k << " ranks";
      MPI_Comm_free(&sub);
    }
  }
}

TEST(Solver, RejectsBadOptions) {
  SolverOptions o;
  o.algorithm = "nope";
  EXPECT_NE(o.validate(), "");
  o.algorithm = "mm";
  o.tol = -1;
  EXPECT_NE(o.validate(), "");
  o.tol = 0;
  o.max_iter = -5;
  EXPECT_NE(o.validate(), "");
}

// The phases share the problem's lane layout (detail::shared_lanes), which
// holds the ranges: after resample_ranges a solve on the same problem equals
// one on a fresh problem with the same ranges, bit for bit, and the layout is
// one object across phases.
TEST(SharedLanes, OneLayoutPerProblemRebuiltWhenTheRangesChange) {
  const Network w = make_network({.n = 120, .dim = 2, .radius = 0.3, .anchor_radius = 0.35, .sigma = 0.01, .seed = 7});
  SolverOptions opt;
  opt.algorithm = "pipeline";
  opt.refine = "mm-accel";
  opt.max_iter = 40;
  opt.tol = 0;
  opt.history_every = 1000000;
  auto solve = [&](LocalizationProblem& prob) {
    Solver s(prob, opt);
    std::vector<double> x;
    s.solve(random_initial_positions(prob, 3), &x);
    return allgather_positions(prob, x);
  };
  LocalizationProblem reused(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  solve(reused);  // lays out the file's ranges
  const auto first = detail::shared_lanes(reused);
  EXPECT_EQ(first.get(), detail::shared_lanes(reused).get());
  reused.resample_ranges(0.05, 11);
  EXPECT_NE(first.get(), detail::shared_lanes(reused).get());
  LocalizationProblem fresh(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  fresh.resample_ranges(0.05, 11);
  const auto a = solve(reused), b = solve(fresh);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(double)));
}
