// The centralized relaxations sdp, esdp and edm (src/solvers/centralized/):
// on a network with exact ranges and every sensor ranged to three or more
// anchors each relaxation is tight, so its solution is the truth and its
// objective zero (closed form); with noise each objective is a lower bound on
// the ML cost, ESDP's below SDP's (ESDP relaxes SDP); the positions are the
// same bits on 1, 2 and 3 ranks; DSDP's verdict on an infeasible SDP is a
// failure; too large a network is refused.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <cstring>

#include "solve_helpers.hpp"
#include "solvers/centralized/sdp_problem.hpp"

using namespace snl;
using snl::test::allgather_positions;
using snl::test::make_network;
using snl::test::merged;
using snl::test::slab_of;
using snl::test::world_rank;
using snl::test::world_size;

namespace {

// Three sensors in the unit square with its corners as anchors; every range
// exact, every sensor ranged to every anchor and to the other sensors.
Network exact_network() {
  Network w;
  w.dim = 2;
  w.num_sensors = 3;
  w.anchors = {0, 0, 1, 0, 0, 1, 1, 1};
  w.truth = {0.3, 0.4, 0.7, 0.6, 0.5, 0.2};
  w.has_truth = true;
  auto dist = [](const double* a, const double* b) { return std::hypot(a[0] - b[0], a[1] - b[1]); };
  for (GlobalId i = 0; i < 3; ++i) {
    for (GlobalId j = i + 1; j < 3; ++j) {
      w.sensor_edges.insert(w.sensor_edges.end(), {i, j});
      w.sensor_ranges.push_back(dist(&w.truth[2 * i], &w.truth[2 * j]));
    }
    for (GlobalId k = 0; k < 4; ++k) {
      w.anchor_edges.insert(w.anchor_edges.end(), {i, k});
      w.anchor_ranges.push_back(dist(&w.truth[2 * i], &w.anchors[2 * k]));
    }
  }
  w.total_sensor_edges = w.local_sensor_edges();
  w.total_anchor_edges = w.local_anchor_edges();
  return w;
}

using snl::test::method_value;
using snl::test::Outcome;

Outcome solve(MPI_Comm comm, const Network& w, const std::string& alg) {
  SolverOptions opt;
  opt.algorithm = alg;
  return snl::test::solve_outcome(comm, w, opt);
}

}  // namespace

TEST(SdpRelaxations, TightOnExactRangesRecoverTheTruth) {
  const Network w = exact_network();
  for (const char* alg : {"sdp", "esdp", "edm"}) {
    const Outcome o = solve(MPI_COMM_WORLD, w, alg);
    EXPECT_EQ(o.s.termination, TerminationType::kConvergence) << alg;
    EXPECT_EQ(o.s.iterations, 1) << alg;
    ASSERT_EQ(o.x.size(), w.truth.size());
    for (std::size_t t = 0; t < o.x.size(); ++t) EXPECT_NEAR(o.x[t], w.truth[t], 1e-4) << alg << " coordinate " << t;
    EXPECT_NEAR(method_value(o.s, "relaxation_objective"), 0.0, 1e-7) << alg;
    ASSERT_EQ(o.s.method_texts.size(), 2u);
    EXPECT_EQ(o.s.method_texts[1].second, "converged") << alg;
  }
}

TEST(SdpRelaxations, LowerBoundsOnTheMLCostAndSameBitsOnAnyRankCount) {
  const Network w = merged(make_network({.n = 20, .dim = 2, .radius = 0.4, .anchor_radius = 0.5, .sigma = 0.05}));
  double sdp_obj = NAN, esdp_obj = NAN;
  for (const char* alg : {"sdp", "esdp", "edm"}) {
    const Outcome ref = solve(MPI_COMM_SELF, w, alg);
    const double obj = method_value(ref.s, "relaxation_objective");
    EXPECT_LE(obj, ref.s.costs.ml + 1e-9) << alg;
    if (std::string(alg) == "sdp") sdp_obj = obj;
    if (std::string(alg) == "esdp") esdp_obj = obj;
    for (int k = 2; k <= world_size(); ++k) {
      MPI_Comm sub;
      MPI_Comm_split(MPI_COMM_WORLD, world_rank() < k ? 0 : MPI_UNDEFINED, world_rank(), &sub);
      if (sub == MPI_COMM_NULL) continue;
      const Outcome o = solve(sub, w, alg);
      ASSERT_EQ(o.x.size(), ref.x.size());
      EXPECT_EQ(0, std::memcmp(o.x.data(), ref.x.data(), o.x.size() * sizeof(double))) << alg << " on " << k << " ranks";
      MPI_Comm_free(&sub);
    }
  }
  EXPECT_LE(esdp_obj, sdp_obj + 1e-7);  // ESDP keeps only some of SDP's constraints
  EXPECT_GT(sdp_obj, 1e-6);             // noisy ranges: no exact fit
}

TEST(SdpRelaxations, InfeasibleSdpIsAFailure) {
  detail::SdpProblem sp;  // X in S^1 with X = 1 and X = 2
  const int b = sp.add_block(1);
  sp.c.push_back({b, 0, 0, 1.0});
  sp.a[sp.add_constraint(1.0)].push_back({b, 0, 0, 1.0});
  sp.a[sp.add_constraint(2.0)].push_back({b, 0, 0, 1.0});
  const detail::SdpSolution s = detail::solve_sdp_dsdp(sp, {});
  EXPECT_FALSE(s.ok) << s.status;
  EXPECT_NE(s.status, "converged");
}

TEST(SdpRelaxations, RefusesNetworksAboveTheLimit) {
  const Network w = make_network({.n = 201, .dim = 2, .radius = 0.15, .anchor_radius = 0.2, .sigma = 0.01});
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kBlock, nullptr);
  SolverOptions opt;
  opt.algorithm = "sdp";
  Solver solver(prob, opt);
  try {
    solver.solve(random_initial_positions(prob, 3), nullptr);
    FAIL() << "a 201-sensor network was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("at most 200 sensors"), std::string::npos) << e.what();
  }
}
