// The weighted / Huber measurement model (src/problem/weights.cpp,
// src/solvers/weighted.cpp and the model-aware metrics, PM, async, BB): the
// relaxation, MM, mm-accel, PM, async and BB against their serial reference twins, MM's objective never
// increasing, the gradients against finite differences, and bit-identical
// positions of every method on 1, 2 and 3 ranks.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <cstdio>
#include <cstring>

#include "reference/bb.hpp"
#include "reference/reference.hpp"
#include "snl/problem/metrics.hpp"
#include "solve_helpers.hpp"

using namespace snl;
using snl::test::allgather_positions;
using snl::test::make_network;
using snl::test::slab_of;
using snl::test::world_rank;
using snl::test::world_size;

namespace {

// A network with sigmas spread over a factor 4 (so weights over 16) and a few
// ranges pushed out by a bias (outliers, for the Huber loss).
Network weighted_network(int dim = 2) {
  Network w = make_network({.n = 60, .dim = dim, .radius = dim == 2 ? 0.3 : 0.5, .anchor_radius = 0.6, .sigma = 0.02});
  w.sensor_sigmas.resize(w.sensor_ranges.size());
  w.anchor_sigmas.resize(w.anchor_ranges.size());
  for (std::size_t e = 0; e < w.sensor_ranges.size(); ++e) {
    w.sensor_sigmas[e] = 0.01 * (1 + double(e % 4));
    if (e % 7 == 3) w.sensor_ranges[e] += 0.2;
  }
  for (std::size_t e = 0; e < w.anchor_ranges.size(); ++e) w.anchor_sigmas[e] = 0.01 * (1 + double(e % 3));
  return w;
}

// Positions after `iters` iterations of `alg` under --weights/--loss on comm.
std::vector<double> run_model(MPI_Comm comm, const Network& w, const std::string& alg, int iters,
                              const std::string& weights, const std::string& loss, double* lip = nullptr) {
  LocalizationProblem prob(comm, slab_of(w, comm), PartitionMethod::kMetis, nullptr);
  SolverOptions opt;
  opt.algorithm = alg;
  opt.max_iter = iters;
  opt.tol = 0;
  opt.history_every = 1000000;
  opt.weights = weights;
  opt.loss = loss;
  opt.check_monotone = alg == "mm" || alg == "mm-accel";
  Solver solver(prob, opt);
  std::vector<double> x;
  const Summary s = solver.solve(random_initial_positions(prob, 3), &x);
  if (lip) *lip = s.lipschitz;
  return allgather_positions(prob, x);
}

std::vector<double> start_positions(const Network& w) {
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  return allgather_positions(prob, random_initial_positions(prob, 3));
}

}  // namespace

namespace {

// PM, async, async-exact and BB on the model against their serial twins.
void expect_sequential_and_bb_match(const Network& w, const std::vector<double>& x0, const reference::Model& m,
                                    const std::string& loss) {
  const auto xp = run_model(MPI_COMM_WORLD, w, "pm", 20, "file", loss);
  const auto rp = reference::model_pm(w, m, x0, 20);
  for (std::size_t t = 0; t < xp.size(); ++t) ASSERT_NEAR(xp[t], rp[t], 1e-12) << loss << " pm " << t;
  for (bool exact : {false, true}) {
    // SolverOptions::seed (1 by default) keys the activation sequence; an iteration is n activations.
    const auto xa = run_model(MPI_COMM_WORLD, w, exact ? "async-exact" : "async", 6, "file", loss);
    const auto ra = reference::model_async(w, m, x0, 6 * w.num_sensors, 1, exact);
    // async-exact's inner solves stop on a step of 1e-12: sums in another
    // order can stop them an iteration apart (up to ~1e-10 under Huber).
    const double tol = exact ? 1e-9 : 1e-12;
    for (std::size_t t = 0; t < xa.size(); ++t)
      ASSERT_NEAR(xa[t], ra[t], tol) << loss << (exact ? " async-exact " : " async ") << t;
  }
  const auto xb = run_model(MPI_COMM_WORLD, w, "bb", 30, "file", loss);
  const auto rb = reference::model_bb(w, m, x0, 30, SolverOptions().bb_rounds);
  double moved = 0;
  for (std::size_t t = 0; t < xb.size(); ++t) {
    ASSERT_NEAR(xb[t], rb[t], 1e-12) << loss << " bb " << t;
    moved = std::max(moved, std::abs(xb[t] - x0[t]));
  }
  EXPECT_GT(moved, 1e-3) << loss;  // not two unmoved starts
}

}  // namespace

