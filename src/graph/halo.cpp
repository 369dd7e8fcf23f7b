#include "snl/graph/halo.hpp"

#include <algorithm>
#include <cstring>
#include <utility>

namespace snl {

namespace {
// The tag of every halo message; the plan's communicator is its graph's own
// duplicate (DistGraph), so no other traffic can match it.
constexpr int kHaloTag = 7401;
}

HaloPlan::HaloPlan(MPI_Comm comm, LocalId n_owned, std::vector<int> neighbor_ranks,
                   std::vector<std::vector<LocalId>> send_ids, std::vector<LocalId> recv_offset,
                   std::vector<LocalId> recv_count, int max_width)
    : comm_(comm),
      n_owned_(n_owned),
      max_width_(max_width),
      neighbors_(std::move(neighbor_ranks)),
      recv_offset_(std::move(recv_offset)),
      recv_count_(std::move(recv_count)) {
  send_begin_.assign(neighbors_.size() + 1, 0);
  for (std::size_t r = 0; r < neighbors_.size(); ++r) send_begin_[r + 1] = send_begin_[r] + send_ids[r].size();
  send_ids_.reserve(send_begin_.back());
  for (auto& s : send_ids) send_ids_.insert(send_ids_.end(), s.begin(), s.end());
  send_total_ = send_begin_.back();
  recv_total_ = 0;
  for (auto c : recv_count_) recv_total_ += c;
  send_buf_.assign(static_cast<std::size_t>(send_total_) * max_width_, 0.0);
  recv_buf_.assign(static_cast<std::size_t>(recv_total_) * max_width_, 0.0);
  requests_.resize(max_width_);
}

HaloPlan::~HaloPlan() { free_requests(); }

HaloPlan::HaloPlan(HaloPlan&& o) noexcept { *this = std::move(o); }

HaloRowIndex::HaloRowIndex(const HaloPlan& plan) {
  const int nn = plan.num_neighbors();
  send_begin.assign(nn + 1, 0);
  for (int r = 0; r < nn; ++r) send_begin[r + 1] = send_begin[r] + plan.send_count(r);
  send_ids.reserve(send_begin.back());
  for (int r = 0; r < nn; ++r) send_ids.insert(send_ids.end(), plan.send_ids(r), plan.send_ids(r) + plan.send_count(r));
  for (int r = 0; r < nn; ++r) {
    recv_offset.push_back(plan.recv_offset(r));
    recv_count.push_back(plan.recv_count(r));
  }
  // Each owned row's (neighbour, slot) pairs, grouped by row.
  const LocalId n_owned = plan.num_owned();
  mark_begin.assign(std::size_t(n_owned) + 1, 0);
  for (LocalId v : send_ids) ++mark_begin[v + 1];
  for (LocalId v = 0; v < n_owned; ++v) mark_begin[v + 1] += mark_begin[v];
  mark_rank.resize(send_ids.size());
  mark_slot.resize(send_ids.size());
  std::vector<std::int64_t> fill(mark_begin.begin(), mark_begin.end() - 1);
  for (int r = 0; r < nn; ++r)
    for (auto t = send_begin[r]; t < send_begin[r + 1]; ++t) {
      const LocalId v = send_ids[t];
      mark_rank[fill[v]] = r;
      mark_slot[fill[v]++] = static_cast<LocalId>(t - send_begin[r]);
    }
}

HaloPlan& HaloPlan::operator=(HaloPlan&& o) noexcept {
  if (this != &o) {
    free_requests();
    comm_ = o.comm_;
    n_owned_ = o.n_owned_;
    max_width_ = o.max_width_;
    neighbors_ = std::move(o.neighbors_);
    send_ids_ = std::move(o.send_ids_);
    send_begin_ = std::move(o.send_begin_);
    recv_offset_ = std::move(o.recv_offset_);
    recv_count_ = std::move(o.recv_count_);
    send_total_ = o.send_total_;
    recv_total_ = o.recv_total_;
    // Persistent requests point into the buffers; moving a std::vector keeps
    // its storage, so the requests stay valid.
    send_buf_ = std::move(o.send_buf_);
    recv_buf_ = std::move(o.recv_buf_);
    requests_ = std::move(o.requests_);
    active_width_ = o.active_width_;
    in_flight_ = o.in_flight_;
    messages_sent_ = o.messages_sent_;
    bytes_sent_ = o.bytes_sent_;
    wait_seconds_ = o.wait_seconds_;
    o.requests_.clear();
    o.neighbors_.clear();
    o.active_width_ = 0;
    o.in_flight_ = false;
  }
  return *this;
}

void HaloPlan::free_requests() {
  for (auto& set : requests_)
    for (auto& r : set)
      if (r != MPI_REQUEST_NULL) MPI_Request_free(&r);
  requests_.clear();
}

void HaloPlan::make_requests(int width) {
  auto& set = requests_[width - 1];
  const int nn = num_neighbors();
  set.assign(2 * nn, MPI_REQUEST_NULL);
  std::int64_t recv_pos = 0;
  for (int r = 0; r < nn; ++r) {
    const int count = recv_count_[r] * width;
    MPI_Recv_init(recv_buf_.data() + recv_pos * width, count, MPI_DOUBLE, neighbors_[r], kHaloTag, comm_, &set[r]);
    recv_pos += recv_count_[r];
  }
  for (int r = 0; r < nn; ++r) {
    const int count = static_cast<int>(send_begin_[r + 1] - send_begin_[r]) * width;
    MPI_Send_init(send_buf_.data() + send_begin_[r] * width, count, MPI_DOUBLE, neighbors_[r], kHaloTag, comm_,
                  &set[nn + r]);
  }
}

void HaloPlan::begin(const double* field, int width) {
  // One exchange at a time: the buffers and requests are the plan's own, and a
  // second begin() would restart requests that are still active.
  if (in_flight_) throw Error("halo exchange: begin() called while an exchange is in flight (end() it first)");
  if (width < 1 || width > max_width_) throw Error("halo exchange width out of range");
  in_flight_ = true;
  if (neighbors_.empty()) return;
  auto& set = requests_[width - 1];
  if (set.empty()) make_requests(width);
  // Pack in send-list order (the receiver's ghost order).
  double* out = send_buf_.data();
  for (std::size_t t = 0; t < send_ids_.size(); ++t) {
    const double* src = field + static_cast<std::size_t>(send_ids_[t]) * width;
    for (int c = 0; c < width; ++c) out[c] = src[c];
    out += width;
  }
  MPI_Startall(static_cast<int>(set.size()), set.data());
  active_width_ = width;
  messages_sent_ += num_neighbors();
  bytes_sent_ += send_total_ * width * static_cast<std::int64_t>(sizeof(double));
}

void HaloPlan::end(double* field, int width) {
  if (!in_flight_) throw Error("halo exchange: end() called without a matching begin()");
  in_flight_ = false;
  if (neighbors_.empty()) return;
  if (width != active_width_) throw Error("halo end() width differs from begin()");
  auto& set = requests_[width - 1];
  const double t0 = MPI_Wtime();
  MPI_Waitall(static_cast<int>(set.size()), set.data(), MPI_STATUSES_IGNORE);
  wait_seconds_ += MPI_Wtime() - t0;
  // Ghosts from one rank are contiguous, in the order that rank packed them.
  std::int64_t pos = 0;
  for (int r = 0; r < num_neighbors(); ++r) {
    double* dst = field + (static_cast<std::size_t>(n_owned_) + recv_offset_[r]) * width;
    std::memcpy(dst, recv_buf_.data() + pos * width, sizeof(double) * recv_count_[r] * width);
    pos += recv_count_[r];
  }
  active_width_ = 0;
}

}  // namespace snl
