#pragma once
// Random geometric test networks (the papers' setting): sensors uniform in the
// unit square/cube, anchors at the corners or random, ranges with the noise of
// seed 003, eq. (28).
#include <cstdint>
#include <string>

#include "snl/problem/analysis.hpp"
#include "snl/io/network.hpp"

namespace snl {

struct GenerateOptions {
  GlobalId sensors = 0;          ///< n (required, >= 1)
  int dim = 2;                   ///< 2 or 3
  double avg_degree = 6.0;       ///< target average sensor-sensor degree; achieved within +-5%
  double sigma = 0.01;           ///< range noise standard deviation (>= 0)
  int num_random_anchors = 0;    ///< 0: anchors at the 2^p corners; K > 0: K uniform anchors
  double anchor_radius = -1.0;   ///< < 0: same radius as sensor-sensor links
  std::uint64_t seed = 1;
  enum class Localizable { kAuto, kYes, kNo } localizable = Localizable::kAuto;
  int max_draws = 1000;          ///< redraw limit under --localizable
  std::string validate() const;  ///< "" if valid, else the message
};

struct GenerateReport {
  int draws = 1;                 ///< draws taken (1 unless redrawn for localizability)
  double radius = 0.0;           ///< sensor-sensor connection radius used
  double anchor_radius = 0.0;
  double achieved_avg_degree = 0.0;
  std::uint64_t draw_seed = 0;   ///< seed of the draw returned (opt.seed for draw 1)
  LocalizabilityReport localizability;
};

/// Deterministic for given options. O(n) expected time (spatial hashing).
/// Throws snl::Error if --localizable was demanded and no draw succeeded.
///
/// Conventions (so that independent implementations can reproduce a network):
/// - sensor i coordinate c = uniform01(seed', kSensorPositions, i*p + c), where
///   seed' = seed for draw 1 and random_bits(seed, kRedraw, d) for draw d+1;
/// - random anchor k coordinate c = uniform01(seed', kAnchorPositions, k*p + c);
/// - with k = round(avg_degree*n/2) and s_ij = float(||x_i - x_j||^2): t = the k-th
///   smallest s_ij; edges are the pairs with s_ij <= t, equivalently with
///   ||x_i - x_j||^2 <= R2 := max{||x_i - x_j||^2 : s_ij <= t}; radius = sqrt(R2);
/// - anchor edge (i, k) iff ||x_i - a_k||^2 <= anchor_radius^2 (R2 by default);
/// - ranges (003, eq. 28): |true + sigma * standard_normal(seed', kSensorNoise, i*n + j)|
///   for i < j, and kAnchorNoise with counter i*m + k for anchor edges.
/// Redraws: kYes redraws (up to max_draws, else throws) until the network is
/// localizable (rigidity checked when n <= kRigidityLimit); kAuto does the same
/// for n <= kRigidityLimit with at most min(max_draws, kAutoMaxDraws) draws and
/// returns the last draw (flagged) instead of throwing; kNo never redraws.
/// net.localizability always receives the per-sensor flags.
Network generate_network(const GenerateOptions& opt, GenerateReport* report = nullptr);

constexpr int kAutoMaxDraws = 100;

/// Reference twin for tests: the same network, built with an O(n^2) all-pairs
/// search instead of the spatial hash (small n only).
Network generate_network_reference(const GenerateOptions& opt, GenerateReport* report = nullptr);

}  // namespace snl
