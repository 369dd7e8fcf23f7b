// OwnerDirectory: each node's owner, held by the block holder of its id, and
// each rank's owned nodes in the order of their keys.
#include <algorithm>
#include <limits>
#include <numeric>

#include "graph/partition_detail.hpp"
#include "snl/core/mpi_util.hpp"
#include "snl/graph/dist_graph.hpp"
#include "snl/graph/partition.hpp"
#include "snl/io/network.hpp"

namespace snl {

namespace {
// Key histograms of more entries fall back to global-id order (keys ignored).
constexpr long long kMaxKeyBins = 1LL << 22;
}  // namespace

OwnerDirectory::OwnerDirectory(MPI_Comm comm, GlobalId n, const std::vector<int>& owners,
                               const std::vector<std::int32_t>& keys)
    : comm_(comm), n_(n) {
  const MPI_Comm c = comm_.get();
  const int size = comm_size(c);
  GlobalId e;
  block_range(n, size, comm_rank(c), begin_, e);
  if (static_cast<GlobalId>(owners.size()) != e - begin_ || (!keys.empty() && keys.size() != owners.size()))
    throw Error("internal error: owner block of wrong size");
  // A node's index on its owner: the owner's nodes in lower blocks (an
  // exclusive scan), then its place among the owner's nodes of this block in
  // (key, global id) order: block by block, so that a block holder sends an
  // owner's rows in the owner's index order and the owner receives them in
  // place (DistGraph). Bins (owner, key) laid out owner by owner, keys 0..max
  // of that owner in this block; without keys, or with more bins than
  // kMaxKeyBins, one bin per owner.
  std::vector<long long> per_owner(size, 0), base(size, 0);
  for (const int o : owners) ++per_owner[o];
  MPI_Exscan(per_owner.data(), base.data(), size, MPI_LONG_LONG, MPI_SUM, c);
  if (comm_rank(c) == 0) std::fill(base.begin(), base.end(), 0);  // Exscan leaves rank 0's undefined
  std::vector<long long> kmax(size, 0);
  for (std::size_t t = 0; t < keys.size(); ++t) kmax[owners[t]] = std::max<long long>(kmax[owners[t]], keys[t]);
  std::vector<long long> first(static_cast<std::size_t>(size) + 1, 0);
  for (int o = 0; o < size; ++o) first[o + 1] = first[o] + kmax[o] + 1;
  const bool keyed = !keys.empty() && first[size] <= kMaxKeyBins;
  if (!keyed)
    for (int o = 0; o < size; ++o) first[o + 1] = o + 1;
  auto bin = [&](std::size_t t) { return first[owners[t]] + (keyed ? keys[t] : 0); };
  std::vector<long long> next(static_cast<std::size_t>(first[size]), 0);
  for (std::size_t t = 0; t < owners.size(); ++t) ++next[bin(t)];
  for (int o = 0; o < size; ++o)
    for (long long b = first[o], below = base[o]; b < first[o + 1]; ++b) {
      const long long k = next[b];
      next[b] = below;
      below += k;
    }
  slots_.resize(owners.size());
  for (std::size_t t = 0; t < owners.size(); ++t) {
    const long long i = next[bin(t)]++;
    if (i > std::numeric_limits<LocalId>::max())
      throw Error("too many sensors on one rank for 32-bit local ids; use more ranks");
    slots_[t] = {owners[t], static_cast<std::int32_t>(i)};
  }
}

OwnerDirectory OwnerDirectory::from_dense(MPI_Comm comm, GlobalId n, const std::vector<int>& owner) {
  GlobalId b, e;
  block_range(n, comm_size(comm), comm_rank(comm), b, e);
  return OwnerDirectory(comm, n, std::vector<int>(owner.begin() + b, owner.begin() + e));
}

std::vector<GlobalId> OwnerDirectory::owned_nodes(std::vector<std::int32_t>* by_gid) const {
  // Each block sends its nodes, with their indices, to their owners in one
  // exchange; blocks arrive in rank order, each ascending, so the
  // concatenation is in global id order.
  struct Node {
    GlobalId g;
    std::int32_t index;
  };
  const MPI_Comm c = comm_.get();
  const int size = comm_size(c);
  std::vector<std::vector<Node>> out(size);
  {  // counted first: no reallocation
    std::vector<std::size_t> cnt(size, 0);
    for (const Slot& s : slots_) ++cnt[s.owner];
    for (int r = 0; r < size; ++r) out[r].reserve(cnt[r]);
  }
  for (std::size_t t = 0; t < slots_.size(); ++t)
    out[slots_[t].owner].push_back({begin_ + static_cast<GlobalId>(t), slots_[t].index});
  const std::vector<Node> got = exchange_records(c, out);
  std::vector<GlobalId> owned(got.size());
  if (by_gid) by_gid->resize(got.size());
  for (std::size_t t = 0; t < got.size(); ++t) {
    owned[static_cast<std::size_t>(got[t].index)] = got[t].g;
    if (by_gid) (*by_gid)[t] = got[t].index;
  }
  return owned;
}

std::vector<GlobalId> OwnerDirectory::counts() const {
  const int size = comm_size(comm_.get());
  std::vector<long long> cnt(size, 0), tot(size, 0);
  for (const Slot& s : slots_) ++cnt[s.owner];
  MPI_Allreduce(cnt.data(), tot.data(), size, MPI_LONG_LONG, MPI_SUM, comm_.get());
  return std::vector<GlobalId>(tot.begin(), tot.end());
}

std::vector<int> OwnerDirectory::gather_dense() const {
  const MPI_Comm c = comm_.get();
  const int size = comm_size(c);
  std::vector<int> mine(slots_.size()), counts(size), displs(size);
  for (std::size_t t = 0; t < slots_.size(); ++t) mine[t] = slots_[t].owner;
  for (int r = 0; r < size; ++r) {
    GlobalId b, e;
    block_range(n_, size, r, b, e);
    counts[r] = static_cast<int>(e - b);
    displs[r] = static_cast<int>(b);
  }
  if (n_ > std::numeric_limits<int>::max()) throw Error("gather_dense: more than 2^31 nodes");
  std::vector<int> all(static_cast<std::size_t>(n_));
  MPI_Allgatherv(mine.data(), static_cast<int>(mine.size()), MPI_INT, all.data(), counts.data(), displs.data(), MPI_INT,
                 c);
  return all;
}

}  // namespace snl
