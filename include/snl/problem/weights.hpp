#pragma once
// The measurement model of the ML cost: a weight 1/sigma_e^2 per range
// (weighted ML) and the loss on the range residual (l2 or Huber). Weights are
// normalized to w_e = (sigma_min / sigma_e)^2 in (0, 1], sigma_min the
// smallest sigma of the network: the minimizer depends only on relative
// weights, and w = 1 everywhere is the unweighted problem bit for bit
// (docs/quality.md, "Weighted ML").
#include <string>
#include <vector>

namespace snl {

/// --weights file|multiplicative:NF|none (and "auto": file when the network
/// has sensor_sigmas/anchor_sigmas, else none).
struct WeightsSpec {
  enum class Kind { kAuto, kFile, kNone, kMultiplicative } kind = Kind::kAuto;
  double factor = 0;  ///< NF of multiplicative:NF (sigma_e = NF * max(d_e, floor))
};
/// Throws snl::Error with the accepted forms for a bad string.
WeightsSpec parse_weights_spec(const std::string& s);

/// --loss l2|huber:DELTA: the Huber threshold DELTA > 0, or 0 for l2.
/// Throws snl::Error for a bad string.
double parse_loss_spec(const std::string& s);

/// The model as the kernels use it. Each edge term of the costs is
/// w_e * rho(r_e), rho(r) = r^2/2 (l2) or the Huber function
/// r^2/2 for |r| <= delta, delta |r| - delta^2/2 beyond.
struct MeasurementModel {
  bool weighted = false;     ///< some w_e != 1
  double huber_delta = 0;    ///< 0: l2
  /// Per CSR slot of the owned nodes (graph().adjacency() order); empty if !weighted.
  std::vector<double> edge_weights;
  /// Per anchor measurement (anchor_ranges() order); empty if !weighted.
  std::vector<double> anchor_weights;
  /// Global maxima over sensors of sum_j w_ij and of sum_k w_ik (the Lipschitz
  /// bounds; the degree and anchor degree when unweighted).
  double max_weight_sum = 0, max_anchor_weight_sum = 0;
  bool active() const { return weighted || huber_delta > 0; }
  double edge_weight(std::size_t e) const { return weighted ? edge_weights[e] : 1.0; }
  double anchor_weight(std::size_t e) const { return weighted ? anchor_weights[e] : 1.0; }
};

/// Huber factor min(1, delta / |r|) of a residual magnitude r >= 0 (1 for l2):
/// rho'(r) / r, the weight of the quadratic majorizer of rho at r.
inline double huber_factor(double delta, double r) { return delta > 0 && r > delta ? delta / r : 1.0; }
/// rho(r) (r >= 0).
inline double loss_value(double delta, double r) {
  return delta > 0 && r > delta ? delta * r - 0.5 * delta * delta : 0.5 * r * r;
}

}  // namespace snl
