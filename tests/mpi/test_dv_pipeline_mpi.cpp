// dv-pipeline, the default of snl solve (registry.cpp): its distance-vector
// start (dv_start.hpp) against the serial reference twin (Dijkstra from every
// anchor, the same calibration and multilateration written independently),
// ml-agd (relaxation.cpp) against its twin, the same bits on 1, 2 and 3 ranks,
// and the whole pipeline never ending above the papers' pipeline.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cstdlib>
#include <cstring>

#include "reference/reference.hpp"
#include "snl/io/network.hpp"
#include "snl/problem/generate.hpp"
#include "snl/solvers/dv_start.hpp"
#include "solve_helpers.hpp"

using namespace snl;
using snl::test::make_network;
using snl::test::merged;
using snl::test::slab_of;
using snl::test::world_rank;
using snl::test::world_size;

namespace {

// A network whose anchors sit in one corner region, so that paths run many hops.
Network far_anchor_network(int dim, std::uint64_t seed, double sigma) {
  return make_network({.n = GlobalId(dim == 3 ? 150 : 120), .dim = dim, .radius = dim == 3 ? 0.35 : 0.22,
                       .anchor_radius = 0.3, .sigma = sigma, .seed = seed});
}

}  // namespace

TEST(DvStart, AnchorListsAreTheShortestPaths) {
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    const int dim = seed % 2 ? 2 : 3;
    const Network w = far_anchor_network(dim, seed, 0.02);
    const Network m = merged(w);
    LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
    const int k = dv_start_anchors(dim);
    const AnchorPaths paths = nearest_anchor_paths(prob, k);
    const auto ref = reference::nearest_anchor_paths(m, k);
    int entries = 0;
    for (LocalId v = 0; v < prob.num_owned(); ++v) {
      const auto& r = ref[prob.graph().global_id(v)];
      for (int t = 0; t < k; ++t) {
        const std::size_t i = std::size_t(v) * k + t;
        if (t >= int(r.size())) {
          EXPECT_EQ(paths.ids[i], -1) << "seed " << seed << " sensor " << prob.graph().global_id(v);
          continue;
        }
        ++entries;
        // The same sums along the same paths: equal, not merely close.
        EXPECT_EQ(paths.dist[i], r[t].first) << "seed " << seed << " sensor " << prob.graph().global_id(v);
        EXPECT_EQ(paths.ids[i], r[t].second) << "seed " << seed << " sensor " << prob.graph().global_id(v);
      }
    }
    EXPECT_GT(entries, 0);
    EXPECT_GT(paths.rounds, 3) << "the anchors should be several hops from most sensors";
  }
}

TEST(DvStart, PositionsMatchTheReference) {
  for (std::uint64_t seed = 11; seed <= 14; ++seed) {
    const int dim = seed % 2 ? 2 : 3;
    const Network w = far_anchor_network(dim, seed, 0.01);
    const Network m = merged(w);
    LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
    DvStartReport rep;
    const auto x = test::allgather_positions(prob, dv_initial_positions(prob, 5, &rep));
    const auto fallback = test::allgather_positions(prob, random_initial_positions(prob, 5));
    const auto xr = reference::dv_start(m, dv_start_anchors(dim), fallback);
    EXPECT_NEAR(rep.correction, reference::path_correction(m, reference::nearest_anchor_paths(m, dv_start_anchors(dim))),
                1e-12);
    ASSERT_EQ(x.size(), xr.size());
    for (std::size_t t = 0; t < x.size(); ++t) EXPECT_NEAR(x[t], xr[t], 1e-9) << "seed " << seed << " row " << t / dim;
    // A start, not a random point: within a few link radii of the truth on average.
    double e2 = 0;
    for (std::size_t t = 0; t < x.size(); ++t) e2 += (x[t] - w.truth[t]) * (x[t] - w.truth[t]);
    EXPECT_LT(std::sqrt(e2 / double(w.num_sensors)), 0.5) << "seed " << seed;
  }
}

