#pragma once
// The distance-vector start of dv-pipeline (the default of snl solve): every
// sensor learns its path distances to its K nearest anchors (sums of measured
// ranges along the shortest path through the sensor graph, a distributed
// label-correcting search in distance order with one halo exchange per round;
// "DV-distance", Niculescu & Nath, IEEE INFOCOM 2003), the path lengths are
// calibrated by one global factor (anchor-to-anchor straight distances over
// their shortest paths, whose noise makes them shorter than the truth), and
// each sensor places itself by least-squares multilateration against those
// anchors. The start is a few
// tenths of a link radius from the truth and, unlike the random start, places
// sensors outside the anchors' hull on the side they are (docs/dv-pipeline.md).
#include <cstdint>
#include <vector>

#include "snl/problem/problem.hpp"

namespace snl {

/// Anchors per sensor of the start: 3p (6 in 2D).
int dv_start_anchors(int dim);

/// Per owned sensor (local order) up to k (anchor id, path distance) entries,
/// ascending by (distance, id); id -1 marks an empty entry.
struct AnchorPaths {
  int k = 0;
  std::vector<std::int32_t> ids;  ///< k per owned sensor
  std::vector<double> dist;       ///< k per owned sensor
  std::int64_t rounds = 0;        ///< halo exchanges until no list changed
};

/// Collective: the k nearest anchors of every owned sensor by shortest path
/// (the same lists, bit for bit, on any number of ranks: each round is a
/// synchronous update from the previous round's lists, ties broken by anchor
/// id; the lists are the one fixed point of such updates, so the order in
/// which entries are offered sets the rounds and the work, not the lists).
AnchorPaths nearest_anchor_paths(LocalizationProblem& prob, int k);

/// Collective: sum of |a - b| over sum of the shortest measured path a -> b,
/// over the anchor pairs that some sensor's list links (1 if none).
double path_correction(LocalizationProblem& prob, const AnchorPaths& paths);

/// Owned rows: each sensor multilaterated from its entries (distances times
/// `correction`); a sensor without any anchor entry keeps its row of `fallback`.
std::vector<double> multilaterate(const LocalizationProblem& prob, const AnchorPaths& paths, double correction,
                                  const std::vector<double>& fallback);

struct DvStartReport {
  std::int64_t rounds = 0;      ///< halo exchanges of the path search
  double correction = 1;        ///< path_correction()
  GlobalId without_anchor = 0;  ///< sensors with no anchor path (kept at their random start)
  double seconds = 0;           ///< all of it (rank 0's clock), and its steps:
  double paths_seconds = 0, correction_seconds = 0, multilateration_seconds = 0;
  std::int64_t mpi_bytes = 0;   ///< halo bytes of the path search, all ranks
};

/// Collective: the start, owned rows (sensors no anchor reaches: --init random's rows for `seed`).
std::vector<double> dv_initial_positions(LocalizationProblem& prob, std::uint64_t seed, DvStartReport* report);

}  // namespace snl
