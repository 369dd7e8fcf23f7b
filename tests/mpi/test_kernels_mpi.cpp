// The node-lane kernels (src/kernels/kernels.hpp): the lane layout against the
// CSR graph, the SIMD steps against their scalar twins bit for bit (awkward
// values included), and the disk residual's boundary cases. Skips the SIMD
// halves where the CPU has no AVX2 (the scalar path is then the only one). The
// kernel tests run on a 2D and a 3D network (KernelsByDim). No communication:
// each rank checks its own part, and only on 2 or more ranks is there a
// boundary part (nodes with ghost neighbours) after the interior, so the
// partial chunk that ends the interior and the boundary chunks are exercised.
#include <mpi.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "kernels/kernels.hpp"
#include "test_networks.hpp"

using namespace snl;
using namespace snl::test;

namespace {

// Bit for bit, except that any two NaNs are equal: which operand's NaN an
// add returns depends on the operand order, and compilers treat a + b and
// b + a as the same.
bool same_bits(double a, double b) { return (std::isnan(a) && std::isnan(b)) || std::memcmp(&a, &b, sizeof a) == 0; }
bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (!same_bits(a[i], b[i])) return false;
  return true;
}

// 150 sensors split over the ranks of this run (chunks of 4 or 8; on 2 or 3
// ranks each rank has an interior and a boundary part, each ending in a
// partial chunk on some rank).
LocalizationProblem make_problem(int dim = 2) {
  const Network w = make_network({.n = 150, .dim = dim, .radius = 0.18, .anchor_radius = 0.25, .sigma = 0.02});
  return LocalizationProblem(MPI_COMM_WORLD, slab_of(w, MPI_COMM_WORLD), PartitionMethod::kMetis, nullptr);
}

int world_size() {
  int s = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &s);
  return s;
}

// Local rows with the awkward cases mixed in: an infinite and a NaN row, and
// node 10 on top of its first neighbour (z = 0).
std::vector<double> awkward_rows(const LocalizationProblem& prob, unsigned seed) {
  std::mt19937_64 gen(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  const int p = prob.dim();
  std::vector<double> x(std::size_t(prob.num_local()) * p);
  for (auto& v : x) v = u(gen);
  x[0] = std::numeric_limits<double>::infinity();
  x[std::size_t(p) * 5 + 1] = std::numeric_limits<double>::quiet_NaN();
  const auto& off = prob.graph().offsets();
  if (off[11] > off[10])
    for (int c = 0; c < p; ++c) x[std::size_t(p) * prob.graph().adjacency()[off[10]] + c] = x[std::size_t(p) * 10 + c];
  return x;
}

struct RelaxOut {
  std::vector<double> xn, wn, norms;
};

RelaxOut relax(const LocalizationProblem& prob, const detail::NodeLanes& nl, const std::vector<double>& w,
               const std::vector<double>& x, bool simd, bool stream = false) {
  RelaxOut o{std::vector<double>(w.size(), -7.0), std::vector<double>(w.size(), -7.0), std::vector<double>(24, 0.0)};
  const bool had = detail::set_simd_enabled(simd);
  const detail::RelaxStep st{w.data(), x.data(), o.xn.data(), o.wn.data(), 1.7, 0.6, o.norms.data(), stream};
  detail::relax_chunks(prob, nl, 0, nl.split, st);
  detail::relax_chunks(prob, nl, nl.split, nl.size(), st);
  detail::set_simd_enabled(had);
  return o;
}

bool have_simd() {
  const bool had = detail::set_simd_enabled(true);
  const bool on = detail::simd_enabled();
  detail::set_simd_enabled(had);
  return on;
}

}  // namespace

