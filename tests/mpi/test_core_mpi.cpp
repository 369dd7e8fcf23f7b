// Distributed core: halo plan, relaxation and MM against the serial reference
// twin, bit-identical iterates for 1, 2 and 3 ranks (sub-communicators of this
// run), metis and block partitions.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <cstring>

#include "kernels/kernels.hpp"
#include "snl/problem/metrics.hpp"
#include "reference/reference.hpp"
#include "snl/solvers/solver.hpp"
#include "test_networks.hpp"

using namespace snl;
using snl::test::allgather_positions;
using snl::test::make_network;
using snl::test::NetSpec;
using snl::test::slab_of;

namespace {

Network merged(Network w) {
  merge_duplicates(w.sensor_edges, w.sensor_ranges, w.anchor_edges, w.anchor_ranges);
  w.total_sensor_edges = w.local_sensor_edges();
  w.total_anchor_edges = w.local_anchor_edges();
  return w;
}

// Positions (global order) after `iters` iterations of `alg` on `comm`, with
// up to `block` iterations per pass over memory (SolverOptions::temporal_block).
std::vector<double> run(MPI_Comm comm, const Network& whole, const std::string& alg, int iters,
                        PartitionMethod pm = PartitionMethod::kMetis, int block = 1) {
  LocalizationProblem prob(comm, slab_of(whole, comm), pm, nullptr);
  SolverOptions opt;
  opt.algorithm = alg;
  opt.max_iter = iters;
  opt.tol = 0;
  opt.history_every = 1000000;
  opt.temporal_block = block;
  Solver solver(prob, opt);
  std::vector<double> x;
  solver.solve(random_initial_positions(prob, 3), &x);
  return allgather_positions(prob, x);
}

int world_rank() {
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}
int world_size() {
  int s = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &s);
  return s;
}

}  // namespace

