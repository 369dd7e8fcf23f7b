#pragma once
// Random geometric test networks (the papers' setting): sensors uniform in the
// unit square/cube (a larger square/cube at constant density beyond
// kReferenceSensors sensors), anchors at the corners and/or random, ranges with
// the noise of seed 003, eq. (28).
#include <cstdint>
#include <string>
#include <vector>

#include "snl/problem/analysis.hpp"
#include "snl/io/network.hpp"

namespace snl {

/// Up to this many sensors the region is the unit square/cube (the papers'
/// geometry); beyond it the side grows as (n / kReferenceSensors)^(1/p), so the
/// density, the link radius at a given degree and hence the meaning of an
/// absolute --sigma stay those of a kReferenceSensors-sensor unit square.
constexpr GlobalId kReferenceSensors = 1000;
/// avg_degree value for the default degree, default_avg_degree(dim).
constexpr double kAutoDegree = -1.0;
/// The default average degree: 16 in 2D, 24 in 3D, the smallest even degrees of
/// docs/generator.md's measurements at which default networks of up to 20,000
/// sensors are fully localizable within a few draws (and at most a few sensors
/// in 10^4 are not localizable at any n).
double default_avg_degree(int dim);
/// num_random_anchors value for the default anchors: the 2^p corners plus
/// floor(n / 100) uniform random anchors.
constexpr int kAutoAnchors = -1;

struct GenerateOptions {
  GlobalId sensors = 0;          ///< n (required, >= 1)
  int dim = 2;                   ///< 1, 2 or 3
  double avg_degree = kAutoDegree;  ///< target average sensor-sensor degree (within +-5%); kAutoDegree: default_avg_degree(dim)
  double sigma = 0.01;           ///< range noise standard deviation (>= 0), in region units
  double sigma_rel = 0.0;        ///< > 0: sigma = sigma_rel * link radius (overrides sigma)
  int num_random_anchors = kAutoAnchors;  ///< kAutoAnchors: corners + floor(n/100) random; 0: the 2^p corners only; K > 0: K uniform anchors
  double side = 0.0;             ///< region side; <= 0: auto (1 up to kReferenceSensors, then constant density)
  double anchor_radius = -1.0;   ///< < 0: same radius as sensor-sensor links
  std::uint64_t seed = 1;
  enum class Localizable { kAuto, kYes, kNo } localizable = Localizable::kAuto;
  int max_draws = 1000;          ///< redraw limit under --localizable
  /// kStar (dim 1, sensors 1): the star of 003 Fig. 2 / Table I, one sensor at
  /// star_center whose neighbours are anchors at star_anchors (all measured,
  /// noise of eq. 28); the random-network options do not apply.
  enum class Topology { kRandom, kStar } topology = Topology::kRandom;
  double star_center = 3.0;
  /// Distances 1, 1 and 2 from the hub: the expected eq. (23) bound, 1/2 sum
  /// (d_k^2 + sigma^2) = 3.094 at sigma 0.25, matches 003 Table I (3.0871);
  /// docs/reproduction.md.
  std::vector<double> star_anchors = {2.0, 4.0, 5.0};
  std::string validate() const;  ///< "" if valid, else the message
  std::string validate_star() const;
};

struct GenerateReport {
  int draws = 1;                 ///< draws taken (1 unless redrawn for localizability)
  double radius = 0.0;           ///< sensor-sensor connection radius used
  double anchor_radius = 0.0;
  double achieved_avg_degree = 0.0;
  double side = 1.0;             ///< side of the region [0, side]^p
  double sigma = 0.0;            ///< noise standard deviation used (sigma_rel * radius under sigma_rel)
  std::uint64_t draw_seed = 0;   ///< seed of the draw returned (opt.seed for draw 1)
  LocalizabilityReport localizability;
  std::string warning;           ///< "" or why the network is not (fully) localizable, with the remedy
};

/// Side L of the region [0, L]^p for these options (opt.side if > 0).
double region_side(const GenerateOptions& opt);

/// Deterministic for given options. O(n) expected time (spatial hashing).
/// Throws snl::Error if --localizable was demanded and no draw succeeded.
///
/// Conventions (so that independent implementations can reproduce a network):
/// - L = region_side(opt): the side of the region [0, L]^p;
/// - sensor i coordinate c = L * uniform01(seed', kSensorPositions, i*p + c), where
///   seed' = seed for draw 1 and random_bits(seed, kRedraw, d) for draw d+1;
/// - anchors: the 2^p corners of the region (bit d of k is coordinate d), then
///   the random ones, random anchor k' coordinate c = L * uniform01(seed',
///   kAnchorPositions, k'*p + c);
/// - edges are chosen on the unit-cube coordinates u = x / L (for L = 1, x itself):
///   with k = round(avg_degree*n/2) and s_ij = float(||u_i - u_j||^2): t = the k-th
///   smallest s_ij; edges are the pairs with s_ij <= t, equivalently with
///   ||u_i - u_j||^2 <= R2 := max{||u_i - u_j||^2 : s_ij <= t}; radius = L sqrt(R2);
///   true distances L ||u_i - u_j||;
/// - anchor edge (i, k) iff ||u_i - a_k / L||^2 <= (anchor_radius / L)^2 (R2 by
///   default), true distance L ||u_i - a_k / L||;
/// - ranges (003, eq. 28): |true + sigma * standard_normal(seed', kSensorNoise, i*n + j)|
///   for i < j, and kAnchorNoise with counter i*m + k for anchor edges.
/// Redraws: kYes redraws (up to max_draws, else throws) until the network is
/// localizable (rigidity checked when n <= kRigidityLimit); kAuto does the same
/// for n <= kRigidityLimit with at most min(max_draws, kAutoMaxDraws) draws and
/// returns the last draw (flagged, with report->warning set) instead of
/// throwing; kNo never redraws. report->warning is also set when more than 1% of
/// the sensors of the returned network cannot be localized.
/// net.localizability always receives the per-sensor flags.
Network generate_network(const GenerateOptions& opt, GenerateReport* report = nullptr);

constexpr int kAutoMaxDraws = 100;

/// Reference twin for tests: the same network, built with an O(n^2) all-pairs
/// search instead of the spatial hash (small n only).
Network generate_network_reference(const GenerateOptions& opt, GenerateReport* report = nullptr);

}  // namespace snl
