// Reproducible sums (src/core/exact_sum.hpp): the sum of adversarial data
// (cancellation across the whole exponent range, subnormals, ties) over any
// split across the ranks and any order is the correctly rounded exact sum,
// bit for bit the same. The reference is an independent big integer in units
// of 2^-1074 that checks correct rounding: |S - r| <= |S - r'| for both
// neighbours r' of the result r (ties: r has an even mantissa).
#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "core/exact_sum.hpp"

using snl::detail::allreduce_exact;
using snl::detail::ExactSum;

namespace {

int rank_of() {
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}
int size_of() {
  int s = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &s);
  return s;
}

// Signed integer in 16-bit digits (base 2^16) of units 2^-1074; a term is
// added bit by bit, a different scheme from ExactSum's 32-bit digit windows.
struct Big {
  static constexpr int kDigits = 2300 / 16;
  std::vector<std::int64_t> d = std::vector<std::int64_t>(kDigits, 0);
  void add(double x, int sign = 1) {
    int e = 0;
    const double f = std::frexp(std::fabs(x), &e);  // |x| = f 2^e, f in [0.5, 1)
    if (f == 0) return;
    // |x| = M 2^(e - 53) with M < 2^53 an integer; bit j of M has unit index e - 53 + j + 1074.
    const auto M = static_cast<std::uint64_t>(std::ldexp(f, 53));
    const int s = (x < 0 ? -1 : 1) * sign;
    for (int j = 0; j < 53; ++j)
      if ((M >> j) & 1) {
        const int bit = e - 53 + j + 1074;
        ASSERT_GE(bit, 0);
        d[bit / 16] += s * (std::int64_t(1) << (bit % 16));
      }
  }
  int normalize() {  // digits in [0, 2^16) but the top; returns the sign
    for (int i = 0; i + 1 < kDigits; ++i) {
      const std::int64_t c = d[i] >> 16;
      d[i] -= c * 65536;
      d[i + 1] += c;
    }
    if (d.back() < 0) {
      for (auto& v : d) v = -v;
      normalize();
      return -1;
    }
    for (auto v : d)
      if (v) return 1;
    return 0;
  }
};

// |a| compared with |b|: -1, 0, 1.
int cmp_abs(Big a, Big b) {
  a.normalize();
  b.normalize();
  for (int i = Big::kDigits - 1; i >= 0; --i)
    if (a.d[i] != b.d[i]) return a.d[i] < b.d[i] ? -1 : 1;
  return 0;
}

// r is the exact sum of v rounded to nearest, ties to even.
::testing::AssertionResult correctly_rounded(const std::vector<double>& v, double r) {
  if (!std::isfinite(r)) return ::testing::AssertionFailure() << "not finite: " << r;
  Big S;
  for (double x : v) S.add(x);
  auto diff = [&](double y) {
    Big D = S;
    D.add(y, -1);
    return D;
  };
  const Big d0 = diff(r);
  for (double nb : {std::nextafter(r, -INFINITY), std::nextafter(r, INFINITY)}) {
    if (!std::isfinite(nb)) continue;
    const int c = cmp_abs(d0, diff(nb));
    if (c > 0) return ::testing::AssertionFailure() << std::hexfloat << r << " is not the nearest (" << nb << " is nearer)";
    if (c == 0) {
      std::uint64_t b;
      std::memcpy(&b, &r, 8);
      if (b & 1) return ::testing::AssertionFailure() << std::hexfloat << r << ": a tie not rounded to even";
    }
  }
  return ::testing::AssertionSuccess();
}

// The sum of v split across the ranks at cut points and in an order drawn from seed.
double split_sum(std::vector<double> v, std::uint64_t seed) {
  std::mt19937_64 g(seed);
  std::shuffle(v.begin(), v.end(), g);
  const int R = size_of();
  std::vector<std::size_t> cut{0, v.size()};
  for (int i = 1; i < R; ++i) cut.push_back(std::uniform_int_distribution<std::size_t>(0, v.size())(g));
  std::sort(cut.begin(), cut.end());
  const int me = rank_of();
  ExactSum s;
  for (std::size_t t = cut[me]; t < cut[me + 1]; ++t) s.add(v[t]);
  allreduce_exact(&s, 1, MPI_COMM_WORLD);
  return s.value();
}

void expect_reproducible(const std::vector<double>& v) {
  const double r0 = split_sum(v, 1);
  EXPECT_TRUE(correctly_rounded(v, r0));
  for (std::uint64_t seed = 2; seed < 12; ++seed) {
    const double r = split_sum(v, seed);
    EXPECT_EQ(std::memcmp(&r, &r0, 8), 0) << std::hexfloat << r << " vs " << r0 << " (seed " << seed << ")";
  }
}