// Sensors that no anchor path reaches (a component without anchor
// measurements) keep the random start, and the report counts them.
TEST(DvStart, UnreachedSensorsKeepTheRandomStart) {
  Network w = make_network({.n = 60, .dim = 2, .radius = 0.3, .anchor_radius = 0.3, .sigma = 0.01, .seed = 3});
  // Two extra sensors linked only to each other.
  const GlobalId a = w.num_sensors, b = w.num_sensors + 1;
  w.num_sensors += 2;
  w.sensor_edges.insert(w.sensor_edges.end(), {a, b});
  w.sensor_ranges.push_back(0.1);
  w.truth.insert(w.truth.end(), {0.5, 0.5, 0.6, 0.5});
  w.localizability.clear();
  w.total_sensor_edges = w.local_sensor_edges();
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  DvStartReport rep;
  const auto x = test::allgather_positions(prob, dv_initial_positions(prob, 9, &rep));
  const auto r = test::allgather_positions(prob, random_initial_positions(prob, 9));
  EXPECT_EQ(rep.without_anchor, 2);
  for (GlobalId s : {a, b})
    for (int c = 0; c < 2; ++c) EXPECT_EQ(x[s * 2 + c], r[s * 2 + c]);
  int moved = 0;
  for (GlobalId s = 0; s < a; ++s) moved += x[s * 2] != r[s * 2];
  EXPECT_EQ(moved, a);
}

TEST(DvStart, SameBitsOnOneTwoThreeRanks) {
  const Network w = far_anchor_network(2, 21, 0.02);
  std::vector<double> ref;
  {
    LocalizationProblem prob(MPI_COMM_SELF, slab_of(w, MPI_COMM_SELF), PartitionMethod::kMetis, nullptr);
    ref = test::allgather_positions(prob, dv_initial_positions(prob, 1, nullptr));
  }
  for (PartitionMethod pm : {PartitionMethod::kMetis, PartitionMethod::kBfs, PartitionMethod::kBlock})
    for (int k = 2; k <= world_size(); ++k) {
      MPI_Comm sub;
      MPI_Comm_split(MPI_COMM_WORLD, world_rank() < k ? 0 : MPI_UNDEFINED, world_rank(), &sub);
      if (sub == MPI_COMM_NULL) continue;
      LocalizationProblem prob(sub, slab_of(w, sub), pm, nullptr);
      const auto x = test::allgather_positions(prob, dv_initial_positions(prob, 1, nullptr));
      ASSERT_EQ(x.size(), ref.size());
      EXPECT_EQ(0, std::memcmp(x.data(), ref.data(), x.size() * sizeof(double))) << "differs on " << k << " ranks";
      MPI_Comm_free(&sub);
    }
}

TEST(MlAgd, MatchesTheReferenceTwin) {
  int restarted = 0;
  for (std::uint64_t seed = 31; seed <= 36; ++seed) {
    const int dim = seed % 3 == 0 ? 3 : 2;
    const Network w = make_network({.n = 80, .dim = dim, .radius = dim == 3 ? 0.45 : 0.3, .anchor_radius = 0.35,
                                    .sigma = 0.05, .seed = seed});
    SolverOptions opt;
    opt.algorithm = "ml-agd";
    opt.max_iter = 80;
    opt.tol = 0;
    opt.history_every = 1000000;
    const test::Outcome o = test::solve_outcome(MPI_COMM_WORLD, w, opt);
    LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
    const auto x0 = test::allgather_positions(prob, random_initial_positions(prob, 3));
    const auto xr = reference::ml_agd(merged(w), x0, 80);
    ASSERT_EQ(o.x.size(), xr.size());
    for (std::size_t t = 0; t < xr.size(); ++t) EXPECT_NEAR(o.x[t], xr[t], 1e-9) << "seed " << seed << " " << t;
    restarted += test::method_value(o.s, "restarts") > 0;
    // The restart test's plain sums with their rounding bound decide as the exact sum does.
    setenv("SNL_TEST_EXACT_RESTART", "1", 1);
    const test::Outcome exact = test::solve_outcome(MPI_COMM_WORLD, w, opt);
    unsetenv("SNL_TEST_EXACT_RESTART");
    ASSERT_EQ(exact.x.size(), o.x.size());
    EXPECT_EQ(0, std::memcmp(exact.x.data(), o.x.data(), o.x.size() * sizeof(double))) << "seed " << seed;
    // Lower than the start.
    EXPECT_LT(reference::ml_cost(merged(w), o.x), reference::ml_cost(merged(w), x0)) << "seed " << seed;
  }
  EXPECT_GT(restarted, 0) << "no run restarted its momentum: the restart path went untested";
}

