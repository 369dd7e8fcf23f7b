#pragma once
// The network: anchors, range measurements and (optionally) true positions,
// as stored in the HDF5 network file (docs/formats.md, shared spec v1).
// Implemented by src/io/network.cpp (reading and writing files) and
// src/io/validate.cpp (validation and merging, without MPI or HDF5: the fuzz
// target links it alone).
#include <mpi.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "snl/core/common.hpp"

namespace snl {

/// Localizability flags per sensor (bit mask), stored in the file as
/// dataset `localizability/flags` [n] uint8 when a report exists.
enum LocalizabilityFlag : std::uint8_t {
  kUnanchoredComponent = 1,  ///< its connected component has no anchor measurement
  kFewMeasurements = 2,      ///< fewer than p+1 measurements (sensor + anchor)
  kNotRigid = 4,             ///< the anchored framework is not infinitesimally rigid here
};

/// A network, or one rank's slab of it. For a whole network all offsets are 0
/// and the totals equal the local sizes. Row-major arrays.
struct Network {
  int dim = 2;                           ///< p
  GlobalId num_sensors = 0;              ///< n
  std::vector<double> anchors;           ///< [m * p], always complete on every rank
  std::vector<GlobalId> sensor_edges;    ///< [2 * E_local] pairs (i, j)
  std::vector<double> sensor_ranges;     ///< [E_local]
  std::vector<GlobalId> anchor_edges;    ///< [2 * Ea_local] pairs (i, k)
  std::vector<double> anchor_ranges;     ///< [Ea_local]
  bool has_truth = false;
  std::vector<double> truth;             ///< [rows * p] truth rows [truth_offset, ...)
  std::optional<double> sigma;           ///< noise standard deviation, when known
  std::vector<std::uint8_t> localizability;  ///< optional flags rows [truth_offset, ...) or empty
  // Optional per-measurement data (format version 1; older readers ignore them).
  // Each is empty when absent, else one value per row of its edge slab.
  std::vector<double> sensor_sigmas;      ///< [E_local] noise std of each sensor range (> 0)
  std::vector<double> anchor_sigmas;      ///< [Ea_local] noise std of each anchor range (> 0)
  std::vector<std::uint8_t> sensor_nlos;  ///< [E_local] 1 where the range is a non-line-of-sight outlier
  std::vector<std::uint8_t> anchor_nlos;  ///< [Ea_local] the same for anchor ranges

  // Slab bookkeeping (all zero / equal to the local sizes for a whole network).
  GlobalId sensor_edge_offset = 0;  ///< global row of sensor_edges[0]
  GlobalId anchor_edge_offset = 0;  ///< global row of anchor_edges[0]
  GlobalId sensor_row_offset = 0;   ///< global sensor id of the first truth/flags row held
  GlobalId total_sensor_edges = 0;  ///< E in the file
  GlobalId total_anchor_edges = 0;  ///< Ea in the file

