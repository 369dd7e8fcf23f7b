// Temporal blocking (the level plan and schedule of src/kernels, run by the
// solver): every dependency respected, the same iterates for any block size
// and rank count, and records that see the same iterates.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <cstring>

#include "kernels/kernels.hpp"
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
