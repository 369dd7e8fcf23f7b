#pragma once
// Internal to the graph layer (not installed): what DistGraph's build
// (dist_graph.cpp) hands between its steps, and the steps kept in files of
// their own: the rows routed to their owners (row_routing.cpp, with the
// neighbour-slot directory of neighbour_slots.hpp) and the local order
// (local_order.cpp).
#include <mpi.h>

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/phase_clock.hpp"
#include "snl/core/common.hpp"
#include "snl/graph/dist_graph.hpp"

namespace snl::graph_build {

// One neighbour of an owned node: its global id and directory slot
// (OwnerDirectory::Slot), so that no later pass reads the edge records again.
template <class Id>
struct Entry {
  Id nbr;
  std::int32_t owner, index;
};

// The owned nodes and their neighbour lists, indexed by position in `owned`
// (the directory's owner-side index), before the local numbering.
template <class Id>
struct OwnedLists {
  std::vector<GlobalId> owned;    // owned nodes in owner-side index order
  std::vector<std::int32_t> by_gid;  // their owner-side indices in ascending global id
  std::vector<std::int64_t> cnt;  // owned index v: entries [cnt[v], cnt[v + 1])
  std::vector<Entry<Id>> entries;  // per node sorted by neighbour global id
  std::vector<char> boundary;     // owned index v has a neighbour on another rank
  int rank = 0;
  std::int64_t peak_bytes = 0;    // the step's temporaries at their largest
  std::int32_t nbr_owner(std::int64_t k) const { return entries[k].owner; }
  std::int32_t nbr_index(std::int64_t k) const { return entries[k].index; }
};

// A row's header on its way to its owner: the node, its degree and, in a
// second order, an owner-side index (see plan_rows).
struct RowHeader {
  GlobalId g;
  std::int32_t degree, by_gid;
};

// Where a block holder's rows go. The directory numbers an owner's nodes
// block by block (OwnerDirectory), so this rank's rows for owner o take
// consecutive indices there: in the owner's index order ("pack order"),
// owner by owner, they are pack positions first[o] .. first[o + 1]. Each
// owner's part (its entries from this rank, in pack order) is sent as it
// lands in the owner's lists.
struct RowPlan {
  std::vector<std::int64_t> rows_to, ents_to, first;  // per owner: rows, entries; first pack position
  std::vector<RowHeader> hdr;  // by pack position: node and degree; by_gid: the owner's k-th node of this block by id
  std::vector<std::int32_t> row;      // by pack position: the block row
  std::vector<std::int64_t> within;   // by pack position: the row's first entry within its owner's part
};

// The entries leaving for other owners go in rounds: round c carries entries
// [c * per_owner, (c + 1) * per_owner) of every owner's part, so that the
// send and receive buffers stay small (64 MiB of entries per rank) beside the
// rows and the lists (a send buffer of all leaving entries was the build's
// high-water mark). per_owner and count are the same on every rank.
struct Rounds {
  std::int64_t per_owner = 1;
  int count = 0;
  std::int64_t piece(std::int64_t total, int c) const {  // entries of a part of `total` in round c
    return std::clamp<std::int64_t>(total - c * per_owner, 0, per_owner);
  }
  // A round's entries at most, parts of `total` (per rank; not this rank's own).
  std::int64_t largest(const std::vector<std::int64_t>& total, int rank) const {
    std::int64_t sum = 0;
    for (std::size_t r = 0; r < total.size(); ++r)
      if (static_cast<int>(r) != rank) sum += std::min(total[r], per_owner);
    return sum;
  }
};

// Step 1 (row_routing.cpp): every block row to the owner of its node, with
// its neighbours' directory slots.
template <class Id>
OwnedLists<Id> rows_to_owners(MPI_Comm comm, const OwnerDirectory& dir, const BlockRows& R, std::vector<Id>& nbr,
                              RowPlan& P, std::vector<std::int64_t>& seg, Rounds& rd, GlobalId& cut,
                              PhaseClock& clock);

// Step 3 (local_order.cpp): owned indices in local order, interior then
// boundary.
template <class Id>
std::vector<std::int64_t> local_order(const OwnedLists<Id>& L, LocalOrdering ordering, LocalId& n_interior,
                                      std::vector<std::int32_t>& spare);

// Step 6 (row_routing.cpp): the rows' values to the owners, straight into
// the CSR's edge values.
void values_to_csr(MPI_Comm comm, const RowPlan& P, const Rounds& rd, const BlockRows& R,
                   const std::vector<std::int64_t>& cnt, const std::vector<std::int64_t>& seg,
                   const std::vector<LocalId>& owned_to_local, const std::vector<std::int64_t>& offsets,
                   std::vector<double>& values, std::int64_t& peak);

}  // namespace snl::graph_build
