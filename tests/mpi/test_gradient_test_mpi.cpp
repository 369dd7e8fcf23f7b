// The gradient stopping test on plain sums (src/solvers/gradient_test.cpp):
// its interval holds the relative gradient the exact test forms and is
// tight; a solve that settles every test it can on the bounds takes the same
// stops, so the same bits, as one that sums every test exactly; a record at
// a test's iteration keeps the cost the test formed, which is the objective.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "core/exact_sum.hpp"
#include "kernels/kernels.hpp"
#include "snl/problem/metrics.hpp"
#include "solve_helpers.hpp"
#include "solvers/gradient_test.hpp"
#include "solvers/lane_costs.hpp"

using namespace snl;
using snl::test::make_network;
using snl::test::slab_of;

namespace {

// The Solver's exact test (Solver::Run::relative_gradient) at local rows x.
double exact_relative_gradient(const LocalizationProblem& prob, const double* x, bool relaxed) {
  const int p = prob.dim();
  std::vector<double> g(std::size_t(prob.num_owned()) * p);
  const double f = ml_cost_and_gradient(prob, x, g.data(), relaxed);
  detail::ExactSum s;
  for (LocalId v = 0; v < prob.num_owned(); ++v) {
    double t = 0;
    for (int c = 0; c < p; ++c) t += g[std::size_t(v) * p + c] * g[std::size_t(v) * p + c];
    s.add(t);
  }
  detail::allreduce_exact(&s, 1, prob.comm());
  const double gn = std::sqrt(s.value());
  return f > 0 ? gn / (2.0 * std::sqrt(f)) : gn;
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

struct SolveRun {
  Summary s;
  std::vector<double> x;
};

SolveRun solve(const Network& w, const std::string& alg, const char* tests, double tol = -1, int max_iter = 3000,
               int history_every = 0, int test_every = 0) {
  if (tests) setenv("SNL_TEST_GRADIENT_TEST", tests, 1);
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  SolverOptions opt;
  opt.algorithm = alg;
  opt.max_iter = max_iter;
  if (tol >= 0) opt.tol = tol;
  opt.history_every = history_every;
  opt.test_every = test_every;
  Solver solver(prob, opt);
  SolveRun r;
  std::vector<double> x;
  r.s = solver.solve(random_initial_positions(prob, 3), &x);
  r.x = snl::test::allgather_positions(prob, x);
  unsetenv("SNL_TEST_GRADIENT_TEST");
  return r;
}

}  // namespace

// At random starts, near the truth and at a solution, 2D and 3D, noise-free
// to noisy, for f_hat's gradient and f's: lo <= exact <= hi, and hi - lo
// within 1e-9 of it (so the bounds settle every test not that close to tol).
TEST(GradientTest, BoundsHoldTheExactRelativeGradient) {
  int cases = 0;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    const double sigmas[] = {0.0, 0.01, 0.05};
    const int dim = seed % 3 == 0 ? 3 : 2;
    const Network w = make_network({.n = GlobalId(150 + 40 * seed), .dim = dim, .radius = dim == 3 ? 0.4 : 0.25,
                                    .anchor_radius = 0.3, .sigma = sigmas[seed % 3], .seed = seed});
    LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
    const int p = prob.dim();
    const auto lanes = detail::shared_lanes(prob);
    std::vector<double> start = random_initial_positions(prob, seed), solved;
    {
      SolverOptions opt;
      opt.algorithm = "dv-pipeline";
      opt.max_iter = 400;
      Solver(prob, opt).solve(start, &solved);
    }
    std::vector<double> near(std::size_t(prob.num_owned()) * p);
    for (std::size_t i = 0; i < near.size(); ++i) near[i] = prob.truth()[i] + 1e-3 * std::sin(double(i) + seed);
    for (const auto* rows : {&start, &near, &solved}) {
      std::vector<double> x(std::size_t(prob.num_local()) * p), scratch(std::size_t(prob.num_owned()) * p);
      std::copy(rows->begin(), rows->begin() + std::ptrdiff_t(prob.num_owned()) * p, x.begin());
      prob.graph().halo().exchange(x.data(), p);
      for (bool relaxed : {true, false}) {
        const double exact = exact_relative_gradient(prob, x.data(), relaxed);
        const detail::GradientBounds b = detail::bound_relative_gradient(prob, *lanes, x.data(), relaxed, scratch.data());
        ASSERT_TRUE(b.valid) << "seed " << seed;
        EXPECT_LE(b.lo, exact) << "seed " << seed << " relaxed " << relaxed;
        EXPECT_GE(b.hi, exact) << "seed " << seed << " relaxed " << relaxed;
        EXPECT_LE(b.hi - b.lo, 1e-9 * exact) << "seed " << seed << " relaxed " << relaxed;
        ++cases;
      }
    }
  }
  EXPECT_EQ(cases, 36);
}

