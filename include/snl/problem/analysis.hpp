#pragma once
// Whole-network analyses: degree statistics, localizability, Cramér-Rao bound.
// They work on a whole (merged) network held by one process.
#include <cstdint>
#include <string>
#include <vector>

#include "snl/io/network.hpp"

namespace snl {

struct DegreeStats {
  double mean = 0, min = 0, max = 0;  ///< sensor-sensor degree
  double mean_anchor = 0;             ///< anchor measurements per sensor
  GlobalId max_anchor = 0;
  GlobalId isolated = 0;              ///< sensors with no measurement at all
};
DegreeStats degree_stats(const Network& net);

struct LocalizabilityReport {
  GlobalId components = 0;              ///< connected components of the sensor graph
  GlobalId unanchored_components = 0;   ///< components with no anchor measurement
  std::vector<GlobalId> unanchored;     ///< sensors in such components
  std::vector<GlobalId> few_measurements;  ///< sensors with < p+1 measurements
  bool rigidity_checked = false;        ///< only for n <= kRigidityLimit
  bool rigid = false;                   ///< Fisher information positive definite
  std::vector<GlobalId> not_rigid;      ///< sensors in a flexible part (when checked and determinable)
  std::vector<std::uint8_t> flags;      ///< [n] LocalizabilityFlag bits
  bool localizable() const;             ///< all tests passed (rigidity if checked)
  std::string summary() const;          ///< one paragraph for humans
};
constexpr GlobalId kRigidityLimit = 20000;
/// Largest n for which cramer_rao_bound computes tr(J^-1) (selected inversion).
constexpr GlobalId kCrlbLimit = 20000;

/// Connectivity, anchoring and measurement counts; rigidity via the Fisher
/// information matrix at `positions` (truth, if null and present) when
/// check_rigidity and n <= kRigidityLimit (and the sparse factor of J is not
/// too dense: heavy fill, e.g. 3D networks near the limit, leaves
/// rigidity_checked false). not_rigid: the support of the null space of J.
LocalizabilityReport analyze_localizability(const Network& net, bool check_rigidity,
                                            const std::vector<double>* positions = nullptr);

/// Cramér-Rao lower bound (Patwari et al. 2005, equal sigma) at the true
/// positions: RMSE_CRLB = sqrt(tr(J^-1)/n). `defined` is false (with a reason)
/// when J is singular (the anchored network is not rigid) or truth is missing,
/// or n > kCrlbLimit or the factor of J is too dense. tr(J^-1) is computed
/// exactly by selected inversion on the sparse LDL^T factor.
struct CrlbResult {
  bool defined = false;
  double rmse = 0.0;
  std::string reason;
};
CrlbResult cramer_rao_bound(const Network& net, double sigma);

}  // namespace snl
