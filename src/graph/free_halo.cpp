#include "snl/graph/free_halo.hpp"

#include <algorithm>

namespace snl {

namespace {
// The tag of every message; the communicator is this object's own duplicate.
constexpr int kFreeTag = 7403;
}  // namespace

FreeHalo::FreeHalo(const HaloPlan& plan, int width)
    : comm_(plan.comm()), width_(width), n_owned_(plan.num_owned()), neighbors_(plan.neighbor_ranks()), idx_(plan) {
  const int nn = num_neighbors();
  dirty_.assign(idx_.send_ids.size(), 0);
  pending_.assign(idx_.send_ids.size(), 0);
  pending_count_.assign(nn, 0);
  // A message: [last, count, then per row its slot and its values].
  send_buf_begin_.assign(nn + 1, 0);
  recv_buf_begin_.assign(nn + 1, 0);
  for (int r = 0; r < nn; ++r) {
    send_buf_begin_[r + 1] = send_buf_begin_[r] + kSlots * (2 + std::int64_t(plan.send_count(r)) * (1 + width_));
    recv_buf_begin_[r + 1] = recv_buf_begin_[r] + 2 + std::int64_t(idx_.recv_count[r]) * (1 + width_);
  }
  send_buf_.assign(send_buf_begin_.back(), 0.0);
  recv_buf_.assign(recv_buf_begin_.back(), 0.0);
  send_req_.assign(std::size_t(nn) * kSlots, MPI_REQUEST_NULL);
  recv_req_.assign(nn, MPI_REQUEST_NULL);
  last_seen_.assign(nn, 0);
  last_sent_.assign(nn, 0);
}

FreeHalo::~FreeHalo() {
  int finalized = 1;
  MPI_Finalized(&finalized);
  if (finalized) return;
  // Left open only when an error unwinds a session (the run is ending).
  for (auto& q : recv_req_)
    if (q != MPI_REQUEST_NULL) {
      MPI_Cancel(&q);
      MPI_Request_free(&q);
    }
  for (auto& q : send_req_)
    if (q != MPI_REQUEST_NULL) MPI_Request_free(&q);
}

void FreeHalo::post_recv(int r) {
  MPI_Irecv(recv_buf_.data() + recv_buf_begin_[r], static_cast<int>(recv_buf_begin_[r + 1] - recv_buf_begin_[r]),
            MPI_DOUBLE, neighbors_[r], kFreeTag, comm_.get(), &recv_req_[r]);
}

void FreeHalo::open() {
  if (open_) throw Error("free halo: open() while a session is open");
  open_ = true;
  for (int r = 0; r < num_neighbors(); ++r) {
    last_seen_[r] = 0;
    last_sent_[r] = 0;
    post_recv(r);
  }
}

bool FreeHalo::send(int r, const double* field, bool last) {
  int s = 0;
  for (; s < kSlots; ++s) {
    MPI_Request& q = send_req_[std::size_t(r) * kSlots + s];
    if (q == MPI_REQUEST_NULL) break;
    int done = 0;
    MPI_Test(&q, &done, MPI_STATUS_IGNORE);
    if (done) break;
  }
  if (s == kSlots) return false;  // both buffers in flight: the rows wait (and get newer)
  const std::int64_t size = (send_buf_begin_[r + 1] - send_buf_begin_[r]) / kSlots;
  double* out = send_buf_.data() + send_buf_begin_[r] + s * size;
  const LocalId cnt = pending_count_[r];
  out[0] = last ? 1.0 : 0.0;
  out[1] = static_cast<double>(cnt);
  double* o = out + 2;
  const LocalId* ids = idx_.send_ids.data() + idx_.send_begin[r];
  const LocalId* slots = pending_.data() + idx_.send_begin[r];
  for (LocalId j = 0; j < cnt; ++j) {
    const double* src = field + std::size_t(ids[slots[j]]) * width_;
    *o++ = static_cast<double>(slots[j]);
    for (int c = 0; c < width_; ++c) *o++ = src[c];
  }
  for (LocalId j = 0; j < pending_count_[r]; ++j) dirty_[idx_.send_begin[r] + slots[j]] = 0;
  pending_count_[r] = 0;
  const int count = static_cast<int>(o - out);
  MPI_Isend(out, count, MPI_DOUBLE, neighbors_[r], kFreeTag, comm_.get(), &send_req_[std::size_t(r) * kSlots + s]);
  ++messages_sent_;
  bytes_sent_ += std::int64_t(count) * std::int64_t(sizeof(double));
  rows_sent_ += cnt;
  return true;
}

void FreeHalo::flush(const double* field) {
  for (int r = 0; r < num_neighbors(); ++r)
    if (pending_count_[r] > 0) send(r, field, false);
}

void FreeHalo::apply(int r, double* field) {
  const double* in = recv_buf_.data() + recv_buf_begin_[r];
  const auto cnt = static_cast<LocalId>(in[1]);
  const double* q = in + 2;
  double* base = field + (std::size_t(n_owned_) + idx_.recv_offset[r]) * width_;
  for (LocalId j = 0; j < cnt; ++j) {
    const auto slot = static_cast<LocalId>(*q++);
    double* dst = base + std::size_t(slot) * width_;
    for (int c = 0; c < width_; ++c) dst[c] = *q++;
  }
  if (in[0] != 0) last_seen_[r] = 1;
}

int FreeHalo::poll(double* field) {
  int applied = 0;
  for (int r = 0; r < num_neighbors(); ++r) {
    while (recv_req_[r] != MPI_REQUEST_NULL) {
      int done = 0;
      MPI_Test(&recv_req_[r], &done, MPI_STATUS_IGNORE);
      if (!done) break;
      apply(r, field);
      ++applied;
      if (!last_seen_[r]) post_recv(r);  // after its last message a neighbour sends nothing more
    }
  }
  return applied;
}

void FreeHalo::close(double* field) {
  if (!open_) throw Error("free halo: close() without open()");
  const int nn = num_neighbors();
  for (;;) {
    bool done = true;
    for (int r = 0; r < nn; ++r) {
      if (!last_sent_[r]) last_sent_[r] = send(r, field, true) ? 1 : 0;
      done = done && last_sent_[r] && last_seen_[r];
    }
    poll(field);
    if (done) break;
  }
  MPI_Waitall(static_cast<int>(send_req_.size()), send_req_.data(), MPI_STATUSES_IGNORE);
  open_ = false;
}

std::int64_t FreeHalo::memory_bytes() const {
  return idx_.bytes() + static_cast<std::int64_t>(
      (pending_.capacity() + pending_count_.capacity()) * sizeof(LocalId) +
      (send_buf_begin_.capacity() + recv_buf_begin_.capacity()) * sizeof(std::int64_t) +
      neighbors_.capacity() * sizeof(int) + dirty_.capacity() + last_seen_.capacity() +
      last_sent_.capacity() + (send_buf_.capacity() + recv_buf_.capacity()) * sizeof(double) +
      (send_req_.capacity() + recv_req_.capacity()) * sizeof(MPI_Request));
}

}  // namespace snl
