// Exact, order-independent sums of doubles (a superaccumulator in the style of
// Kulisch; cf. Demmel & Nguyen's reproducible summation): every term is added
// without rounding into a fixed-point integer covering the whole double range,
// so the sum over any partition of the terms, in any order, on any number of
// ranks is the same integer; value() rounds it once, to nearest even. The
// stopping tests and the metrics sum their per-node terms this way, so they
// do not depend on the rank count or the partition.
#pragma once

#include <mpi.h>

#include <array>
#include <cstdint>

namespace snl::detail {

class ExactSum {
 public:
  /// 32-bit digits in signed 64-bit limbs: digit i weighs 2^(32 i - 1074).
  /// 67 digits reach past 2^1024 with a 53-bit term shifted in; 3 more are
  /// headroom for sums of up to 2^90 terms near DBL_MAX.
  static constexpr int kDigits = 70;
  /// Digits, then the counts of NaN, +inf and -inf terms.
  static constexpr int kWords = kDigits + 3;

  void add(double x) {
    std::uint64_t b;
    __builtin_memcpy(&b, &x, sizeof b);
    int ex = static_cast<int>((b >> 52) & 0x7ff);
    std::uint64_t m = b & ((std::uint64_t(1) << 52) - 1);
    if (ex == 0x7ff) {
      ++w_[kDigits + (m ? 0 : (b >> 63) ? 2 : 1)];
      return;
    }
    if (ex)
      m |= std::uint64_t(1) << 52;
    else
      ex = 1;  // subnormal: same scale as the smallest normal exponent
    // x = m 2^(ex - 1075): m's lowest bit is bit ex - 1 of the integer.
    const int pos = ex - 1, i = pos >> 5;
    const unsigned __int128 v = static_cast<unsigned __int128>(m) << (pos & 31);
    const std::int64_t d0 = static_cast<std::uint32_t>(v), d1 = static_cast<std::uint32_t>(v >> 32),
                       d2 = static_cast<std::int64_t>(v >> 64);
    if (b >> 63) {
      w_[i] -= d0, w_[i + 1] -= d1, w_[i + 2] -= d2;
    } else {
      w_[i] += d0, w_[i + 1] += d1, w_[i + 2] += d2;
    }
    // Each add moves a limb by < 2^32: carry before 2^30 adds could overflow 2^63.
    if (++pending_ == (1 << 30)) normalize();
  }
  void add(const ExactSum& o);
  void clear() {
    w_.fill(0);
    pending_ = 0;
  }
  /// The exact sum rounded to the nearest double (ties to even); NaN if a
  /// term was NaN or both infinities occurred, else +-inf if one did.
  double value() const;
  /// Carries so that every digit but the top one is in [0, 2^32).
  void normalize();
  std::int64_t* words() { return w_.data(); }
  const std::int64_t* words() const { return w_.data(); }

 private:
  std::array<std::int64_t, kWords> w_{};
  std::int32_t pending_ = 0;
};

/// Collective: sums[0..n) become the sums over all ranks of comm (one
/// MPI_Allreduce of integers, exact and associative). n <= kMaxExactSums.
constexpr int kMaxExactSums = 8;
void allreduce_exact(ExactSum* sums, int n, MPI_Comm comm);
/// The same, and extra[0..n_extra) summed over ranks in the same collective
/// (n_extra <= kMaxExactExtra): counts and flags that travel with the sums.
constexpr int kMaxExactExtra = 8;
void allreduce_exact(ExactSum* sums, int n, MPI_Comm comm, std::int64_t* extra, int n_extra);

}  // namespace snl::detail