// The exact costs and the exact test from the lane layout (lane_costs.hpp,
// what the Solver and the relaxation run once a phase built the layout)
// against metrics.cpp's scalar passes: the same f, f_hat, certificate and
// a-priori bound, and the same gradient, bit for bit; 2D and 3D, at random
// starts, near the truth and with sensors on top of each other (|z| = 0).
TEST(LaneCosts, AreTheScalarPassesBits) {
  int cases = 0;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    const int dim = seed % 3 == 0 ? 3 : 2;
    const Network w = make_network({.n = GlobalId(150 + 40 * seed), .dim = dim, .radius = dim == 3 ? 0.4 : 0.25,
                                    .anchor_radius = 0.3, .sigma = 0.01 * double(seed % 3), .seed = seed});
    LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
    const int p = prob.dim();
    const std::size_t n = std::size_t(prob.num_owned()) * p;
    std::vector<double> start = random_initial_positions(prob, seed), near(n), stacked(n);
    for (std::size_t i = 0; i < n; ++i) {
      near[i] = prob.truth()[i] + 1e-3 * std::sin(double(i) + seed);
      stacked[i] = std::floor(4.0 * prob.truth()[i]) / 4.0;  // many sensors on one point
    }
    ASSERT_FALSE(detail::lane_costs_apply(prob));  // no layout yet: the scalar passes
    detail::shared_lanes(prob);
    ASSERT_TRUE(detail::lane_costs_apply(prob));
    for (const auto* rows : {&start, &near, &stacked}) {
      std::vector<double> x(std::size_t(prob.num_local()) * p);
      std::copy(rows->begin(), rows->begin() + std::ptrdiff_t(n), x.begin());
      prob.graph().halo().exchange(x.data(), p);
      const CostTerms all = evaluate_costs(prob, x.data()), lane = detail::exact_costs(prob, x.data(), detail::kAllSums);
      EXPECT_TRUE(same_bits(all.ml, lane.ml)) << "seed " << seed;
      EXPECT_TRUE(same_bits(all.relaxed, lane.relaxed)) << "seed " << seed;
      EXPECT_TRUE(same_bits(all.certificate, lane.certificate)) << "seed " << seed;
      EXPECT_TRUE(same_bits(all.apriori, lane.apriori)) << "seed " << seed;
      EXPECT_TRUE(same_bits(all.ml, detail::exact_costs(prob, x.data(), detail::kMlSum).ml)) << "seed " << seed;
      EXPECT_TRUE(same_bits(all.relaxed, detail::exact_costs(prob, x.data(), detail::kRelaxedSum).relaxed));
      for (bool relaxed : {true, false}) {
        std::vector<double> gs(n), gl(n);
        const double fs = ml_cost_and_gradient(prob, x.data(), gs.data(), relaxed);
        const double fl = detail::exact_ml_cost_and_gradient(prob, x.data(), gl.data(), relaxed);
        EXPECT_TRUE(same_bits(fs, fl)) << "seed " << seed << " relaxed " << relaxed << ": " << fs << " " << fl;
        EXPECT_EQ(0, std::memcmp(gs.data(), gl.data(), n * sizeof(double))) << "seed " << seed << " relaxed " << relaxed;
      }
      ++cases;
    }
  }
  EXPECT_EQ(cases, 18);
}

