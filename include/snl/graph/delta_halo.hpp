#pragma once
// Sparse halo exchange of the rows that changed (after PETSc's PetscSF with a
// leaf subset): built once from a HaloPlan, then every round marks the owned
// rows it changes (mark()) and exchange() sends each neighbour rank only the
// marked rows it holds as ghosts, each with an integer tag (the asynchronous
// replay: the row's version, the position of its last activation), and the
// sender's clock (an integer the client gives meaning to; the replay: 1 once
// it has done all its activations). A pair of ranks stops exchanging once both
// sent the stop clock in the same round (reset() arms it), so ranks may take
// different numbers of rounds. Buffers (sized for every row), requests and the
// communicator (a duplicate of the plan's) live here; an exchange allocates
// nothing.
#include <mpi.h>

#include <cstdint>
#include <vector>

#include "snl/core/common.hpp"
#include "snl/core/mpi_util.hpp"
#include "snl/graph/halo.hpp"

namespace snl {

class DeltaHalo {
 public:
  DeltaHalo() = default;
  /// Collective over plan.comm() (duplicates it). width: doubles per row.
  DeltaHalo(const HaloPlan& plan, int width);
  DeltaHalo(const DeltaHalo&) = delete;
  DeltaHalo& operator=(const DeltaHalo&) = delete;
  DeltaHalo(DeltaHalo&&) noexcept = default;
  DeltaHalo& operator=(DeltaHalo&&) noexcept = default;

  /// Every pair active, every neighbour's clock `clock`, nothing marked; the
  /// pairs stop after the round in which both ends send `stop`.
  void reset(std::int64_t clock, std::int64_t stop);
  /// Owned row v changed since the last exchange (a no-op for rows no rank holds).
  void mark(LocalId v) {
    if (idx_.mark_begin[v] == idx_.mark_begin[v + 1] || dirty_[v]) return;
    dirty_[v] = 1;
    for (auto t = idx_.mark_begin[v]; t < idx_.mark_begin[v + 1]; ++t) {
      const int r = idx_.mark_rank[t];
      pending_[pending_begin_[r] + pending_count_[r]++] = idx_.mark_slot[t];
    }
  }
  /// Collective over the active pairs: sends the marked rows of `field` with
  /// their `tags` (one per local row) and `clock` to the active neighbours,
  /// writes theirs into the ghost rows of `field` and `tags`, clears the marks.
  /// begin() -> (work that reads no ghost row) -> end().
  void begin(const double* field, const std::int64_t* tags, std::int64_t clock);
  void end(double* field, std::int64_t* tags);
  void exchange(double* field, std::int64_t* tags, std::int64_t clock) {
    begin(field, tags, clock);
    end(field, tags);
  }
  /// No pair active: every neighbour has sent the stop clock and so have we.
  bool done() const { return active_pairs_ == 0; }
  int num_neighbors() const { return static_cast<int>(neighbors_.size()); }
  /// The neighbour (index into the plan's neighbor_ranks()) that owns ghost g (a local id >= num_owned).
  int source_of(LocalId g) const { return ghost_source_[g - n_owned_]; }
  /// The last clock neighbour r sent (reset(): the common clock).
  std::int64_t clock_of(int r) const { return clock_[r]; }
  std::int64_t bytes_sent() const { return bytes_sent_; }
  std::int64_t messages_sent() const { return messages_sent_; }
  std::int64_t rounds() const { return rounds_; }
  std::int64_t rows_sent() const { return rows_sent_; }
  std::int64_t memory_bytes() const;

 private:
  DupComm comm_;
  int width_ = 0;
  LocalId n_owned_ = 0;
  std::vector<int> neighbors_;
  HaloRowIndex idx_;  // the plan's lists, flat, and each owned row's places in them
  std::vector<char> dirty_;                       // [n_owned]
  std::vector<LocalId> pending_;                  // marked slots per neighbour, at idx_.send_begin[r]
  std::vector<std::int64_t> pending_begin_;
  std::vector<LocalId> pending_count_;
  std::vector<int> ghost_source_;                 // [num ghosts]
  std::vector<double> send_buf_, recv_buf_;       // per neighbour: 2 + count * (2 + width)
  std::vector<std::int64_t> buf_begin_send_, buf_begin_recv_;
  std::vector<MPI_Request> requests_;             // [2 nn]
  std::vector<std::int64_t> clock_;
  std::vector<char> active_;
  int active_pairs_ = 0;
  std::int64_t my_clock_ = 0, stop_ = 0;
  bool in_flight_ = false;
  std::int64_t bytes_sent_ = 0, messages_sent_ = 0, rounds_ = 0, rows_sent_ = 0;
};

}  // namespace snl
