#pragma once
// Counter-based random numbers: a value is a pure function of (seed, stream,
// counter), so results do not depend on the number of ranks or on the order in
// which values are drawn.
#include <cmath>
#include <cstdint>

namespace snl {

/// Streams keep independent uses of one seed apart.
enum class RngStream : std::uint64_t {
  kSensorPositions = 1,
  kAnchorPositions = 2,
  kSensorNoise = 3,
  kAnchorNoise = 4,
  kInit = 5,
  kAsyncClock = 6,
  kExperimentNoise = 7,
  kRedraw = 8,
};

/// SplitMix64 finaliser (Steele, Lea, Flood 2014): a bijective 64-bit mixer.
inline std::uint64_t mix64(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

inline std::uint64_t random_bits(std::uint64_t seed, RngStream stream, std::uint64_t counter) {
  std::uint64_t h = mix64(seed ^ 0x6a09e667f3bcc909ULL);
  h = mix64(h ^ static_cast<std::uint64_t>(stream));
  return mix64(h ^ counter);
}

/// Uniform in the open interval (0, 1).
inline double uniform01(std::uint64_t seed, RngStream stream, std::uint64_t counter) {
  return (static_cast<double>(random_bits(seed, stream, counter) >> 11) + 0.5) * 0x1.0p-53;
}

/// Standard normal by Box-Muller from counters 2c and 2c+1.
inline double standard_normal(std::uint64_t seed, RngStream stream, std::uint64_t counter) {
  const double u1 = uniform01(seed, stream, 2 * counter);
  const double u2 = uniform01(seed, stream, 2 * counter + 1);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586476925 * u2);
}

}  // namespace snl
