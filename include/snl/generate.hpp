#pragma once
// Random geometric test networks (the papers' setting): sensors uniform in the
// unit square/cube, anchors at the corners or random, ranges with the noise of
// seed 003, eq. (28).
#include <cstdint>
#include <string>

#include "snl/analysis.hpp"
#include "snl/network.hpp"

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
  LocalizabilityReport localizability;
};

/// Deterministic for given options. O(n) expected time (spatial hashing).
/// Throws snl::Error if --localizable was demanded and no draw succeeded.
Network generate_network(const GenerateOptions& opt, GenerateReport* report = nullptr);

}  // namespace snl