TEST(MlAgd, RefusesAMeasurementModel) {
  const Network w = make_network({.n = 40, .dim = 2, .radius = 0.3, .anchor_radius = 0.35, .sigma = 0.01});
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  SolverOptions opt;
  opt.algorithm = "ml-agd";
  opt.loss = "huber:0.01";
  EXPECT_NE(opt.validate(), "");
}

namespace {

// Final ML cost of dv-pipeline (its own start) and of the papers' pipeline
// (relaxation then plain MM from the random start, 003's stopping rule).
std::pair<double, double> both_costs(const Network& w, const std::string& weights = "auto") {
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  SolverOptions dv;
  dv.weights = weights;
  dv.history_every = 1000000;
  SolverOptions papers = dv;
  papers.algorithm = "pipeline";
  papers.refine = "mm";
  papers.stop = "papers";
  std::vector<double> x;
  Solver s1(prob, dv);
  const Summary a = s1.solve(dv_initial_positions(prob, 1, nullptr), &x);
  Solver s2(prob, papers);
  const Summary b = s2.solve(random_initial_positions(prob, 1), &x);
  return {a.costs.ml, b.costs.ml};
}

}  // namespace

// Generated default networks (2D and 3D) and the two standard benchmarks:
// dv-pipeline never ends above the papers' pipeline.
TEST(DvPipeline, NeverAboveThePapersPipeline) {
  for (std::uint64_t seed : {1, 2, 3}) {
    for (int dim : {2, 3}) {
      GenerateOptions g;
      g.sensors = dim == 2 ? 1500 : 800;
      g.dim = dim;
      g.seed = seed;
      g.localizable = GenerateOptions::Localizable::kNo;
      const auto [dv, papers] = both_costs(generate_network(g));
      EXPECT_LE(dv, papers * (1 + 1e-9)) << "seed " << seed << " dim " << dim;
    }
  }
  for (const char* f : {"test10-500.h5", "test20-1000.h5"})
    for (const char* weights : {"none", "multiplicative:0.1"}) {
      const Network w = read_network(std::string(SNL_SOURCE_DIR) + "/inputs/benchmarks/" + f, MPI_COMM_SELF);
      const auto [dv, papers] = both_costs(w, weights);
      EXPECT_LE(dv, papers * (1 + 1e-9)) << f << " --weights " << weights;
    }
}

// On large networks dv-pipeline runs its smoothing relaxation in passes of
// several iterations (temporal blocking, solver.cpp: phase_block; forced here
// on a small one by SNL_TEST_SMOOTH_BLOCK): its phases must still end on the
// bits of the three methods run one after the other from the same start, one
// iteration per pass.
TEST(DvPipeline, SameBitsAsItsPhasesRunOneByOne) {
  GenerateOptions g;
  g.sensors = 10000;
  g.seed = 4;
  g.localizable = GenerateOptions::Localizable::kNo;
  const Network w = generate_network(g);
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  ASSERT_GE(prob.num_sensors(), 10000);
  auto options = [](const char* alg, std::int64_t iters) {
    SolverOptions o;
    o.algorithm = alg;
    o.max_iter = iters;
    o.tol = 0;
    o.history_every = 1000000;
    return o;
  };
  const std::vector<double> x0 = dv_initial_positions(prob, 1, nullptr);
  std::vector<double> whole, x = x0;
  setenv("SNL_TEST_SMOOTH_BLOCK", "1", 1);
  Solver(prob, options("dv-pipeline", 60)).solve(x0, &whole);
  unsetenv("SNL_TEST_SMOOTH_BLOCK");
  // smoothing (--smooth-iter 200, capped at 60), settling (likewise), ml-agd
  for (const char* alg : {"relaxation", "mm-accel", "ml-agd"}) {
    std::vector<double> next;
    Solver(prob, options(alg, 60)).solve(x, &next);
    x = next;
  }
  const auto a = test::allgather_positions(prob, whole), b = test::allgather_positions(prob, x);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(double)));
  EXPECT_NE(0, std::memcmp(a.data(), test::allgather_positions(prob, x0).data(), a.size() * sizeof(double)));
}
