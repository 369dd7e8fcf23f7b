// The neighbour-slot directory's one exchange (NeighbourSlots).
#include "graph/neighbour_slots.hpp"

#include "snl/graph/dist_graph.hpp"

namespace snl::graph_build {

template <class Id>
void NeighbourSlots<Id>::exchange(MPI_Comm comm, std::vector<std::vector<Id>>& ask) {
  const int size = blocks_.size();
  // Per pair: whether the whole block is wanted, and how many ids are asked.
  std::vector<std::int64_t> want(2 * static_cast<std::size_t>(size)), wanted(want.size());
  for (int r = 0; r < size; ++r) {
    want[2 * r] = dense_[r];
    want[2 * r + 1] = static_cast<std::int64_t>(ask[r].size());
  }
  MPI_Alltoall(want.data(), 2, MPI_INT64_T, wanted.data(), 2, MPI_INT64_T, comm);
  std::vector<std::int64_t> qstart(static_cast<std::size_t>(size) + 1, 0);
  for (int r = 0; r < size; ++r) qstart[r + 1] = static_cast<std::int64_t>(ask[r].size());
  std::vector<int> qcount;
  pack_offsets(qstart, qcount, 1, "neighbour slots");
  std::vector<Id> qbuf;
  qbuf.reserve(static_cast<std::size_t>(qstart[size]));
  for (auto& a : ask) {
    qbuf.insert(qbuf.end(), a.begin(), a.end());
    release(a);
  }
  std::vector<int> rq;
  const std::vector<Id> questions = exchange_packed(comm, std::move(qbuf), qcount, &rq);
  // The answers: a whole block where it is wanted, else each asked id's slot.
  const std::int64_t nb = blocks_.first[rank_ + 1] - blocks_.first[rank_];
  std::vector<std::int64_t> astart(static_cast<std::size_t>(size) + 1, 0);
  for (int r = 0; r < size; ++r) astart[r + 1] = wanted[2 * r] ? nb : rq[r];
  std::vector<int> acount;
  pack_offsets(astart, acount, 2, "neighbour slots");
  std::vector<OwnerDirectory::Slot> abuf(static_cast<std::size_t>(astart[size]));
  for (std::size_t r = 0, q = 0, p = 0; r < static_cast<std::size_t>(size); q += static_cast<std::size_t>(rq[r++])) {
    if (wanted[2 * r])
      for (std::int64_t t = 0; t < nb; ++t) abuf[p++] = dir_.local(blocks_.first[rank_] + t);
    else
      for (int t = 0; t < rq[r]; ++t) abuf[p++] = dir_.local(static_cast<GlobalId>(questions[q + t]));
  }
  std::vector<int> rcount;
  got_ = exchange_packed(comm, std::move(abuf), acount, &rcount);
  from_.assign(static_cast<std::size_t>(size), 0);
  next_.assign(static_cast<std::size_t>(size), 0);
  for (int r = 1; r < size; ++r) from_[r] = from_[r - 1] + rcount[r - 1];
  whole_.assign(static_cast<std::size_t>(size), nullptr);
  for (int r = 0; r < size; ++r)
    if (r == rank_ && nb > 0) whole_[r] = &dir_.local(blocks_.first[r]);
    else if (dense_[r] && rcount[r] > 0) whole_[r] = got_.data() + from_[r];
}

template class NeighbourSlots<std::int32_t>;
template class NeighbourSlots<std::int64_t>;

}  // namespace snl::graph_build
