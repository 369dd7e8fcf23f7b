#include "core/exact_sum.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace snl::detail {

void ExactSum::add(const ExactSum& o) {
  for (int i = 0; i < kWords; ++i) w_[i] += o.w_[i];
  normalize();
}

void ExactSum::normalize() {
  for (int i = 0; i + 1 < kDigits; ++i) {
    const std::int64_t c = w_[i] >> 32;  // floor division: digit ends in [0, 2^32)
    w_[i] -= c * (std::int64_t(1) << 32);
    w_[i + 1] += c;
  }
  pending_ = 0;
}

double ExactSum::value() const {
  const std::int64_t nan = w_[kDigits], pinf = w_[kDigits + 1], ninf = w_[kDigits + 2];
  if (nan > 0 || (pinf > 0 && ninf > 0)) return std::numeric_limits<double>::quiet_NaN();
  if (pinf > 0) return std::numeric_limits<double>::infinity();
  if (ninf > 0) return -std::numeric_limits<double>::infinity();
  ExactSum t = *this;
  t.normalize();
  const bool neg = t.w_[kDigits - 1] < 0;
  if (neg) {  // magnitude: negate every digit and carry again
    for (int i = 0; i < kDigits; ++i) t.w_[i] = -t.w_[i];
    t.normalize();
  }
  int h = kDigits - 1;
  while (h >= 0 && t.w_[h] == 0) --h;
  if (h < 0) return 0.0;
  // The top three digits (the top one nonzero) and a sticky bit for the rest.
  auto digit = [&](int i) { return i >= 0 ? static_cast<unsigned __int128>(t.w_[i]) : 0; };
  const unsigned __int128 top = (digit(h) << 64) | (digit(h - 1) << 32) | digit(h - 2);
  bool sticky = false;
  for (int i = 0; i < h - 2; ++i) sticky |= t.w_[i] != 0;
  int bits = 64;
  for (std::uint64_t d = static_cast<std::uint64_t>(t.w_[h]); d; d >>= 1) ++bits;
  const int drop = bits > 53 ? bits - 53 : 0;
  std::uint64_t m = static_cast<std::uint64_t>(top >> drop);
  if (drop > 0) {  // round to nearest, ties to even
    const unsigned __int128 rem = top & ((static_cast<unsigned __int128>(1) << drop) - 1);
    const unsigned __int128 half = static_cast<unsigned __int128>(1) << (drop - 1);
    if (rem > half || (rem == half && (sticky || (m & 1)))) ++m;
  }
  // m < 2^54 is exact as a double; ldexp is exact unless it overflows.
  const double r = std::ldexp(static_cast<double>(m), 32 * (h - 2) + drop - 1074);
  return neg ? -r : r;
}

void allreduce_exact(ExactSum* sums, int n, MPI_Comm comm) { allreduce_exact(sums, n, comm, nullptr, 0); }

void allreduce_exact(ExactSum* sums, int n, MPI_Comm comm, std::int64_t* extra, int n_extra) {
  if (n < 0 || n > kMaxExactSums || n_extra < 0 || n_extra > kMaxExactExtra)
    throw std::logic_error("allreduce_exact: too many sums");
  std::int64_t buf[kMaxExactSums * ExactSum::kWords + kMaxExactExtra];
  for (int j = 0; j < n; ++j) {
    sums[j].normalize();  // digits in [0, 2^32): a sum over 2^31 ranks cannot overflow
    for (int i = 0; i < ExactSum::kWords; ++i) buf[j * ExactSum::kWords + i] = sums[j].words()[i];
  }
  const int words = n * ExactSum::kWords;
  for (int i = 0; i < n_extra; ++i) buf[words + i] = extra[i];
  MPI_Allreduce(MPI_IN_PLACE, buf, words + n_extra, MPI_INT64_T, MPI_SUM, comm);
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < ExactSum::kWords; ++i) sums[j].words()[i] = buf[j * ExactSum::kWords + i];
    sums[j].normalize();
  }
  for (int i = 0; i < n_extra; ++i) extra[i] = buf[words + i];
}

}  // namespace snl::detail
