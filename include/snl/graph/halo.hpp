#pragma once
// Halo exchange plan (after HPCG SetupHalo/ExchangeHalo and PETSc's PetscSF):
// built once from the graph, then every iteration calls begin() -> interior
// work -> end() -> boundary work. Buffers and persistent requests live here;
// an exchange allocates nothing.
#include <mpi.h>

#include <cstdint>
#include <vector>

#include "snl/core/common.hpp"

namespace snl {

class HaloPlan {
 public:
  HaloPlan() = default;
  /// comm: the communicator of the messages, used as it is (not freed; the
  /// owning DistGraph passes its own duplicate). neighbor_ranks: ranks we
  /// exchange with (sorted). send_ids[r]: owned local
  /// ids whose values go to neighbor_ranks[r], in the receiver's ghost order.
  /// recv_offset[r], recv_count[r]: ghost slots [n_owned + offset, +count) that
  /// neighbor_ranks[r] fills. max_width: most doubles per node ever exchanged.
  HaloPlan(MPI_Comm comm, LocalId n_owned, std::vector<int> neighbor_ranks,
           std::vector<std::vector<LocalId>> send_ids, std::vector<LocalId> recv_offset,
           std::vector<LocalId> recv_count, int max_width);
  ~HaloPlan();
  HaloPlan(const HaloPlan&) = delete;
  HaloPlan& operator=(const HaloPlan&) = delete;
  HaloPlan(HaloPlan&& o) noexcept;
  HaloPlan& operator=(HaloPlan&& o) noexcept;

  /// Packs the owned rows of `field` (row-major, `width` doubles per local
  /// node) and starts the sends and receives. One exchange at a time: throws
  /// snl::Error while one is in flight (begin() without its end()).
  void begin(const double* field, int width);
  /// Completes the exchange and writes the ghost rows of `field`. Throws
  /// snl::Error without a begin() before it.
  void end(double* field, int width);
  /// Whether begin() has run without its end().
  bool in_flight() const { return in_flight_; }
  /// begin + end.
  void exchange(double* field, int width) {
    begin(field, width);
    end(field, width);
  }

  int num_neighbors() const { return static_cast<int>(neighbors_.size()); }
  const std::vector<int>& neighbor_ranks() const { return neighbors_; }
  /// The plan's communicator (not owned by the plan).
  MPI_Comm comm() const { return comm_; }
  LocalId num_owned() const { return n_owned_; }
  /// The owned local ids sent to neighbor_ranks()[r], in the receiver's ghost order.
  const LocalId* send_ids(int r) const { return send_ids_.data() + send_begin_[r]; }
  LocalId send_count(int r) const { return static_cast<LocalId>(send_begin_[r + 1] - send_begin_[r]); }
  /// Ghost slots [num_owned() + recv_offset(r), + recv_count(r)) come from neighbor_ranks()[r].
  LocalId recv_offset(int r) const { return recv_offset_[r]; }
  LocalId recv_count(int r) const { return recv_count_[r]; }
  /// Number of owned nodes sent to some rank, with multiplicity.
  std::int64_t send_volume() const { return send_total_; }
  std::int64_t recv_volume() const { return recv_total_; }
  /// Cumulative counters of this rank.
  std::int64_t messages_sent() const { return messages_sent_; }
  std::int64_t bytes_sent() const { return bytes_sent_; }
  double wait_seconds() const { return wait_seconds_; }
  /// Bytes held by the plan's arrays (capacities).
  std::int64_t memory_bytes() const {
    return static_cast<std::int64_t>(send_ids_.capacity() * sizeof(LocalId) +
                                     send_begin_.capacity() * sizeof(std::int64_t) +
                                     (recv_offset_.capacity() + recv_count_.capacity()) * sizeof(LocalId) +
                                     (send_buf_.capacity() + recv_buf_.capacity()) * sizeof(double));
  }
  void reset_counters() { messages_sent_ = bytes_sent_ = 0; wait_seconds_ = 0; }

 private:
  void free_requests();
  void make_requests(int width);

  MPI_Comm comm_ = MPI_COMM_NULL;
  LocalId n_owned_ = 0;
  int max_width_ = 0;
  std::vector<int> neighbors_;
  std::vector<LocalId> send_ids_;         // concatenated send lists
  std::vector<std::int64_t> send_begin_;  // [num_neighbors + 1] into send_ids_
  std::vector<LocalId> recv_offset_, recv_count_;
  std::int64_t send_total_ = 0, recv_total_ = 0;
  std::vector<double> send_buf_, recv_buf_;
  // Persistent requests per width (index width-1), created on first use.
  std::vector<std::vector<MPI_Request>> requests_;
  int active_width_ = 0;
  bool in_flight_ = false;
  std::int64_t messages_sent_ = 0, bytes_sent_ = 0;
  double wait_seconds_ = 0;
};

/// A plan's send and receive lists as flat arrays, with each owned row's
/// places in the send lists: what the halos that send only changed rows
/// (DeltaHalo, FreeHalo) mark and pack by.
struct HaloRowIndex {
  HaloRowIndex() = default;
  explicit HaloRowIndex(const HaloPlan& plan);
  std::vector<LocalId> send_ids;          ///< concatenated send lists (the plan's)
  std::vector<std::int64_t> send_begin;   ///< [num_neighbors + 1] into send_ids
  std::vector<LocalId> recv_offset, recv_count;
  std::vector<std::int64_t> mark_begin;   ///< [n_owned + 1] into mark_rank / mark_slot
  std::vector<int> mark_rank;             ///< the neighbours an owned row goes to ...
  std::vector<LocalId> mark_slot;         ///< ... and its place in their send list
  std::int64_t bytes() const {
    return static_cast<std::int64_t>((send_ids.capacity() + recv_offset.capacity() + recv_count.capacity() +
                                      mark_slot.capacity()) * sizeof(LocalId) +
                                     (send_begin.capacity() + mark_begin.capacity()) * sizeof(std::int64_t) +
                                     mark_rank.capacity() * sizeof(int));
  }
};

}  // namespace snl
