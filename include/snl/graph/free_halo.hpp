#pragma once
// Unsynchronised halo of changed rows (003's asynchronous method run for real,
// `--algorithm async --mode free`, docs/async.md): each rank marks the owned
// rows it changes (mark()) and, whenever it likes, flush() sends each
// neighbour rank the marked rows it holds as ghosts, with their current
// values, in a nonblocking message (MPI_Isend) if one of that neighbour's two
// send buffers is free; otherwise the rows stay marked and go later, with
// newer values. poll() applies every message that has arrived (one MPI_Irecv
// posted per neighbour) to the ghost rows. Messages between a pair arrive in
// order (MPI's non-overtaking rule), so a ghost row always moves forward.
// A session runs from open() to close(): close() sends each neighbour the rows
// still marked with a "last" flag and applies messages until every
// neighbour's last one has come, so afterwards every ghost row holds its
// owner's final value and no message is in flight (a consistent state: the
// stopping test, records and checkpoints read it). Buffers (two per neighbour
// for sends, one for receives, each sized for every row), requests and the
// communicator (a duplicate of the plan's) live here; nothing is allocated
// after construction.
#include <mpi.h>

#include <cstdint>
#include <vector>

#include "snl/core/common.hpp"
#include "snl/core/mpi_util.hpp"
#include "snl/graph/halo.hpp"

namespace snl {

class FreeHalo {
 public:
  FreeHalo() = default;
  /// Collective over plan.comm() (duplicates it). width: doubles per row.
  FreeHalo(const HaloPlan& plan, int width);
  FreeHalo(const FreeHalo&) = delete;
  FreeHalo& operator=(const FreeHalo&) = delete;
  FreeHalo(FreeHalo&&) noexcept = default;
  FreeHalo& operator=(FreeHalo&&) noexcept = default;
  ~FreeHalo();

  /// Starts a session: posts one receive per neighbour.
  void open();
  /// Owned row v changed: pending for every neighbour that holds it.
  void mark(LocalId v) {
    for (auto t = idx_.mark_begin[v]; t < idx_.mark_begin[v + 1]; ++t) {
      const int r = idx_.mark_rank[t];
      const auto idx = idx_.send_begin[r] + idx_.mark_slot[t];
      if (dirty_[idx]) continue;
      dirty_[idx] = 1;
      pending_[idx_.send_begin[r] + pending_count_[r]++] = idx_.mark_slot[t];
    }
  }
  /// Nonblocking: sends every neighbour with pending rows and a free send
  /// buffer those rows (values read from `field` now).
  void flush(const double* field);
  /// Nonblocking: applies every message that has arrived to the ghost rows of
  /// `field`; returns the number of messages applied.
  int poll(double* field);
  /// Ends the session (every rank of the neighbourhood must close): the rows
  /// still pending go with the "last" flag; returns once every neighbour's
  /// last message is applied and every send has completed.
  void close(double* field);

  int num_neighbors() const { return static_cast<int>(neighbors_.size()); }
  std::int64_t bytes_sent() const { return bytes_sent_; }
  std::int64_t messages_sent() const { return messages_sent_; }
  std::int64_t rows_sent() const { return rows_sent_; }
  std::int64_t memory_bytes() const;

 private:
  static constexpr int kSlots = 2;  // send buffers per neighbour
  bool send(int r, const double* field, bool last);
  void post_recv(int r);
  void apply(int r, double* field);

  DupComm comm_;
  int width_ = 0;
  LocalId n_owned_ = 0;
  std::vector<int> neighbors_;
  HaloRowIndex idx_;  // the plan's lists, flat, and each owned row's places in them
  std::vector<char> dirty_;               // [send list entries]: pending for that neighbour
  std::vector<LocalId> pending_;          // pending slots per neighbour, at idx_.send_begin[r]
  std::vector<LocalId> pending_count_;
  std::vector<double> send_buf_, recv_buf_;
  std::vector<std::int64_t> send_buf_begin_, recv_buf_begin_;  // [nn + 1]; a send buffer r, s at begin + s * size
  std::vector<MPI_Request> send_req_;     // [nn * kSlots]
  std::vector<MPI_Request> recv_req_;     // [nn]
  std::vector<char> last_seen_, last_sent_;
  bool open_ = false;
  std::int64_t bytes_sent_ = 0, messages_sent_ = 0, rows_sent_ = 0;
};

}  // namespace snl