// Every test on the bounds where they settle it (SNL_TEST_GRADIENT_TEST=
// bounded) against every test on exact sums: the same stops, iterates and
// records, for the default pipeline and for methods that stop on f_hat's
// gradient (relaxation) and on f's (ml-agd), tests at the automatic
// intervals and at every iteration.
TEST(GradientTest, BoundedTestsStopWhereTheExactOnesDo) {
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    const int dim = seed % 3 == 0 ? 3 : 2;
    const Network w = make_network({.n = GlobalId(100 + 20 * seed), .dim = dim, .radius = dim == 3 ? 0.45 : 0.3,
                                    .anchor_radius = 0.3, .sigma = seed % 2 ? 0.01 : 0.03, .seed = seed});
    for (const char* alg : {"dv-pipeline", "relaxation", "ml-agd"}) {
      // Tests every iteration too: the stopping test then sees a relative
      // gradient just below tol, where a loose bound would decide wrongly.
      const int every = seed % 2 ? 1 : 0;
      const SolveRun bounded = solve(w, alg, "bounded", -1, 3000, 10, every);
      const SolveRun exact = solve(w, alg, "exact", -1, 3000, 10, every);
      const std::string what = std::string(alg) + " seed " + std::to_string(seed) + " test every " + std::to_string(every);
      // Every test but a stop is settled on the bounds (they are within 1e-9
      // of each other); a stop always takes the exact sums.
      EXPECT_GT(bounded.s.gradient_tests_bounded, 0) << what;
      EXPECT_EQ(bounded.s.gradient_tests_bounded,
                bounded.s.gradient_tests - (bounded.s.termination == TerminationType::kConvergence ? 1 : 0))
          << what;
      EXPECT_EQ(exact.s.gradient_tests_bounded, 0) << what;
      EXPECT_EQ(bounded.s.gradient_tests, exact.s.gradient_tests) << what;
      EXPECT_EQ(bounded.s.iterations, exact.s.iterations) << what;
      EXPECT_EQ(bounded.s.message, exact.s.message) << what;
      ASSERT_EQ(bounded.x.size(), exact.x.size());
      EXPECT_EQ(0, std::memcmp(bounded.x.data(), exact.x.data(), bounded.x.size() * sizeof(double))) << what;
      ASSERT_EQ(bounded.s.history.size(), exact.s.history.size()) << what;
      for (std::size_t t = 0; t < exact.s.history.size(); ++t) {
        EXPECT_TRUE(same_bits(bounded.s.history[t].cost, exact.s.history[t].cost)) << what << " record " << t;
        EXPECT_TRUE(same_bits(bounded.s.history[t].grad_norm, exact.s.history[t].grad_norm)) << what << " record " << t;
      }
    }
  }
}

// ml-agd's records at its tests take f from the test: the same bits as the
// objective evaluated where no test runs (tol 0, the same iterates).
TEST(GradientTest, RecordsKeepTheTestsCost) {
  for (std::uint64_t seed = 11; seed <= 13; ++seed) {
    const Network w = make_network({.n = GlobalId(200 + 20 * seed), .dim = 2, .radius = 0.25, .anchor_radius = 0.3,
                                    .sigma = 0.01, .seed = seed});
    // Records every third iteration, tests every tenth: some records fall on
    // a test (f reused), the others between tests (f evaluated).
    const SolveRun tested = solve(w, "ml-agd", "exact", -1, 3000, 3);
    ASSERT_GT(tested.s.gradient_tests, 0);
    const SolveRun untested = solve(w, "ml-agd", nullptr, 0.0, int(tested.s.iterations), 3);
    ASSERT_EQ(untested.s.gradient_tests, 0);
    ASSERT_EQ(tested.s.history.size(), untested.s.history.size()) << "seed " << seed;
    for (std::size_t t = 0; t < tested.s.history.size(); ++t) {
      ASSERT_EQ(tested.s.history[t].iteration, untested.s.history[t].iteration);
      EXPECT_EQ(tested.s.history[t].cost, untested.s.history[t].cost) << "seed " << seed << " record " << t;
      EXPECT_EQ(tested.s.history[t].cost, tested.s.history[t].ml_cost) << "seed " << seed << " record " << t;
    }
  }
}
