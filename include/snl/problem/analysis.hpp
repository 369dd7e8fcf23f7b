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
/// Largest n for which cramer_rao_bound computes the bound (selected inversion
/// on a sparse factor; the factor's work limit applies as well).
constexpr GlobalId kCrlbLimit = 1000000;

/// Connectivity, anchoring and measurement counts; rigidity via the Fisher
/// information matrix at `positions` (truth, if null and present) when
/// check_rigidity and n <= kRigidityLimit (and the sparse factor of J is not
/// too dense: heavy fill, e.g. 3D networks near the limit, leaves
/// rigidity_checked false). not_rigid: the support of the null space of J.
LocalizabilityReport analyze_localizability(const Network& net, bool check_rigidity,
                                            const std::vector<double>* positions = nullptr);

/// The maximal anchored, infinitesimally rigid part of a network at positions
/// x ([n * p]): the sensors whose position the measurements fix to first order.
/// Found by (1) the components of the sensor graph that see an anchor,
/// (2) peeling sensors with fewer than p measurements inside the part, and
/// (3) a numeric check: the Fisher information of the part (measurements among
/// its sensors and to anchors) is factorised; while it is singular, the sensors
/// in the support of its null space (inverse iteration) are removed and (2)-(3)
/// repeat. The numeric test also catches non-generic configurations (collinear
/// anchors, aligned bars) that counting cannot see.
struct RigidPart {
  std::vector<GlobalId> covered;  ///< sorted ids of the rigid part
  std::vector<GlobalId> outside;  ///< sorted ids of every other sensor
  bool identified = false;        ///< false: refused (factor too dense) or numerically inconclusive
  std::string reason;             ///< why not identified
  int rounds = 0;                 ///< numeric rounds (factorisations of the part's J)
};
/// `weights`: optional 1/sigma^2 per sensor edge and per anchor edge (empty: 1).
RigidPart rigid_anchored_part(const Network& net, const std::vector<double>& x,
                              const std::vector<double>& sensor_weights = {},
                              const std::vector<double>& anchor_weights = {});

/// What cramer_rao_bound computes.
struct CrlbOptions {
  /// >= 0: one noise standard deviation for every range. < 0: per-measurement
  /// sigmas from the network (sensor_sigmas / anchor_sigmas; the network's
  /// scalar sigma for a dataset that is absent).
  double sigma = -1;
  /// Fisher information evaluated here ([n * p]); null: at the true positions.
  const std::vector<double>* positions = nullptr;
  /// Also the p x p diagonal blocks of J^-1 (per-sensor covariances).
  bool covariance = false;
  /// Throws snl::Error on a bad value.
  void validate() const;
};

/// Cramér-Rao lower bound (Patwari et al. 2005) on the maximal anchored rigid
/// part (rigid_anchored_part): J = sum_ij w_ij u_ij u_ij^T over its
/// measurements, w_ij = 1/sigma_ij^2, and RMSE_CRLB = sqrt(tr(J^-1) / covered).
/// Sensors outside the part have no finite bound: listed in `outside`, not
/// averaged in. tr(J^-1) and the diagonal blocks of J^-1 are computed exactly
/// by selected inversion on the sparse LDL^T factor (AMD ordering). `defined`
/// is false (with a reason) when the part is empty, truth/positions or a sigma
/// is missing, n > kCrlbLimit or the factor of J is too dense.
struct CrlbResult {
  bool defined = false;
  double rmse = 0.0;                  ///< over the covered sensors
  std::string reason;                 ///< why not defined
  GlobalId covered = 0;               ///< sensors the bound covers
  std::vector<GlobalId> outside;      ///< sorted ids of the sensors it does not cover
  bool weighted = false;              ///< per-measurement sigmas were used
  /// [n * p * p] row-major p x p blocks of J^-1 (covariance options only);
  /// zero for sensors outside the part.
  std::vector<double> covariance;
};
CrlbResult cramer_rao_bound(const Network& net, const CrlbOptions& opt);
/// One sigma for every range, at the true positions.
CrlbResult cramer_rao_bound(const Network& net, double sigma);

/// Selected inversion of a sparse symmetric positive definite matrix: the
/// entries of A^-1 on the pattern of its Cholesky factor, returned here as the
/// p x p diagonal blocks of A^-1 ([N/p * p * p]; A is N x N, N divisible by p)
/// and its trace. A is given as triplets (row, col, value; both triangles,
/// duplicates summed); its p x p diagonal blocks must be structurally dense
/// (entries off the factor's pattern come back as 0). Exposed for tests; false if A is not positive definite.
bool inverse_diagonal_blocks(int N, const std::vector<int>& rows, const std::vector<int>& cols,
                             const std::vector<double>& values, int p, std::vector<double>& blocks, double& trace);

}  // namespace snl