TEST(NodeLanes, LayoutHoldsEverySlotOnceInItsOrder) {
  const LocalizationProblem prob = make_problem();
  detail::NodeLanes nl;
  nl.build(prob);
  const auto& gr = prob.graph();
  const int C = nl.lanes;
  ASSERT_TRUE(C == 4 || C == 8);
  // Chunks cover the interior, then the boundary, each in node order.
  LocalId next = 0;
  for (std::int64_t c = 0; c < nl.size(); ++c) {
    if (c == nl.split) EXPECT_EQ(next, gr.num_interior());
    EXPECT_EQ(nl.first[c], next);
    EXPECT_TRUE(nl.count[c] == C || c + 1 == nl.size() || c + 1 == nl.split) << c;
    next += nl.count[c];
  }
  EXPECT_EQ(next, gr.num_owned());
  std::set<std::size_t> seen;
  for (std::int64_t c = 0; c < nl.size(); ++c) {
    for (int q = 0; q < nl.count[c]; ++q) {
      const LocalId v = nl.first[c] + q;
      const int L = detail::NodeLanes::lane_of_node(q, C);
      EXPECT_EQ(detail::NodeLanes::lane_node(L, C), q);
      const std::int64_t deg = gr.offsets()[v + 1] - gr.offsets()[v];
      for (std::int64_t g = nl.group_off[c]; g < nl.group_off[c + 1]; ++g) {
        const std::int64_t k = g - nl.group_off[c];
        const bool real = (nl.real[g] >> L) & 1;
        EXPECT_EQ(real, k < deg);
        if (!real) {
          EXPECT_EQ(nl.adj[g * C + q], v);  // padding: the node itself
          continue;
        }
        const LocalId u = gr.adjacency()[gr.offsets()[v] + k];
        EXPECT_EQ(nl.adj[g * C + q], u);
        EXPECT_EQ(nl.rho[g * C + L], gr.edge_values()[gr.offsets()[v] + k]);
        EXPECT_EQ(((nl.fwd[g] >> L) & 1) != 0, gr.global_id(v) < gr.global_id(u));
        EXPECT_EQ(nl.at(v, k, 2, 1), std::size_t((g * 2 + 1) * C + L));
        EXPECT_TRUE(seen.insert(nl.at(v, k, 2, 0)).second);
        EXPECT_TRUE(seen.insert(nl.at(v, k, 2, 1)).second);
      }
    }
  }
  EXPECT_EQ(seen.size(), gr.adjacency().size() * 2);
  if (world_size() > 1) {  // the layout has a boundary part, and partial chunks before it on some rank
    EXPECT_LT(nl.split, nl.size());
    int partial[2] = {gr.num_interior() % C != 0, (gr.num_owned() - gr.num_interior()) % C != 0};
    MPI_Allreduce(MPI_IN_PLACE, partial, 2, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    EXPECT_TRUE(partial[0] && partial[1]) << "no partial interior or boundary chunk on any rank";
  }
}

// Every kernel test runs on a 2D and a 3D network, with the network's lane
// layout built once per test.
class KernelsByDim : public ::testing::TestWithParam<int> {
 protected:
  KernelsByDim() : dim(GetParam()), prob(make_problem(dim)) { nl.build(prob); }
  const int dim;
  const LocalizationProblem prob;
  detail::NodeLanes nl;
};
INSTANTIATE_TEST_SUITE_P(Dim, KernelsByDim, ::testing::Values(2, 3),
                         [](const ::testing::TestParamInfo<int>& i) { return "p" + std::to_string(i.param); });

TEST_P(KernelsByDim, SimdRelaxationStepEqualsScalarBitForBit) {
  if (!have_simd()) GTEST_SKIP() << "no AVX2 on this CPU";
  for (unsigned seed : {1u, 2u, 3u}) {
    const auto w = awkward_rows(prob, seed), x = awkward_rows(prob, seed + 10);
    const RelaxOut b = relax(prob, nl, w, x, false);
    for (bool stream : {false, true}) {  // plain or non-temporal stores of the rows
      const RelaxOut a = relax(prob, nl, w, x, true, stream);
      EXPECT_TRUE(same_bits(a.xn, b.xn)) << seed << " stream " << stream;
      EXPECT_TRUE(same_bits(a.wn, b.wn)) << seed << " stream " << stream;
      EXPECT_TRUE(same_bits(a.norms, b.norms)) << seed << " stream " << stream;
    }
  }
}

// ml-agd's step (RelaxStep::ml, inv_d, restart): the same bits on the scalar
// and the SIMD path, and the restart sums are the sums of the per-node terms
// q_v = sum_c (w - x(k))_c (x(k) - x(k-1))_c / inv_d[v] over the nodes with
// inv_d[v] > 0 (some are 0 here), and of their absolute values.
TEST_P(KernelsByDim, MlStepRestartSumsAreThePerNodeTerms) {
  auto w = awkward_rows(prob, 4), x = awkward_rows(prob, 5);
  for (auto* r : {&w, &x})  // finite rows (the awkward ones make every sum NaN), node 10 still on its neighbour
    for (auto& v : *r)
      if (!std::isfinite(v)) v = 0.25;
  const LocalId n = prob.num_owned();
  std::vector<double> inv_d(static_cast<std::size_t>(n), 0.0);
  for (LocalId v = 0; v < n; ++v) inv_d[v] = v % 7 == 3 ? 0.0 : 1.0 / (3.0 + v % 5);
  std::vector<double> ref_xn;
  for (bool simd : {false, true}) {
    if (simd && !have_simd()) continue;
    std::vector<double> xn(w.size(), -7.0), wn(w.size(), -7.0), norms(24, 0.0), rs(2 * detail::kMaxLanes, 0.0);
    const bool had = detail::set_simd_enabled(simd);
    const detail::RelaxStep st{w.data(), x.data(), xn.data(), wn.data(), 1.7, 0.6, norms.data(), false, true,
                               inv_d.data(), rs.data()};
    detail::relax_chunks(prob, nl, 0, nl.split, st);
    detail::relax_chunks(prob, nl, nl.split, nl.size(), st);
    detail::set_simd_enabled(had);
    if (simd) EXPECT_TRUE(same_bits(xn, ref_xn)) << "x(k) differs between the scalar and the SIMD path";
    ref_xn = xn;
    double s = 0, a = 0, got_s = 0, got_a = 0;
    for (LocalId v = 0; v < n; ++v) {
      if (!(inv_d[v] > 0)) continue;
      double t = 0;
      for (int c = 0; c < dim; ++c) {
        const std::size_t i = std::size_t(v) * dim + c;
        t += (w[i] - xn[i]) * (xn[i] - x[i]);
      }
      s += t / inv_d[v];
      a += std::fabs(t / inv_d[v]);
    }
    for (int L = 0; L < nl.lanes; ++L) {
      got_s += rs[std::size_t(L)];
      got_a += rs[std::size_t(nl.lanes + L)];
    }
    EXPECT_GT(a, 0);
    EXPECT_NEAR(got_s, s, 1e-12 * a) << "simd " << simd;
    EXPECT_NEAR(got_a, a, 1e-12 * a) << "simd " << simd;
  }
}

TEST_P(KernelsByDim, DiskResidualIsZeroInsideAndOnTheBoundary) {
  // e(z, rho) = max(0, 1 - rho/|z|) z: with every range set to exactly the
  // computed |z| (boundary) or larger (inside), and z = 0 for coincident rows,
  // g = 0 and x(k) = w for nodes without anchors, on both paths.
  std::mt19937_64 gen(5);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> w(std::size_t(prob.num_local()) * dim);
  for (auto& v : w) v = u(gen);
  for (std::int64_t c = 0; c < nl.size(); ++c)
    for (int q = 0; q < nl.count[c]; ++q)
      for (std::int64_t g = nl.group_off[c]; g < nl.group_off[c + 1]; ++g) {
        const LocalId v = nl.first[c] + q, nb = nl.adj[g * nl.lanes + q];
        double s = 0;  // |z|^2 summed in the kernels' order
        for (int k = 0; k < dim; ++k) {
          const double z = w[dim * std::size_t(v) + k] - w[dim * std::size_t(nb) + k];
          s += z * z;
        }
        const double nz = std::sqrt(s);
        nl.rho[g * nl.lanes + detail::NodeLanes::lane_of_node(q, nl.lanes)] = (g % 2) ? nz : 2 * nz;
      }
  for (bool simd : {false, true}) {
    if (simd && !have_simd()) continue;
    const RelaxOut o = relax(prob, nl, w, w, simd);
    int checked = 0;
    for (LocalId v = 0; v < prob.num_owned(); ++v) {
      if (prob.anchor_offsets()[v] != prob.anchor_offsets()[v + 1]) continue;
      ++checked;
      for (int c = 0; c < dim; ++c) {
        EXPECT_EQ(o.xn[dim * std::size_t(v) + c], w[dim * std::size_t(v) + c]) << v << " simd " << simd;
      }
    }
    EXPECT_GT(3 * checked, prob.num_owned());  // a third of the nodes at least
  }
}

TEST_P(KernelsByDim, SimdMMStepEqualsScalarBitForBit) {
  if (!have_simd()) GTEST_SKIP() << "no AVX2 on this CPU";
  std::mt19937_64 gen(9);
  std::uniform_real_distribution<double> u(-1, 1);
  const auto x = awkward_rows(prob, 4);
  std::vector<double> y0(std::size_t(nl.groups()) * nl.lanes * dim), aw0(prob.anchor_ranges().size() * dim);
  for (auto& v : y0) v = u(gen);
  for (auto& v : aw0) v = u(gen);
  // Zero edge variables next to coincident rows: the projection's 0 case.
  const auto& off = prob.graph().offsets();
  for (int c = 0; c < dim; ++c) y0[nl.at(10, 0, dim, c)] = 0.0;
  ASSERT_GT(off[11], off[10]);
  auto run = [&](bool simd, bool stream, std::vector<double>* y, std::vector<double>* aw, std::vector<double>* xn,
                 std::vector<double>* norms) {
    *y = y0;
    *aw = aw0;
    xn->assign(x.size(), -7.0);
    norms->assign(16, 0.0);
    const bool had = detail::set_simd_enabled(simd);
    const detail::MMStep st{x.data(), xn->data(), y->data(), aw->data(), 0.9, 0.1, norms->data(), stream};
    detail::mm_chunks(prob, nl, 0, nl.split, st);
    detail::mm_chunks(prob, nl, nl.split, nl.size(), st);
    detail::set_simd_enabled(had);
  };
  std::vector<double> ya, awa, xa, na, yb, awb, xb, nb, ys, aws, xs, ns;
  run(true, false, &ya, &awa, &xa, &na);
  run(false, false, &yb, &awb, &xb, &nb);
  run(true, true, &ys, &aws, &xs, &ns);  // non-temporal stores of x(t+1)
  EXPECT_TRUE(same_bits(xs, xb));
  EXPECT_TRUE(same_bits(ns, nb));
  EXPECT_TRUE(same_bits(xa, xb));
  EXPECT_TRUE(same_bits(awa, awb));
  EXPECT_TRUE(same_bits(na, nb));
  // Edge variables of real slots (padding lanes are never read back).
  for (LocalId v = 0; v < prob.num_owned(); ++v)
    for (auto e = off[v]; e < off[v + 1]; ++e)
      for (int c = 0; c < dim; ++c) {
        const std::size_t at = nl.at(v, e - off[v], dim, c);
        EXPECT_TRUE(same_bits(ya[at], yb[at])) << v << " slot " << e - off[v];
      }
  // P_sphere(0) = rho e_1 where keep y + invL dz = 0.
  EXPECT_EQ(ya[nl.at(10, 0, dim, 0)], prob.graph().edge_values()[off[10]]);
  for (int c = 1; c < dim; ++c) EXPECT_EQ(ya[nl.at(10, 0, dim, c)], 0.0);
}

// mm-accel's extrapolating step (MMStep::ya, MMStep::xb): forming ya + beta
// (ya - yb) and, with xb, the rows x + beta (x - xb) in the kernel gives the
// bits of separate blend passes followed by the in-place step, on the scalar
// and the SIMD path (AVX2 or AVX-512, the layout's), with y's regular and
// non-temporal stores (MMStep::stream_y), every real slot, x(t+1), the anchor
// variables and the norms; ya, yb, x and xb are not written.
TEST_P(KernelsByDim, ExtrapolatingMMStepEqualsBlendThenStep) {
  std::mt19937_64 gen(13);
  std::uniform_real_distribution<double> u(-1, 1);
  const auto x = awkward_rows(prob, 6);
  std::vector<double> xprev(x.size());
  for (auto& v : xprev) v = u(gen);
  std::vector<double> ycur(std::size_t(nl.groups()) * nl.lanes * dim), yprev(ycur.size()),
      aw0(prob.anchor_ranges().size() * dim);
  for (auto& v : ycur) v = u(gen);
  for (auto& v : yprev) v = u(gen);
  for (auto& v : aw0) v = u(gen);
  const double beta = 0.7;
  const auto& off = prob.graph().offsets();
  for (int path = 0; path < 6; ++path) {
    const bool simd = path % 3 > 0, stream = path % 3 == 2, with_x = path >= 3;
    if (simd && !have_simd()) continue;
    const bool had = detail::set_simd_enabled(simd);
    std::vector<double> xblend = x;
    if (with_x)
      for (std::size_t i = 0; i < x.size(); ++i) xblend[i] = x[i] + beta * (x[i] - xprev[i]);
    auto step = [&](bool fused, std::vector<double>* y, std::vector<double>* aw, std::vector<double>* xn,
                    std::vector<double>* norms) {
      y->assign(ycur.size(), -3.0);
      if (!fused)
        for (std::size_t i = 0; i < y->size(); ++i) (*y)[i] = ycur[i] + beta * (ycur[i] - yprev[i]);
      *aw = aw0;
      xn->assign(x.size(), -7.0);
      norms->assign(16, 0.0);
      detail::MMStep st{fused ? x.data() : xblend.data(), xn->data(), y->data(), aw->data(), 0.9, 0.1,
                        norms->data(), false};
      if (fused) {
        st.ya = ycur.data();
        st.yb = yprev.data();
        st.xb = with_x ? xprev.data() : nullptr;
        st.beta = beta;
        st.stream_y = stream;
      }
      detail::mm_chunks(prob, nl, 0, nl.split, st);
      detail::mm_chunks(prob, nl, nl.split, nl.size(), st);
    };
    const std::vector<double> ycur0 = ycur, yprev0 = yprev, x0 = x, xprev0 = xprev;
    std::vector<double> yf, awf, xf, nf, yb, awb, xb, nb;
    step(true, &yf, &awf, &xf, &nf);
    step(false, &yb, &awb, &xb, &nb);
    detail::set_simd_enabled(had);
    EXPECT_TRUE(same_bits(xf, xb)) << "path " << path;
    EXPECT_TRUE(same_bits(awf, awb)) << "path " << path;
    EXPECT_TRUE(same_bits(nf, nb)) << "path " << path;
    EXPECT_TRUE(same_bits(ycur, ycur0) && same_bits(yprev, yprev0)) << "path " << path;
    EXPECT_TRUE(same_bits(x, x0) && same_bits(xprev, xprev0)) << "path " << path;
    int differs = 0;
    for (LocalId v = 0; v < prob.num_owned(); ++v)
      for (auto e = off[v]; e < off[v + 1]; ++e)
        for (int c = 0; c < dim; ++c) {
          const std::size_t at = nl.at(v, e - off[v], dim, c);
          differs += !same_bits(yf[at], yb[at]);
          differs += yf[at] == -3.0;  // every real slot written
        }
    EXPECT_EQ(differs, 0) << "path " << path;
  }
}

// mm-accel's acceptance costs per chunk: each lane holds its node's sums over
// its forward slots in slot order (checked against a plain loop over the CSR),
// and the SIMD path of the layout (AVX2 or AVX-512) gives the scalar twin's
// bits, the awkward rows included.
TEST_P(KernelsByDim, MMCostChunkSumsEachNodesForwardSlotsInOrder) {
  std::mt19937_64 gen(13);
  std::uniform_real_distribution<double> u(-1, 1);
  const auto x = awkward_rows(prob, 5);
  std::vector<double> y(std::size_t(nl.groups()) * nl.lanes * dim);
  for (auto& v : y) v = u(gen);
  const auto& g = prob.graph();
  const auto& off = g.offsets();
  const bool simd = have_simd();
  std::int64_t full = 0, counted = 0;
  for (std::int64_t c = 0; c < nl.size(); ++c) {
    double F[2][detail::kMaxLanes] = {}, f[2][detail::kMaxLanes] = {};
    unsigned any[2] = {0, 0};
    for (int path = 0; path < (simd ? 2 : 1); ++path) {
      const bool had = detail::set_simd_enabled(path == 1);
      any[path] = detail::mm_cost_chunk(nl, dim, c, x.data(), y.data(), F[path], f[path]);
      detail::set_simd_enabled(had);
    }
    full += nl.count[c] == nl.lanes;
    for (int q = 0; q < nl.count[c]; ++q) {
      const LocalId v = nl.first[c] + q;
      const int L = detail::NodeLanes::lane_of_node(q, nl.lanes);
      double eF = 0, ef = 0;
      bool fwd = false;
      for (auto e = off[v]; e < off[v + 1]; ++e) {
        if (!(g.global_id(v) < g.global_id(g.adjacency()[e]))) continue;
        fwd = true;
        double s = 0, z2 = 0;
        for (int k = 0; k < dim; ++k) {
          const double z = x[std::size_t(v) * dim + k] - x[std::size_t(g.adjacency()[e]) * dim + k];
          const double r = z - y[nl.at(v, e - off[v], dim, k)];
          s += r * r;
          z2 += z * z;
        }
        const double m = std::sqrt(z2) - g.edge_value(e);
        eF += s;
        ef += m * m;
      }
      EXPECT_EQ((any[0] >> L) & 1, fwd ? 1u : 0u) << "node " << v;
      EXPECT_TRUE(same_bits(F[0][L], eF)) << "node " << v << ": " << F[0][L] << " vs " << eF;
      EXPECT_TRUE(same_bits(f[0][L], ef)) << "node " << v << ": " << f[0][L] << " vs " << ef;
      counted += fwd;
    }
    if (simd) {
      EXPECT_EQ(any[1], any[0]) << "chunk " << c;
      for (int L = 0; L < nl.lanes; ++L) {
        EXPECT_TRUE(same_bits(F[1][L], F[0][L])) << "chunk " << c << " lane " << L;
        EXPECT_TRUE(same_bits(f[1][L], f[0][L])) << "chunk " << c << " lane " << L;
      }
    }
  }
  EXPECT_GT(full, 0);
  EXPECT_GT(3 * counted, prob.num_owned());
}

// One call over both parts (as mm-accel makes) steps each node once: the
// same bits as part by part. The interior's partial last chunk must not go
// through the SIMD kernel, whose extra lanes would step the next nodes'
// anchor variables a second time.
// mm-accel's pass (MMStep::cost_F): the extrapolating step, called a block
// of chunks at a time as the solver does, also gives each chunk's acceptance
// costs of (x, ya), the bits of mm_cost_chunk on the same chunk, with the
// same lanes mask, on the scalar and the SIMD path (the AVX-512 kernel sums
// them itself), and takes the same step as without them.
TEST_P(KernelsByDim, ExtrapolatingMMStepSumsTheCandidatesCosts) {
  std::mt19937_64 gen(17);
  std::uniform_real_distribution<double> u(-1, 1);
  const auto x = awkward_rows(prob, 7);
  std::vector<double> xprev(x.size());
  for (auto& v : xprev) v = u(gen);
  std::vector<double> ya(std::size_t(nl.groups()) * nl.lanes * dim), yb(ya.size()),
      aw0(prob.anchor_ranges().size() * dim);
  for (auto& v : ya) v = u(gen);
  for (auto& v : yb) v = u(gen);
  for (auto& v : aw0) v = u(gen);
  const int C = nl.lanes;
  const std::int64_t block = 5;  // blocks cross the interior/boundary split and end in partial chunks
  for (int path = 0; path < 2; ++path) {
    if (path == 1 && !have_simd()) continue;
    const bool had = detail::set_simd_enabled(path == 1);
    auto step = [&](bool costs, std::vector<double>* y, std::vector<double>* xn, std::vector<double>* F,
                    std::vector<double>* f, std::vector<unsigned>* any) {
      y->assign(ya.size(), -3.0);
      std::vector<double> aw = aw0, norms(16, 0.0);
      xn->assign(x.size(), -7.0);
      F->assign(std::size_t(nl.size()) * C, -5.0);
      f->assign(F->size(), -5.0);
      any->assign(std::size_t(nl.size()), 999);
      detail::MMStep st{x.data(), xn->data(), y->data(), aw.data(), 0.9, 0.1, norms.data(), false};
      st.ya = ya.data();
      st.yb = yb.data();
      st.xb = xprev.data();
      st.beta = 0.6;
      for (std::int64_t b = 0; b < nl.size(); b += block) {
        if (costs) {
          st.cost_F = F->data() + b * C;
          st.cost_f = f->data() + b * C;
          st.cost_any = any->data() + b;
          st.cost_base = b;
        }
        detail::mm_chunks(prob, nl, b, std::min(nl.size(), b + block), st);
      }
    };
    std::vector<double> y1, x1, F1, f1, y0, x0, F0, f0;
    std::vector<unsigned> any1, any0;
    step(true, &y1, &x1, &F1, &f1, &any1);
    step(false, &y0, &x0, &F0, &f0, &any0);
    EXPECT_TRUE(same_bits(x1, x0)) << "path " << path;
    EXPECT_TRUE(same_bits(y1, y0)) << "path " << path;
    int differs = 0, counted = 0;
    for (std::int64_t c = 0; c < nl.size(); ++c) {
      double F[detail::kMaxLanes] = {}, f[detail::kMaxLanes] = {};
      const unsigned any = detail::mm_cost_chunk(nl, dim, c, x.data(), ya.data(), F, f);
      differs += any1[c] != any;
      for (int L = 0; L < C; ++L) {
        differs += !same_bits(F1[c * C + L], F[L]) || !same_bits(f1[c * C + L], f[L]);
        counted += (any >> L) & 1;
      }
    }
    detail::set_simd_enabled(had);
    EXPECT_EQ(differs, 0) << "path " << path;
    EXPECT_GT(3 * counted, prob.num_owned()) << "path " << path;
  }
}

TEST_P(KernelsByDim, OneMMCallOverBothPartsEqualsPartByPart) {
  std::mt19937_64 gen(11);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> x(std::size_t(prob.num_local()) * dim);
  for (auto& v : x) v = u(gen);
  std::vector<double> y0(std::size_t(nl.groups()) * nl.lanes * dim), aw0(prob.anchor_ranges().size() * dim);
  for (auto& v : y0) v = u(gen);
  for (auto& v : aw0) v = u(gen);
  auto run = [&](bool whole, std::vector<double>* aw, std::vector<double>* xn) {
    std::vector<double> y = y0, norms(16, 0.0);
    *aw = aw0;
    xn->assign(x.size(), -7.0);
    const detail::MMStep st{x.data(), xn->data(), y.data(), aw->data(), 0.9, 0.1, norms.data(), false};
    if (whole) {
      detail::mm_chunks(prob, nl, 0, nl.size(), st);
    } else {
      detail::mm_chunks(prob, nl, 0, nl.split, st);
      detail::mm_chunks(prob, nl, nl.split, nl.size(), st);
    }
  };
  std::vector<double> awa, xa, awb, xb;
  run(true, &awa, &xa);
  run(false, &awb, &xb);
  EXPECT_TRUE(same_bits(xa, xb));
  EXPECT_TRUE(same_bits(awa, awb));
}