  GlobalId num_anchors() const { return dim > 0 ? static_cast<GlobalId>(anchors.size()) / dim : 0; }
  GlobalId local_sensor_edges() const { return static_cast<GlobalId>(sensor_ranges.size()); }
  GlobalId local_anchor_edges() const { return static_cast<GlobalId>(anchor_ranges.size()); }
};

/// Checks every row-level rule of the spec on a network or slab held in memory
/// (shapes, index ranges, NaN/Inf, negative ranges, self-loops). Throws
/// snl::Error naming the dataset and the first offending (global) row.
/// Returns normally when valid. Pure function, no MPI (fuzzable).
void validate_network(const Network& net);

/// The first violation of a network or slab: its message (empty if valid) and a
/// key ordering violations by dataset (anchors, sensor_edges, sensor_ranges,
/// anchor_edges, anchor_ranges, truth, sigma, localizability) then by global
/// row, so that the collective reader reports the same "first" error on every rank.
struct NetworkIssue {
  std::int64_t key = 0;
  std::string message;
  bool ok() const { return message.empty(); }
};
/// whole == true: `net` must be a whole network (truth/flags have n rows).
/// whole == false: a slab (rows [sensor_row_offset, ...) of truth/flags).
/// validate_network(net) is check_network(net, whole) with whole decided from
/// the slab bookkeeping (all offsets 0 and totals 0 or equal to local sizes).
NetworkIssue check_network(const Network& net, bool whole);

/// Result of merging duplicate measurements.
struct MergeStats {
  GlobalId merged_sensor_pairs = 0;  ///< number of duplicate rows removed
  GlobalId merged_anchor_pairs = 0;
};

/// Merges duplicate measurements of the same pair (either order) by averaging
/// their ranges (seed 003, footnote 1). Sensor edges become canonical (i < j)
/// and are sorted by (i, j); anchor edges are sorted by (i, k). The average is
/// taken over the ranges sorted ascending, so the result does not depend on the
/// order of the input rows. In memory, no MPI (fuzzable).
MergeStats merge_duplicates(std::vector<GlobalId>& sensor_edges, std::vector<double>& sensor_ranges,
                            std::vector<GlobalId>& anchor_edges, std::vector<double>& anchor_ranges);

/// Per-row data that travels with the measurements through merge_duplicates.
/// Each vector is empty (absent) or has one value per row.
struct MeasurementExtras {
  std::vector<double>* sigmas = nullptr;       ///< merged by inverse-variance weighting
  std::vector<std::uint8_t>* nlos = nullptr;   ///< merged by logical or
};

/// merge_duplicates carrying per-row sigmas and NLOS flags. With sigmas, the
/// duplicates of a pair merge into the inverse-variance weighted mean of their
/// ranges, with sigma = (sum 1/sigma_k^2)^(-1/2) (the ML estimate of one range
/// from independent Gaussian readings); without, into the plain mean as above.
MergeStats merge_duplicates(std::vector<GlobalId>& sensor_edges, std::vector<double>& sensor_ranges,
                            MeasurementExtras sensor_extras, std::vector<GlobalId>& anchor_edges,
                            std::vector<double>& anchor_ranges, MeasurementExtras anchor_extras);

/// The merge of one pair's `count` readings, ascending in (range, sigma):
/// range k at ranges[k * stride], its sigma at sigmas[k * stride] (sigmas
/// null: none). Returns the merged range (merge_duplicates' rule, kept
/// within [min, max]); with sigmas, *sigma gets the combined sigma.
double merge_readings(const double* ranges, const double* sigmas, std::size_t count, std::size_t stride,
                      double* sigma);

/// Header of a network file: what is needed before reading the data.
struct NetworkHeader {
  int dim = 0;
  GlobalId num_sensors = 0;
  GlobalId num_anchors = 0;
  GlobalId num_sensor_edges = 0;
  GlobalId num_anchor_edges = 0;
  bool has_truth = false;
  std::optional<double> sigma;
  bool has_localizability = false;
  bool has_sensor_sigmas = false, has_anchor_sigmas = false;
  bool has_sensor_nlos = false, has_anchor_nlos = false;
};

/// Collective over comm. Reads the network file: anchors on every rank, and
/// each rank a contiguous block of rows of each per-row dataset (collective
/// hyperslab reads). Validates everything; on a violation every rank throws the
/// same snl::Error (the first offending row over all ranks). With
/// MPI_COMM_SELF this reads the whole network.
Network read_network(const std::string& path, MPI_Comm comm);

/// This rank's slab of a whole network held in memory: the same rows and
/// bookkeeping read_network would hand this rank for the same data.
Network network_slab(const Network& whole, MPI_Comm comm);

/// Whole network on the calling process (read_network on MPI_COMM_SELF).
Network read_network_serial(const std::string& path);

/// Writes a whole network (serial, from one process) atomically: a temporary
/// file next to `path` is renamed over it only once it is complete.
void write_network(const std::string& path, const Network& net);

/// Block distribution of `total` rows over `size` ranks: [begin, end) of `rank`.
inline void block_range(GlobalId total, int size, int rank, GlobalId& begin, GlobalId& end) {
  const GlobalId base = total / size, rem = total % size;
  begin = rank * base + (rank < rem ? rank : rem);
  end = begin + base + (rank < rem ? 1 : 0);
}

/// Owner rank of global row `row` under block_range.
inline int block_owner(GlobalId total, int size, GlobalId row) {
  const GlobalId base = total / size, rem = total % size;
  const GlobalId cut = rem * (base + 1);
  if (row < cut) return static_cast<int>(row / (base + 1));
  return static_cast<int>(rem + (row - cut) / (base > 0 ? base : 1));
}

}  // namespace snl
