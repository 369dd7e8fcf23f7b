#include "snl/graph/delta_halo.hpp"

#include <algorithm>

namespace snl {

namespace {
// The tag of every message; the communicator is this object's own duplicate.
constexpr int kDeltaTag = 7402;
}  // namespace

DeltaHalo::DeltaHalo(const HaloPlan& plan, int width)
    : comm_(plan.comm()), width_(width), n_owned_(plan.num_owned()), neighbors_(plan.neighbor_ranks()), idx_(plan) {
  const int nn = num_neighbors();
  LocalId n_ghost = 0;
  for (int r = 0; r < nn; ++r) n_ghost = std::max(n_ghost, plan.recv_offset(r) + plan.recv_count(r));
  ghost_source_.assign(n_ghost, -1);
  for (int r = 0; r < nn; ++r)
    std::fill(ghost_source_.begin() + idx_.recv_offset[r], ghost_source_.begin() + idx_.recv_offset[r] + idx_.recv_count[r], r);
  dirty_.assign(n_owned_, 0);
  pending_.assign(idx_.send_ids.size(), 0);
  pending_begin_.assign(idx_.send_begin.begin(), idx_.send_begin.end() - 1);
  pending_count_.assign(nn, 0);
  buf_begin_send_.assign(nn + 1, 0);
  buf_begin_recv_.assign(nn + 1, 0);
  for (int r = 0; r < nn; ++r) {
    buf_begin_send_[r + 1] = buf_begin_send_[r] + 2 + std::int64_t(plan.send_count(r)) * (2 + width_);
    buf_begin_recv_[r + 1] = buf_begin_recv_[r] + 2 + std::int64_t(idx_.recv_count[r]) * (2 + width_);
  }
  send_buf_.assign(buf_begin_send_.back(), 0.0);
  recv_buf_.assign(buf_begin_recv_.back(), 0.0);
  requests_.assign(2 * nn, MPI_REQUEST_NULL);
  clock_.assign(nn, 0);
  active_.assign(nn, 0);
}

void DeltaHalo::reset(std::int64_t clock, std::int64_t stop) {
  if (in_flight_) throw Error("delta halo: reset() while an exchange is in flight");
  for (int r = 0; r < num_neighbors(); ++r) {
    for (LocalId j = 0; j < pending_count_[r]; ++j) dirty_[idx_.send_ids[idx_.send_begin[r] + pending_[pending_begin_[r] + j]]] = 0;
    pending_count_[r] = 0;
    clock_[r] = clock;
    active_[r] = 1;
  }
  active_pairs_ = num_neighbors();
  my_clock_ = clock;
  stop_ = stop;
}

void DeltaHalo::begin(const double* field, const std::int64_t* tags, std::int64_t clock) {
  if (in_flight_) throw Error("delta halo: begin() called while an exchange is in flight (end() it first)");
  in_flight_ = true;
  my_clock_ = clock;
  ++rounds_;
  const int nn = num_neighbors();
  for (int r = 0; r < nn; ++r) {
    if (!active_[r]) continue;
    MPI_Irecv(recv_buf_.data() + buf_begin_recv_[r], static_cast<int>(buf_begin_recv_[r + 1] - buf_begin_recv_[r]),
              MPI_DOUBLE, neighbors_[r], kDeltaTag, comm_.get(), &requests_[r]);
  }
  for (int r = 0; r < nn; ++r) {
    if (!active_[r]) continue;
    // [clock, count, then per row: its slot in the send list, its tag and its values]
    double* out = send_buf_.data() + buf_begin_send_[r];
    const LocalId cnt = pending_count_[r];
    out[0] = static_cast<double>(clock);
    out[1] = static_cast<double>(cnt);
    double* o = out + 2;
    const LocalId* ids = idx_.send_ids.data() + idx_.send_begin[r];
    const LocalId* slots = pending_.data() + pending_begin_[r];
    for (LocalId j = 0; j < cnt; ++j) {
      const LocalId v = ids[slots[j]];
      *o++ = static_cast<double>(slots[j]);
      *o++ = static_cast<double>(tags[v]);
      const double* src = field + std::size_t(v) * width_;
      for (int c = 0; c < width_; ++c) *o++ = src[c];
    }
    const int count = static_cast<int>(o - out);
    MPI_Isend(out, count, MPI_DOUBLE, neighbors_[r], kDeltaTag, comm_.get(), &requests_[nn + r]);
    ++messages_sent_;
    bytes_sent_ += std::int64_t(count) * std::int64_t(sizeof(double));
    rows_sent_ += cnt;
  }
  // The marks are spent: a row changed from here on goes in the next round.
  for (int r = 0; r < nn; ++r) {
    const LocalId* ids = idx_.send_ids.data() + idx_.send_begin[r];
    for (LocalId j = 0; j < pending_count_[r]; ++j) dirty_[ids[pending_[pending_begin_[r] + j]]] = 0;
  }
  // Rows marked for an inactive neighbour (none: a pair stops only when both
  // ends are at the stop clock, after which nothing changes) are dropped.
  std::fill(pending_count_.begin(), pending_count_.end(), 0);
}

void DeltaHalo::end(double* field, std::int64_t* tags) {
  if (!in_flight_) throw Error("delta halo: end() called without a matching begin()");
  in_flight_ = false;
  const int nn = num_neighbors();
  MPI_Waitall(static_cast<int>(requests_.size()), requests_.data(), MPI_STATUSES_IGNORE);
  for (int r = 0; r < nn; ++r) {
    if (!active_[r]) continue;
    const double* in = recv_buf_.data() + buf_begin_recv_[r];
    clock_[r] = static_cast<std::int64_t>(in[0]);
    const auto cnt = static_cast<LocalId>(in[1]);
    const double* q = in + 2;
    double* base = field + (std::size_t(n_owned_) + idx_.recv_offset[r]) * width_;
    for (LocalId j = 0; j < cnt; ++j) {
      const auto slot = static_cast<LocalId>(*q++);
      tags[std::size_t(n_owned_) + idx_.recv_offset[r] + slot] = static_cast<std::int64_t>(*q++);
      double* dst = base + std::size_t(slot) * width_;
      for (int c = 0; c < width_; ++c) dst[c] = *q++;
    }
    if (my_clock_ == stop_ && clock_[r] == stop_) {
      active_[r] = 0;
      --active_pairs_;
    }
  }
}

std::int64_t DeltaHalo::memory_bytes() const {
  return idx_.bytes() + static_cast<std::int64_t>(
      (pending_.capacity() + pending_count_.capacity()) * sizeof(LocalId) +
      (pending_begin_.capacity() + buf_begin_send_.capacity() + buf_begin_recv_.capacity() + clock_.capacity()) *
          sizeof(std::int64_t) +
      (ghost_source_.capacity() + neighbors_.capacity()) * sizeof(int) +
      dirty_.capacity() + active_.capacity() + (send_buf_.capacity() + recv_buf_.capacity()) * sizeof(double) +
      requests_.capacity() * sizeof(MPI_Request));
}

}  // namespace snl
