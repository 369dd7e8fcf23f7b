// The SIMD edge kernels (src/kernels.hpp) against their scalar twins, bit for
// bit, and the block summation against a plain loop. Skips the SIMD half where
// the CPU has no AVX2 (the scalar path is then the only one).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "kernels.hpp"

using namespace snl;

namespace {

struct Slots {
  std::vector<LocalId> src, adj;
  std::vector<double> rho, x, y;
  std::vector<std::uint8_t> fwd;
};

// n slots over m rows, with the awkward cases mixed in: coincident rows (z = 0),
// |z| exactly rho, zero edge variables (the sphere projection's 0 case),
// infinite and NaN coordinates.
Slots make_slots(int p, std::int64_t n, LocalId m, unsigned seed) {
  std::mt19937_64 gen(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  Slots s;
  s.x.resize(std::size_t(m) * p);
  for (auto& v : s.x) v = u(gen);
  s.x[0] = std::numeric_limits<double>::infinity();
  s.x[std::size_t(p)] = std::numeric_limits<double>::quiet_NaN();
  for (std::int64_t k = 0; k < n; ++k) {
    s.src.push_back(static_cast<LocalId>(gen() % m));
    s.adj.push_back(k % 7 == 3 ? s.src.back() : static_cast<LocalId>(gen() % m));
    s.rho.push_back(std::abs(u(gen)));
    s.fwd.push_back(static_cast<std::uint8_t>(gen() & 1));
    for (int c = 0; c < p; ++c) s.y.push_back(k % 5 == 1 ? 0.0 : u(gen));
  }
  if (n <= 5) return s;
  // |z| == rho exactly for one slot (z along an axis).
  s.src[5] = 2;
  s.adj[5] = 3;
  for (int c = 0; c < p; ++c) s.x[3 * p + c] = s.x[2 * p + c];
  s.x[3 * p] = s.x[2 * p] + 0.5;  // z = -0.5 e_1: a term 0 * z would be -0.0, the masked one is +0.0
  s.rho[5] = 0.5;
  return s;
}

bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  // memcmp on an empty vector's data() (possibly null) is undefined, hence the size test first.
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}

}  // namespace

TEST(Kernels, SimdTermsEqualScalarTermsBitForBit) {
  const bool had = detail::set_simd_enabled(true);
  if (!detail::simd_enabled()) {
    detail::set_simd_enabled(had);
    GTEST_SKIP() << "no AVX2 on this CPU";
  }
  for (std::int64_t n : {0, 1, 3, 4, 5, 8, 37, 1001}) {
    const Slots s = make_slots(2, n, 50, 7 + unsigned(n));
    std::vector<double> t_simd(2 * n + 2, -1.0), t_scal(2 * n + 2, -1.0);
    detail::set_simd_enabled(true);
    detail::disk_terms(2, s.src.data(), s.adj.data(), s.rho.data(), s.x.data(), n, t_simd.data());
    detail::set_simd_enabled(false);
    detail::disk_terms(2, s.src.data(), s.adj.data(), s.rho.data(), s.x.data(), n, t_scal.data());
    EXPECT_TRUE(same_bits(t_simd, t_scal)) << "disk terms, n = " << n;

    std::vector<double> y_simd = s.y, y_scal = s.y;
    detail::set_simd_enabled(true);
    detail::mm_terms(2, s.src.data(), s.adj.data(), s.fwd.data(), s.rho.data(), s.x.data(), 0.9, 0.1, n,
                     y_simd.data(), t_simd.data());
    detail::set_simd_enabled(false);
    detail::mm_terms(2, s.src.data(), s.adj.data(), s.fwd.data(), s.rho.data(), s.x.data(), 0.9, 0.1, n,
                     y_scal.data(), t_scal.data());
    EXPECT_TRUE(same_bits(t_simd, t_scal)) << "mm terms, n = " << n;
    EXPECT_TRUE(same_bits(y_simd, y_scal)) << "mm edge variables, n = " << n;
  }
  detail::set_simd_enabled(had);
}