double random_double(std::mt19937_64& g, int emin, int emax) {
  const double f = std::uniform_real_distribution<double>(0.5, 1.0)(g);
  const int e = std::uniform_int_distribution<int>(emin, emax)(g);
  return (g() & 1 ? -1 : 1) * std::ldexp(f, e);  // ldexp below -1021 gives subnormals
}

}  // namespace

TEST(ReproducibleSum, HugeCancellation) {
  std::mt19937_64 g(7);
  std::vector<double> v;
  for (int i = 0; i < 400; ++i) {
    const double x = random_double(g, -1000, 1000);
    v.push_back(x);
    v.push_back(-x);
  }
  for (int i = 0; i < 20; ++i) v.push_back(random_double(g, -60, -40));  // what survives
  v.push_back(1e300);
  v.push_back(-1e300);
  expect_reproducible(v);
}

TEST(ReproducibleSum, MixedExponents) {
  std::mt19937_64 g(11);
  std::vector<double> v;
  for (int i = 0; i < 2000; ++i) v.push_back(random_double(g, -1074, 1000));
  expect_reproducible(v);
}

TEST(ReproducibleSum, NearCancellationLeavesLowBits) {
  // 2^0 + many terms around 2^-30 that cancel except in their lowest bits.
  std::mt19937_64 g(13);
  std::vector<double> v{1.0, -1.0};
  for (int i = 0; i < 1000; ++i) {
    const double x = random_double(g, -40, -20);
    v.push_back(x);
    v.push_back(-x + std::ldexp(double(i % 7), -80));
  }
  expect_reproducible(v);
}

TEST(ReproducibleSum, Subnormals) {
  std::mt19937_64 g(17);
  std::vector<double> v;
  for (int i = 0; i < 1000; ++i) v.push_back(random_double(g, -1074, -1022));
  v.push_back(std::numeric_limits<double>::denorm_min());
  expect_reproducible(v);
  EXPECT_EQ(split_sum({std::numeric_limits<double>::denorm_min(), std::numeric_limits<double>::denorm_min()}, 3),
            2 * std::numeric_limits<double>::denorm_min());
}

TEST(ReproducibleSum, TiesRoundToEvenAndStickyBits) {
  const double u = std::ldexp(1.0, -53);  // half an ulp of 1
  EXPECT_EQ(split_sum({1.0, u}, 1), 1.0);                                      // tie: stays even
  EXPECT_EQ(split_sum({1.0 + 2 * u, u}, 1), 1.0 + 4 * u);                      // tie: to even, up
  EXPECT_EQ(split_sum({1.0, u, std::numeric_limits<double>::denorm_min()}, 2), 1.0 + 2 * u);  // sticky: up
  EXPECT_EQ(split_sum({1.0, u, -std::numeric_limits<double>::denorm_min()}, 2), 1.0);         // below the tie
  EXPECT_EQ(split_sum({1e308, 1e308, -1e308}, 5), 1e308);  // an intermediate past DBL_MAX
  // The doubles 0.1 + 0.2 - 0.3 add up to exactly 2^-55; the plain sum gives 2^-54.
  EXPECT_EQ(split_sum({0.1, 0.2, -0.3}, 4), 0x1p-55);
}

TEST(ReproducibleSum, SpecialValues) {
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(split_sum({1.0, inf, 2.0}, 1), inf);
  EXPECT_EQ(split_sum({1.0, -inf, 2.0}, 1), -inf);
  EXPECT_TRUE(std::isnan(split_sum({inf, -inf}, 1)));
  EXPECT_TRUE(std::isnan(split_sum({1.0, std::nan("")}, 1)));
  EXPECT_EQ(split_sum({}, 1), 0.0);
  EXPECT_EQ(split_sum({-0.0, 0.0}, 1), 0.0);
}

TEST(ReproducibleSum, OneAllreduceForSeveralSumsAndManyTerms) {
  // Several sums in one reduction, and more terms per rank than a limb's
  // headroom without the periodic carry would allow at the top exponent.
  ExactSum s[3];
  for (int i = 0; i < 100000; ++i) {
    s[0].add(0x1.fffffffffffffp1000);
    s[1].add(-0.1);
    s[2].add(1.0);
  }
  allreduce_exact(s, 3, MPI_COMM_WORLD);
  const double R = size_of();
  EXPECT_EQ(s[0].value(), std::ldexp(100000 * R, 1000) * 0x1.fffffffffffffp0);
  std::vector<double> tenth(std::size_t(100000 * R), -0.1);
  EXPECT_TRUE(correctly_rounded(tenth, s[1].value()));
  EXPECT_EQ(s[2].value(), 100000 * R);
}