TEST(Halo, GhostsReceiveOwnersValues) {
  const Network w = make_network({.n = 200, .dim = 2, .radius = 0.15});
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  const auto& g = prob.graph();
  std::vector<double> f(std::size_t(g.num_local()) * 2, -1.0);
  for (LocalId v = 0; v < g.num_owned(); ++v) {
    f[2 * v] = double(g.global_id(v));
    f[2 * v + 1] = -double(g.global_id(v));
  }
  prob.graph().halo().exchange(f.data(), 2);
  for (LocalId v = g.num_owned(); v < g.num_local(); ++v) {
    EXPECT_EQ(f[2 * v], double(g.global_id(v)));
    EXPECT_EQ(f[2 * v + 1], -double(g.global_id(v)));
  }
  // Interior nodes have no ghost neighbours; neighbour lists are sorted by global id.
  for (LocalId v = 0; v < g.num_owned(); ++v) {
    for (auto e = g.offsets()[v]; e < g.offsets()[v + 1]; ++e) {
      if (v < g.num_interior()) EXPECT_LT(g.adjacency()[e], g.num_owned());
      if (e > g.offsets()[v]) EXPECT_LT(g.global_id(g.adjacency()[e - 1]), g.global_id(g.adjacency()[e]));
    }
  }
  long long owned = g.num_owned(), total = 0;
  MPI_Allreduce(&owned, &total, 1, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_EQ(total, 200);
}

TEST(Problem, MergesDuplicatesAndMovesAnchorsToOwners) {
  NetSpec s;
  s.n = 60;
  s.duplicates = true;
  const Network w = make_network(s);
  ProblemReport rep;
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kBlock, &rep);
  EXPECT_GT(rep.merged.merged_sensor_pairs, 0);
  const Network m = merged(w);
  EXPECT_EQ(rep.num_sensor_edges, m.local_sensor_edges());
  EXPECT_EQ(rep.num_anchor_edges, m.local_anchor_edges());
  long long a = static_cast<long long>(prob.anchor_ids().size()), at = 0;
  MPI_Allreduce(&a, &at, 1, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_EQ(at, m.local_anchor_edges());
}

TEST(Relaxation, MatchesSerialReference) {
  NetSpec s;
  s.duplicates = true;
  const Network w = make_network(s);
  const Network m = merged(w);
  const auto x = run(MPI_COMM_WORLD, w, "relaxation", 60);
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  const auto x0 = allgather_positions(prob, random_initial_positions(prob, 3));
  const auto xr = reference::nesterov(m, x0, 60);
  ASSERT_EQ(x.size(), xr.size());
  for (std::size_t t = 0; t < x.size(); ++t) EXPECT_NEAR(x[t], xr[t], 1e-12) << t;
}

TEST(MM, MatchesSerialReferenceAndSurrogateNeverIncreases) {
  const Network w = make_network({.n = 40, .dim = 3, .radius = 0.5, .anchor_radius = 0.8, .sigma = 0.05});
  const auto x = run(MPI_COMM_WORLD, w, "mm", 50);
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  const auto x0 = allgather_positions(prob, random_initial_positions(prob, 3));
  std::vector<double> F;
  const auto xr = reference::mm(w, x0, 50, &F);
  for (std::size_t t = 0; t < x.size(); ++t) EXPECT_NEAR(x[t], xr[t], 1e-12) << t;
  for (std::size_t t = 1; t < F.size(); ++t) EXPECT_LE(F[t], F[t - 1] * (1 + 1e-14)) << t;
  EXPECT_LE(reference::ml_cost(w, xr), F.back() * (1 + 1e-12));  // f(x) <= F(z)
}

TEST(Determinism, BitIdenticalForOneTwoThreeRanks) {
  const Network w = make_network({.n = 120, .dim = 2, .radius = 0.2, .anchor_radius = 0.3, .sigma = 0.05});
  for (const char* alg : {"relaxation", "mm", "bb", "pipeline", "pm", "async", "async-exact"}) {
    for (PartitionMethod pm : {PartitionMethod::kMetis, PartitionMethod::kBlock}) {
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

// The schedule of run_levels, checked with "values" that are their level: a
// step at level j must find level j in its own and all its neighbours' rows
// (ghosts included: the halo exchanged them) in the buffer it reads, i.e.
// every dependency done and nothing it needs overwritten yet; after the pass
// every owned row holds level n. Any block size is valid, down to one chunk
// per stage (which catches a skew one too small).
TEST(TemporalBlock, ScheduleRespectsEveryDependency) {
  const Network w = make_network({.n = 3000, .dim = 2, .radius = 0.03, .anchor_radius = 0.2, .sigma = 0.05});
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  const auto& g = prob.graph();
  detail::NodeLanes nl;
  nl.build(prob);
  detail::LevelPlan lp;
  lp.build(prob, nl, 6);
  const std::int64_t default_block = lp.block;
  for (std::int64_t block : {std::int64_t(1), std::int64_t(7), default_block}) {
    lp.block = block;
    for (int n = 1; n <= 6; ++n) {
      std::vector<double> b0(std::size_t(g.num_local()), 0.0), b1(std::size_t(g.num_local()), -1.0);
      double* const buf[2] = {b0.data(), b1.data()};
      std::int64_t bad = 0, steps = 0;
      detail::run_levels(lp, nl, n, prob.graph().halo(), buf, 1, [&](int j, std::int64_t c0, std::int64_t c1) {
        for (std::int64_t c = c0; c < c1; ++c)
          for (LocalId v = nl.first[c]; v < nl.first[c] + nl.count[c]; ++v) {
            bad += buf[j & 1][v] != j;
            for (auto e = g.offsets()[v]; e < g.offsets()[v + 1]; ++e) bad += buf[j & 1][g.adjacency()[e]] != j;
            buf[(j + 1) & 1][v] = j + 1;
            ++steps;
          }
      });
      EXPECT_EQ(bad, 0) << "n = " << n << ", block = " << block;
      EXPECT_EQ(steps, std::int64_t(n) * g.num_owned()) << "n = " << n << ", block = " << block;
      for (LocalId v = 0; v < g.num_owned(); ++v) ASSERT_EQ(buf[n & 1][v], n) << v;
    }
  }
}

// Temporal blocking: several iterations per pass (a wavefront over the
// chunks, the chunks near the boundary level by level after it) gives the
// iterates of one iteration at a time, bit for bit, on any number of ranks.
TEST(TemporalBlock, SameIteratesForAnyBlockAndRankCount) {
  for (int dim : {2, 3}) {
    const Network w = make_network({.n = dim == 2 ? 3000 : 2000, .dim = dim, .radius = dim == 2 ? 0.03 : 0.09,
                                     .anchor_radius = 0.2, .sigma = 0.05});
    {  // the plan has a real wavefront (several blocks) and, on several ranks, deferred chunks
      LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
      detail::NodeLanes nl;
      nl.build(prob);
      detail::LevelPlan lp;
      lp.build(prob, nl, 3);
      EXPECT_GT(lp.skew, 0);
      EXPECT_LT(2 * lp.block, nl.split) << "too few chunks for a wavefront of several stages";
      auto deferred = [&](int j) {
        std::int64_t c = 0;
        for (const auto& [b, e] : lp.deferred[j]) c += e - b;
        return c;
      };
      if (world_size() > 1) {  // level 2 defers the chunks next to level 1's too
        EXPECT_GT(deferred(1), 0);
        EXPECT_GT(deferred(2), deferred(1));
      }
    }
    for (const char* alg : {"relaxation", "mm", "pipeline"}) {
      if (dim == 3 && std::strcmp(alg, "pipeline") == 0) continue;
      const auto ref = run(MPI_COMM_SELF, w, alg, 23);
      for (int block : {2, 3, 5}) {
        for (int k = 1; k <= world_size(); ++k) {
          MPI_Comm sub;
          MPI_Comm_split(MPI_COMM_WORLD, world_rank() < k ? 0 : MPI_UNDEFINED, world_rank(), &sub);
          if (sub == MPI_COMM_NULL) continue;
          const auto x = run(sub, w, alg, 23, PartitionMethod::kMetis, block);
          ASSERT_EQ(x.size(), ref.size());
          EXPECT_EQ(0, std::memcmp(x.data(), ref.data(), x.size() * sizeof(double)))
              << alg << " " << dim << "D with blocks of " << block << " differs on " << k << " ranks";
          MPI_Comm_free(&sub);
        }
      }
    }
  }
}

// The records (history, callbacks) fall on pass ends, so they see the same
// iterates as without blocking; a pass never crosses max_iter.
TEST(TemporalBlock, RecordsSeeTheSameIterates) {
  const Network w = make_network({.n = 400, .dim = 2, .radius = 0.09, .anchor_radius = 0.3, .sigma = 0.05});
  std::vector<std::vector<IterationSummary>> hist;
  for (int block : {1, 4}) {
    LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
    SolverOptions opt;
    opt.algorithm = "pipeline";
    opt.max_iter = 19;
    opt.tol = 0;
    opt.history_every = 5;
    opt.temporal_block = block;
    Solver solver(prob, opt);
    const Summary s = solver.solve(random_initial_positions(prob, 3), nullptr);
    EXPECT_EQ(s.iterations, 38);
    hist.push_back(s.history);
  }
  ASSERT_EQ(hist[0].size(), hist[1].size());
  for (std::size_t r = 0; r < hist[0].size(); ++r) {
    const auto &a = hist[0][r], &b = hist[1][r];
    EXPECT_EQ(a.phase, b.phase);
    EXPECT_EQ(a.iteration, b.iteration);
    EXPECT_EQ(a.cost, b.cost) << r;  // objective at the iterate: the same bits
    EXPECT_EQ(a.ml_cost, b.ml_cost) << r;
    EXPECT_EQ(a.messages, b.messages) << r;
    // Norms summed in another order (the wavefront): equal up to rounding
    // (NaN at a phase's first record).
    EXPECT_EQ(std::isnan(a.rel_change), std::isnan(b.rel_change)) << r;
    if (!std::isnan(a.rel_change)) EXPECT_NEAR(a.rel_change, b.rel_change, 1e-12 * a.rel_change) << r;
  }
  EXPECT_EQ(hist[1].back().iteration, 19);
}

TEST(SequentialMethods, PMAndAsyncMatchTheirOneAtATimeReference) {
  const Network w = merged(make_network({.n = 70, .dim = 2, .radius = 0.25, .anchor_radius = 0.4, .sigma = 0.05}));
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  const auto x0 = allgather_positions(prob, random_initial_positions(prob, 3));
  // Colours: neighbours differ, and the distributed colouring equals the serial one.
  const auto col = jones_plassmann_coloring(prob.graph());
  const auto ref_col = reference::coloring(w);
  for (LocalId v = 0; v < prob.num_owned(); ++v) {
    EXPECT_EQ(col[v], ref_col[prob.graph().global_id(v)]);
    for (auto e = prob.graph().offsets()[v]; e < prob.graph().offsets()[v + 1]; ++e)
      EXPECT_NE(col[v], col[prob.graph().adjacency()[e]]);
  }
  const auto xp = run(MPI_COMM_WORLD, w, "pm", 25);
  const auto xpr = reference::pm(w, x0, 25);
  for (std::size_t t = 0; t < xp.size(); ++t) EXPECT_NEAR(xp[t], xpr[t], 1e-12) << t;
  for (bool exact : {false, true}) {
    const auto xa = run(MPI_COMM_WORLD, w, exact ? "async-exact" : "async", 6);
    // SolverOptions::seed (1 by default) keys the activation sequence.
    const auto xar = reference::async(w, x0, 6 * w.num_sensors, 1, exact);
    for (std::size_t t = 0; t < xa.size(); ++t) EXPECT_NEAR(xa[t], xar[t], 1e-10) << t << (exact ? " exact" : "");
  }
}

TEST(Relaxation, ConvergesAtTheNesterovRate) {
  // f_hat(x(k)) - f_hat* <= 2 L ||x(0) - x*||^2 / (k+1)^2 (003, Sec. IV-B).
  const Network w = merged(make_network({.n = 50, .dim = 2, .radius = 0.3, .anchor_radius = 0.3, .sigma = 0.05}));
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  const auto x0 = allgather_positions(prob, random_initial_positions(prob, 3));
  const double L = reference::relaxation_lipschitz(w);
  EXPECT_EQ(L, relaxation_lipschitz(prob));
  const auto xstar = reference::nesterov(w, x0, 20000);
  const double fstar = reference::relaxed_cost(w, xstar);
  double r2 = 0;
  for (std::size_t t = 0; t < x0.size(); ++t) r2 += (x0[t] - xstar[t]) * (x0[t] - xstar[t]);
  for (int k : {1, 2, 5, 10, 50, 100, 500, 1000}) {
    const auto xk = reference::nesterov(w, x0, k);
    EXPECT_LE(reference::relaxed_cost(w, xk) - fstar, 2 * L * r2 / ((k + 1.0) * (k + 1.0)) + 1e-12) << k;
  }
}

TEST(Relaxation, NoiselessFullAnchorNetworkIsRecoveredExactly) {
  // Every sensor measures every anchor and sigma = 0: the relaxation is tight.
  const Network w = make_network({.n = 30, .dim = 2, .radius = 0.35, .anchor_radius = 2.0, .sigma = 0.0});
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  SolverOptions opt;
  opt.algorithm = "relaxation";
  opt.max_iter = 20000;
  opt.tol = 1e-13;
  Solver solver(prob, opt);
  const Summary s = solver.solve(random_initial_positions(prob, 1), nullptr);
  EXPECT_LT(s.errors.rmse, 1e-6);
  EXPECT_LT(s.costs.certificate, 1e-10);
  EXPECT_LT(s.gap_certificate, 1e-10);
  EXPECT_GT(s.costs.apriori, 1.0);
}

TEST(Solver, StopsOnRelativeImprovementAndRecordsHistory) {
  const Network w = make_network({.n = 50, .dim = 2, .radius = 0.3, .anchor_radius = 0.3, .sigma = 0.01});
  LocalizationProblem prob(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
  SolverOptions opt;
  opt.algorithm = "pipeline";
  opt.max_iter = 100000;
  opt.tol = 1e-6;
  Solver solver(prob, opt);
  const Summary s = solver.solve(random_initial_positions(prob, 1), nullptr);
  EXPECT_EQ(s.termination, TerminationType::kConvergence);
  EXPECT_LT(s.iterations, 200000);
  ASSERT_GE(s.history.size(), 3u);
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