TEST(Kernels, DiskTermIsTheProjectionResidual) {
  // e(z, rho) = max(0, 1 - rho/|z|) z: zero inside the disk, on its boundary and at z = 0.
  const std::vector<LocalId> src = {0, 0, 0, 0}, adj = {1, 2, 3, 0};
  const std::vector<double> x = {0, 0, 3, 4, 0.3, 0.4, 0, 1};
  const std::vector<double> rho = {1, 1, 1, 1};
  for (bool simd : {false, true}) {
    const bool had = detail::set_simd_enabled(simd);
    std::vector<double> t(8);
    detail::disk_terms(2, src.data(), adj.data(), rho.data(), x.data(), 4, t.data());
    EXPECT_DOUBLE_EQ(t[0], -3 * (1 - 1.0 / 5));
    EXPECT_DOUBLE_EQ(t[1], -4 * (1 - 1.0 / 5));
    EXPECT_EQ(t[2], 0.0);  // inside
    EXPECT_EQ(t[3], 0.0);
    EXPECT_EQ(t[4], 0.0);  // on the boundary
    EXPECT_EQ(t[5], 0.0);
    EXPECT_FALSE(std::signbit(t[5]));  // masked, not 0 * (-1)
    EXPECT_EQ(t[6], 0.0);  // z = 0
    EXPECT_EQ(t[7], 0.0);
    EXPECT_FALSE(std::signbit(t[6]));
    detail::set_simd_enabled(had);
  }
}

TEST(Kernels, FixedCountSumEqualsThePlainLoop) {
  std::mt19937_64 gen(3);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> t(2 * (40 + detail::SlotBlock::kPad));
  for (auto& v : t) v = u(gen);
  t[0] = -0.0;  // a sum of a single -0.0 term must stay +0.0 as in the loop
  for (int deg = 0; deg <= 40; ++deg) {
    double plain[2] = {0, 0};
    for (int k = 0; k < deg; ++k)
      for (int c = 0; c < 2; ++c) plain[c] += t[2 * k + c];
    double fixed[2] = {0, 0};
    detail::sum_terms<2>(t.data(), deg, fixed);
    EXPECT_EQ(0, std::memcmp(plain, fixed, sizeof plain)) << deg;
#ifdef __SSE2__
    double sse[2];
    _mm_storeu_pd(sse, detail::sum_terms_2(t.data(), deg));
    EXPECT_EQ(0, std::memcmp(plain, sse, sizeof plain)) << deg;
#endif
  }
}

TEST(Kernels, BlockLoopVisitsEveryNodeOnceWithItsOwnSlots) {
  // Degrees 0 .. 30 and one node larger than a block's default capacity.
  std::vector<std::int64_t> off = {0};
  for (int v = 0; v < 200; ++v) off.push_back(off.back() + (v == 77 ? 3000 : (v * 7) % 31));
  const LocalId n = 200;
  detail::SlotBlock blk;
  blk.reserve(3000, 1);
  std::vector<int> seen(n, 0);
  LocalId next = 0;
  bool ok = true;
  detail::for_node_blocks(
      off, 0, n, blk,
      [&](LocalId v0, LocalId v1, std::int64_t s0, std::int64_t cnt) {
        ok = ok && s0 == off[v0] && cnt == off[v1] - off[v0];
        for (std::int64_t k = 0; k < cnt; ++k) {
          const LocalId v = blk.src[k];
          ok = ok && v >= v0 && v < v1 && off[v] <= s0 + k && s0 + k < off[v + 1];
          blk.t[k] = double(s0 + k);  // the slot's own index as its term
        }
      },
      [&](LocalId v, const double* t, int deg) {
        ok = ok && v == next++ && deg == off[v + 1] - off[v];
        for (int k = 0; k < deg; ++k) ok = ok && t[k] == double(off[v] + k);
        ++seen[v];
      },
      1);
  EXPECT_TRUE(ok);
  EXPECT_EQ(next, n);
  for (int v = 0; v < n; ++v) EXPECT_EQ(seen[v], 1) << v;
}
