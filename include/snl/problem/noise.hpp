#pragma once
// Noise models applied to a generated network (snl generate --noise,
// --nlos-fraction, --nlos-bias): multiplicative Gaussian noise with a
// per-range sigma, and non-line-of-sight outliers (a positive bias on a
// fraction of the ranges). Counter-based draws keyed by (seed, row): the same
// network for the same options.
#include <cstdint>
#include <string>

#include "snl/io/network.hpp"

namespace snl {

struct NoiseOptions {
  /// gaussian: the ranges as generated (one sigma for all, 003 eq. 28);
  /// multiplicative: r_e = |d_e + sigma_e N(0,1)| with sigma_e = sigma d_e
  /// (d_e the true distance, floored at 1% of the largest), written to
  /// sensor_sigmas / anchor_sigmas.
  std::string model = "gaussian";
  double nlos_fraction = 0.0;  ///< in [0, 1]: the share of ranges given a bias
  double nlos_bias = 0.0;      ///< >= 0: the bias is uniform in [0, nlos_bias]
  std::string validate() const;  ///< "" if valid, else the message
  bool changes_network() const { return model != "gaussian" || nlos_fraction > 0; }
};

/// Applies `opt` to a whole network with truth (generate_network's output),
/// with the generator's sigma and seed. NLOS rows are flagged in sensor_nlos /
/// anchor_nlos whenever nlos_fraction > 0. Throws snl::Error without truth.
void apply_noise_model(Network& net, const NoiseOptions& opt, double sigma, std::uint64_t seed);

}  // namespace snl