TEST(WeightedModel, EveryMethodMatchesItsSerialReference) {
  for (int dim : {2, 3}) {
    const Network w = weighted_network(dim);
    const auto x0 = start_positions(w);
    for (double delta : {0.0, 0.05}) {
      const std::string loss = delta > 0 ? "huber:0.05" : "l2";
      const reference::Model m = reference::model_from_sigmas(w, delta);
      const auto xr = run_model(MPI_COMM_WORLD, w, "relaxation", 60, "file", loss);
      const auto rr = reference::model_nesterov(w, m, x0, 60);
      for (std::size_t t = 0; t < xr.size(); ++t) ASSERT_NEAR(xr[t], rr[t], 1e-11) << loss << " relaxation " << t;
      std::vector<double> phi;
      const auto xm = run_model(MPI_COMM_WORLD, w, "mm", 60, "file", loss);
      const auto rm = reference::model_mm(w, m, x0, 60, &phi);
      for (std::size_t t = 0; t < xm.size(); ++t) ASSERT_NEAR(xm[t], rm[t], 1e-11) << loss << " mm " << t;
      for (std::size_t t = 1; t < phi.size(); ++t) EXPECT_LE(phi[t], phi[t - 1] * (1 + 1e-14)) << loss << " " << t;
      // mm-accel: the same step from the extrapolated point, with its
      // acceptance test; the twin's restarts show that the test was exercised.
      std::vector<double> ml;
      int restarts = 0;
      const auto xa = run_model(MPI_COMM_WORLD, w, "mm-accel", 300, "file", loss);
      const auto ra = reference::model_mm_accel(w, m, x0, 300, &ml, &restarts);
      for (std::size_t t = 0; t < xa.size(); ++t) ASSERT_NEAR(xa[t], ra[t], 1e-11) << loss << " mm-accel " << t;
      for (std::size_t t = 1; t < ml.size(); ++t) EXPECT_LE(ml[t], ml[t - 1]) << loss << " " << t;
      EXPECT_LT(ml[60], phi.back()) << loss << ": mm-accel ends above MM after as many iterations";
      std::printf("%s dim %d: mm-accel restarts %d in 300 iterations\n", loss.c_str(), dim, restarts);
      EXPECT_GT(restarts, 0) << loss;
      expect_sequential_and_bb_match(w, x0, m, loss);
    }
  }
}

TEST(WeightedModel, WeightsChangeTheIterates) {
  // --weights none on a file with sigmas is the unweighted method; file is not.
  const Network w = weighted_network();
  const auto a = run_model(MPI_COMM_WORLD, w, "mm", 30, "none", "l2");
  const auto b = run_model(MPI_COMM_WORLD, w, "mm", 30, "file", "l2");
  const auto c = run_model(MPI_COMM_WORLD, w, "mm", 30, "multiplicative:0.1", "l2");
  Network plain = w;
  plain.sensor_sigmas.clear();
  plain.anchor_sigmas.clear();
  const auto d = run_model(MPI_COMM_WORLD, plain, "mm", 30, "auto", "l2");
  EXPECT_EQ(0, std::memcmp(a.data(), d.data(), a.size() * sizeof(double)));
  EXPECT_NE(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(double)));
  EXPECT_NE(0, std::memcmp(b.data(), c.data(), a.size() * sizeof(double)));
}

