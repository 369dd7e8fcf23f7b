#pragma once
// Internal to the graph layer: the directory slots of the neighbours that a
// rank's block rows name, for the rows' routing (row_routing.cpp).
#include <mpi.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "graph/partition_detail.hpp"
#include "snl/core/mpi_util.hpp"
#include "snl/graph/partition.hpp"

namespace snl::graph_build {

// Step 1a: the directory slots of the rows' neighbours outside this rank's
// block. From a block that the rows name at least half as often as it has
// nodes, its whole block of slots (no ids sent: at 10M on 2 ranks each rank
// names the other's 5M nodes 40M times); from the others, the slots of the
// named ids, asked in the order the pack reads them (at(u) hands them out in
// that order). Collective.
template <class Id>
class NeighbourSlots {
 public:
  NeighbourSlots(MPI_Comm comm, const OwnerDirectory& dir, const std::vector<Id>& nbr)
      : dir_(dir), blocks_(dir.num_global(), comm_size(comm)), rank_(comm_rank(comm)) {
    const int size = blocks_.size();
    refs_.assign(static_cast<std::size_t>(size), 0);
    for (const Id u : nbr) ++refs_[blocks_.of(static_cast<GlobalId>(u))];
    dense_.assign(static_cast<std::size_t>(size), 0);
    for (int r = 0; r < size; ++r)
      dense_[r] = r != rank_ && 2 * refs_[r] >= blocks_.first[r + 1] - blocks_.first[r];
    const char* e = std::getenv("SNL_TEST_SETUP_SLOTS");  // tests: "ask" or "block" for every block
    if (e && std::strcmp(e, "ask") == 0) std::fill(dense_.begin(), dense_.end(), 0);
    if (e && std::strcmp(e, "block") == 0)
      for (int r = 0; r < size; ++r) dense_[r] = r != rank_;
  }
  bool asks() const {
    for (int r = 0; r < blocks_.size(); ++r)
      if (r != rank_ && !dense_[r] && refs_[r] > 0) return true;
    return false;
  }
  // Whether u's slot must be asked for (of block r): the caller lists such
  // ids in the order pack_rows reads them.
  bool asked(GlobalId u, int& r) const {
    r = blocks_.of(u);
    return r != rank_ && !dense_[r];
  }
  // The exchange: `ask[r]` holds the ids asked of block r, in pack order.
  void exchange(MPI_Comm comm, std::vector<std::vector<Id>>& ask);
  // u's slot; asked ids are answered in the order they were asked. A block
  // held whole (this rank's, or one sent whole) is read through its base
  // (whole_), without a branch on which it is: at 10M on 2 ranks the
  // neighbours fall in either block at random.
  const OwnerDirectory::Slot& at(GlobalId u) {
    const int r = blocks_.of(u);
    if (const OwnerDirectory::Slot* b = whole_[r]) return b[u - blocks_.first[r]];
    return got_[static_cast<std::size_t>(from_[r] + next_[r]++)];
  }
  // Where u's slot will be read, for a prefetch (asked slots are read in
  // order: their block's first answer does). The caller issues the prefetch:
  // GCC found a member function around it pure and dropped the call.
  const void* address(GlobalId u) const {
    const int r = blocks_.of(u);
    if (const OwnerDirectory::Slot* b = whole_[r]) return b + (u - blocks_.first[r]);
    return got_.data() + from_[r];
  }
  std::int64_t memory_bytes() const { return static_cast<std::int64_t>(got_.capacity() * sizeof(got_[0])); }

 private:
  const OwnerDirectory& dir_;
  detail::Blocks blocks_;
  int rank_;
  std::vector<std::int64_t> refs_, from_, next_;
  std::vector<char> dense_;
  std::vector<OwnerDirectory::Slot> got_;
  std::vector<const OwnerDirectory::Slot*> whole_;  // per block: its first node's slot where held whole, else null
};

}  // namespace snl::graph_build
