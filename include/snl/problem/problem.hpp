#pragma once
// The localization problem on one rank: its part of the sensor graph (a
// DistGraph whose edge data are the ranges d_ij), the anchor measurements of
// its owned sensors, truth rows, and maps between file (block) order and the
// solver's local order.
#include <mpi.h>

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "snl/graph/dist_graph.hpp"
#include "snl/io/network.hpp"
#include "snl/problem/weights.hpp"

namespace snl {

struct ProblemReport {
  MergeStats merged;                ///< duplicate rows merged (global)
  PartitionStats partition;
  GlobalId num_sensor_edges = 0;    ///< after merging (global)
  GlobalId num_anchor_edges = 0;
  GlobalId unanchored = 0;          ///< sensors in components with no anchor measurement
  GlobalId few_measurements = 0;    ///< sensors with fewer than p+1 measurements
  GlobalId unlocalizable = 0;       ///< sensors flagged by either test or by the file's report
  std::vector<GlobalId> unlocalizable_sample;  ///< the first (up to 20) such ids
  /// Setup time by phase (rank 0's clock, after a barrier-free pass): merge,
  /// partition, graph (with the graph's own phases), anchors, connectivity.
  std::vector<std::pair<std::string, double>> setup_phases;
  /// This rank's accounting of the setup's largest structures, in bytes:
  /// measurements (after merging), partition (the partitioner's graph),
  /// directory (the owner directory), graph_build (DistGraph's temporaries).
  std::vector<std::pair<std::string, std::int64_t>> setup_bytes;
};

class LocalizationProblem {
 public:
  /// Collective. `slab` is this rank's slab of a validated network file
  /// (read_network). Duplicate measurements are merged, the sensor graph is
  /// partitioned and distributed, and anchors/truth move to the owners.
  LocalizationProblem(MPI_Comm comm, const Network& slab, PartitionMethod method, ProblemReport* report);
  /// The same from a slab moved in: its measurement lists are freed once they
  /// are merged (at 10M sensors on 2 ranks, 1 GB per rank that the rest of
  /// the setup then reuses instead of faulting fresh pages).
  LocalizationProblem(MPI_Comm comm, Network&& slab, PartitionMethod method, ProblemReport* report);

  MPI_Comm comm() const { return graph_.comm(); }
  int dim() const { return dim_; }
  GlobalId num_sensors() const { return graph_.num_global(); }
  GlobalId num_anchors() const { return static_cast<GlobalId>(anchors_.size()) / dim_; }
  DistGraph& graph() { return graph_; }
  const DistGraph& graph() const { return graph_; }
  LocalId num_owned() const { return graph_.num_owned(); }
  LocalId num_local() const { return graph_.num_local(); }

  const std::vector<double>& anchors() const { return anchors_; }
  /// Anchor measurements of owned node v: [anchor_offsets()[v], [v+1]), sorted by anchor id.
  const std::vector<std::int64_t>& anchor_offsets() const { return anchor_offsets_; }
  const std::vector<std::int32_t>& anchor_ids() const { return anchor_ids_; }
  const std::vector<double>& anchor_ranges() const { return anchor_ranges_; }

  bool has_truth() const { return has_truth_; }
  const std::vector<double>& truth() const { return truth_; }      ///< owned rows
  const std::vector<std::uint8_t>& flags() const { return flags_; }  ///< owned rows, LocalizabilityFlag bits
  std::optional<double> sigma() const { return sigma_; }

  /// The file's sigmas after merging: per CSR slot of the owned nodes and per
  /// anchor measurement; empty unless the file has sensor_sigmas / anchor_sigmas.
  bool has_sensor_sigmas() const { return has_sensor_sigmas_; }
  bool has_anchor_sigmas() const { return has_anchor_sigmas_; }
  const std::vector<double>& sensor_sigmas() const { return sensor_sigmas_; }
  const std::vector<double>& anchor_sigmas() const { return anchor_sigmas_; }
  /// The weights and loss every method and cost uses (weights.hpp); the
  /// unweighted l2 model until set. Collective (weights.cpp); throws
  /// snl::Error (on every rank) when the file lacks the sigmas `spec` needs.
  void set_measurement_model(const WeightsSpec& spec, double huber_delta);
  const MeasurementModel& model() const { return model_; }

  int max_degree() const { return delta_max_; }            ///< delta_max (global)
  int max_anchor_degree() const { return max_anchor_deg_; }  ///< max_i |A_i| (global)

  /// Bytes held by this rank's problem arrays (capacities; graph included).
  std::int64_t memory_bytes() const;

  /// Internal: arrays derived from the problem that the phases of a solve
  /// share instead of building each their own (the kernels' lane layout,
  /// detail::shared_lanes), made by their first user and dropped when the
  /// ranges change (resample_ranges).
  std::shared_ptr<void>& derived_cache() const { return derived_cache_; }

  /// Monte Carlo over noise: replaces every range by |true distance +
  /// sigma N(0,1)| (003 eq. 28), the noise keyed by (seed, pair) so that both
  /// ends of an edge and any number of ranks draw the same value. Needs truth.
  void resample_ranges(double sigma, std::uint64_t seed);

  /// Rows in file order [row_offset, row_offset + rows) on this rank (any
  /// contiguous slabs that tile [0, n)) -> owned rows in local order.
  std::vector<double> file_rows_to_owned(const std::vector<double>& rows, GlobalId row_offset, int width) const;
  /// Owned rows (local order) -> this rank's block of rows in file order
  /// (block_range); row_offset receives the first row.
  std::vector<double> owned_to_file_rows(const double* owned, int width, GlobalId* row_offset) const;

 private:
  // The constructor's steps (problem.cpp), in this order.
  // `consumed`: the slab itself when it may be emptied of its measurements after the merge.
  void build(MPI_Comm comm, const Network& slab, Network* consumed, PartitionMethod method, ProblemReport* report);
  void distribute_anchors(MPI_Comm comm, const OwnerDirectory& owners, const std::vector<GlobalId>& aedges,
                          const std::vector<double>& aranges, const std::vector<double>& asigmas);
  void read_owned_rows(MPI_Comm comm, const OwnerDirectory& owners, const Network& slab);
  std::vector<std::uint8_t> unanchored_owned(MPI_Comm comm);
  void flag_sensors(MPI_Comm comm, const std::vector<std::uint8_t>& unanchored, ProblemReport& rep);
  int dim_ = 2;
  DistGraph graph_;
  std::vector<double> anchors_;
  std::vector<std::int64_t> anchor_offsets_;
  std::vector<std::int32_t> anchor_ids_;
  std::vector<double> anchor_ranges_;
  bool has_truth_ = false;
  std::vector<double> truth_;
  std::vector<std::uint8_t> flags_;
  std::optional<double> sigma_;
  bool has_sensor_sigmas_ = false, has_anchor_sigmas_ = false;
  std::vector<double> sensor_sigmas_, anchor_sigmas_;
  MeasurementModel model_;
  int delta_max_ = 0, max_anchor_deg_ = 0;
  mutable std::shared_ptr<void> derived_cache_;
};

}  // namespace snl