TEST(WeightedModel, GradientsMatchFiniteDifferences) {
  const Network w = weighted_network();
  for (const char* loss : {"l2", "huber:0.05"}) {
    LocalizationProblem prob(MPI_COMM_SELF, w, PartitionMethod::kBlock, nullptr);
    prob.set_measurement_model(parse_weights_spec("file"), parse_loss_spec(loss));
    std::vector<double> x = random_initial_positions(prob, 5);
    for (auto& v : x) v = 0.5 + 0.3 * (v - 0.5);  // most ranges off, several beyond delta
    std::vector<double> gr(x.size()), gm(x.size());
    relaxed_gradient(prob, x.data(), gr.data(), 0, prob.num_owned());
    ml_gradient(prob, x.data(), gm.data(), 0, prob.num_owned());
    const double h = 1e-6;
    for (std::size_t t = 0; t < x.size(); t += 7) {
      std::vector<double> xp = x, xm = x;
      xp[t] += h;
      xm[t] -= h;
      const CostTerms cp = evaluate_costs(prob, xp.data()), cm = evaluate_costs(prob, xm.data());
      EXPECT_NEAR(gr[t], (cp.relaxed - cm.relaxed) / (2 * h), 1e-5) << loss << " relaxed " << t;
      EXPECT_NEAR(gm[t], (cp.ml - cm.ml) / (2 * h), 1e-5) << loss << " ml " << t;
    }
    // The costs are the reference's (the reference orders rows by the file, the problem by local id).
    const reference::Model m = reference::model_from_sigmas(w, parse_loss_spec(loss));
    const auto xg = allgather_positions(prob, x);
    const CostTerms c = evaluate_costs(prob, x.data());
    EXPECT_NEAR(c.ml, reference::model_ml_cost(w, m, xg), 1e-12 * c.ml);
    EXPECT_NEAR(c.relaxed, reference::model_relaxed_cost(w, m, xg), 1e-12 * c.relaxed);
  }
}

TEST(WeightedModel, BitIdenticalForOneTwoThreeRanks) {
  const Network w = weighted_network();
  for (const char* loss : {"l2", "huber:0.05"})
    for (const char* alg : {"relaxation", "mm", "mm-accel", "pipeline", "bb", "pm", "async", "async-exact"}) {
      const auto ref = run_model(MPI_COMM_SELF, w, alg, 25, "file", loss);
      for (int k = 2; k <= world_size(); ++k) {
        MPI_Comm sub;
        MPI_Comm_split(MPI_COMM_WORLD, world_rank() < k ? 0 : MPI_UNDEFINED, world_rank(), &sub);
        if (sub == MPI_COMM_NULL) continue;
        const auto x = run_model(sub, w, alg, 25, "file", loss);
        EXPECT_EQ(0, std::memcmp(x.data(), ref.data(), x.size() * sizeof(double)))
            << alg << " " << loss << " differs on " << k << " ranks";
        MPI_Comm_free(&sub);
      }
    }
}

TEST(WeightedModel, BadSpecsAreRefused) {
  for (const char* s : {"", "File", "multiplicative", "multiplicative:", "multiplicative:0", "multiplicative:-1",
                        "multiplicative:nan", "multiplicative:1x"})
    EXPECT_THROW(parse_weights_spec(s), Error) << s;
  for (const char* s : {"", "L2", "huber", "huber:", "huber:0", "huber:-0.1", "huber:inf", "huber:0.1,"})
    EXPECT_THROW(parse_loss_spec(s), Error) << s;
  EXPECT_EQ(0.25, parse_loss_spec("huber:0.25"));
  EXPECT_EQ(0.5, parse_weights_spec("multiplicative:0.5").factor);
  SolverOptions o;
  o.algorithm = "mm";
  o.loss = "huber";
  EXPECT_NE("", o.validate());
  // --weights file on a network without sigmas: one error on every rank.
  const Network plain = make_network({.n = 30});
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(plain, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  EXPECT_THROW(prob.set_measurement_model(parse_weights_spec("file"), 0), Error);
}
