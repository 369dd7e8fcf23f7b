// Noise models of snl generate (noise.hpp).
#include "snl/problem/noise.hpp"

#include <algorithm>
#include <cmath>

#include "snl/core/random.hpp"

namespace snl {

namespace {

// Seeds of the draws of this file, apart from the generator's own streams.
constexpr std::uint64_t kMultiplicativeSalt = 0x6d756c7469706c79ULL, kNlosSalt = 0x4e4c4f5362696173ULL;
constexpr double kDistanceFloor = 1e-2;  // sigma_e = sigma max(d_e, 1% of the largest d)

double distance(const double* a, const double* b, int p) {
  double s = 0;
  for (int c = 0; c < p; ++c) s += (a[c] - b[c]) * (a[c] - b[c]);
  return std::sqrt(s);
}

// True distances of the sensor rows and of the anchor rows.
void true_distances(const Network& net, std::vector<double>& ds, std::vector<double>& da) {
  const int p = net.dim;
  ds.resize(net.sensor_ranges.size());
  da.resize(net.anchor_ranges.size());
  for (std::size_t e = 0; e < ds.size(); ++e)
    ds[e] = distance(&net.truth[net.sensor_edges[2 * e] * p], &net.truth[net.sensor_edges[2 * e + 1] * p], p);
  for (std::size_t e = 0; e < da.size(); ++e)
    da[e] = distance(&net.truth[net.anchor_edges[2 * e] * p], &net.anchors[net.anchor_edges[2 * e + 1] * p], p);
}

// r_e = |d_e + sigma_e N(0,1)|, sigma_e = sigma max(d_e, floor), into ranges and sigmas.
void redraw(const std::vector<double>& d, double sigma, double floor, std::uint64_t seed, RngStream stream,
            std::vector<double>& ranges, std::vector<double>& sigmas) {
  sigmas.resize(d.size());
  for (std::size_t e = 0; e < d.size(); ++e) {
    sigmas[e] = sigma * std::max(d[e], floor);
    ranges[e] = std::abs(d[e] + sigmas[e] * standard_normal(seed ^ kMultiplicativeSalt, stream, e));
  }
}

// A bias uniform in [0, B] on each row with probability F (two draws per row).
void add_nlos(double F, double B, std::uint64_t seed, RngStream stream, std::vector<double>& ranges,
              std::vector<std::uint8_t>& flags) {
  flags.assign(ranges.size(), 0);
  for (std::size_t e = 0; e < ranges.size(); ++e) {
    if (uniform01(seed ^ kNlosSalt, stream, 2 * e) >= F) continue;
    ranges[e] += B * uniform01(seed ^ kNlosSalt, stream, 2 * e + 1);
    flags[e] = 1;
  }
}

}  // namespace

std::string NoiseOptions::validate() const {
  if (model != "gaussian" && model != "multiplicative")
    return "bad --noise '" + model + "' (expected gaussian or multiplicative)";
  if (!(nlos_fraction >= 0 && nlos_fraction <= 1)) return "--nlos-fraction must be in [0, 1]";
  if (!(nlos_bias >= 0) || !std::isfinite(nlos_bias)) return "--nlos-bias must be a finite number >= 0";
  if (nlos_fraction > 0 && !(nlos_bias > 0)) return "--nlos-fraction needs --nlos-bias B > 0";
  return "";
}

void apply_noise_model(Network& net, const NoiseOptions& opt, double sigma, std::uint64_t seed) {
  if (!net.has_truth) throw Error("noise models need the true positions");
  if (opt.model == "multiplicative") {
    std::vector<double> ds, da;
    true_distances(net, ds, da);
    double dmax = 0;
    for (double d : ds) dmax = std::max(dmax, d);
    for (double d : da) dmax = std::max(dmax, d);
    const double floor = dmax > 0 ? kDistanceFloor * dmax : 1.0;
    if (!(sigma > 0)) throw Error("--noise multiplicative needs --sigma > 0 (sigma_e = sigma d_e)");
    redraw(ds, sigma, floor, seed, RngStream::kSensorNoise, net.sensor_ranges, net.sensor_sigmas);
    redraw(da, sigma, floor, seed, RngStream::kAnchorNoise, net.anchor_ranges, net.anchor_sigmas);
    net.sigma.reset();  // no single sigma describes the ranges
  }
  if (opt.nlos_fraction > 0) {
    add_nlos(opt.nlos_fraction, opt.nlos_bias, seed, RngStream::kSensorNoise, net.sensor_ranges, net.sensor_nlos);
    add_nlos(opt.nlos_fraction, opt.nlos_bias, seed, RngStream::kAnchorNoise, net.anchor_ranges, net.anchor_nlos);
  }
}

}  // namespace snl
