// Steps 1 and 6 of DistGraph's build: the block rows routed to the owners
// of their nodes in rounds of bounded size, first the entries with their
// neighbours' slots, then (once the CSR is laid out) the values.
#include <algorithm>
#include <cstdlib>
#include <limits>
#include <stdexcept>

#include "graph/graph_build.hpp"
#include "graph/neighbour_slots.hpp"
#include "snl/core/mpi_util.hpp"

namespace snl::graph_build {

namespace {

RowPlan plan_rows(const OwnerDirectory& dir, const BlockRows& R, int size) {
  const std::int64_t nb = R.num_rows();
  RowPlan P;
  P.rows_to.assign(static_cast<std::size_t>(size), 0);
  P.ents_to = P.rows_to;
  std::vector<std::int64_t> base(static_cast<std::size_t>(size), std::numeric_limits<std::int64_t>::max());
  for (std::int64_t t = 0; t < nb; ++t) {
    const auto& s = dir.local(R.begin + t);
    ++P.rows_to[s.owner];
    P.ents_to[s.owner] += R.offsets[t + 1] - R.offsets[t];
    base[s.owner] = std::min<std::int64_t>(base[s.owner], s.index);
  }
  P.first.assign(static_cast<std::size_t>(size) + 1, 0);
  for (int o = 0; o < size; ++o) P.first[o + 1] = P.first[o] + P.rows_to[o];
  std::vector<std::int64_t> seen(P.first.begin(), P.first.end() - 1);
  P.hdr.resize(static_cast<std::size_t>(nb));
  P.row.resize(static_cast<std::size_t>(nb));
  for (std::int64_t t = 0; t < nb; ++t) {
    const auto& s = dir.local(R.begin + t);
    const std::int64_t p = P.first[s.owner] + (s.index - base[s.owner]);
    if (s.index < base[s.owner] || p >= P.first[s.owner + 1])
      throw std::logic_error("graph build: an owner's indices of one block are not consecutive");
    P.row[static_cast<std::size_t>(p)] = static_cast<std::int32_t>(t);
    P.hdr[static_cast<std::size_t>(p)].g = R.begin + t;
    P.hdr[static_cast<std::size_t>(p)].degree = static_cast<std::int32_t>(R.offsets[t + 1] - R.offsets[t]);
    P.hdr[static_cast<std::size_t>(seen[s.owner]++)].by_gid = s.index;  // the k-th in global id order
  }
  P.within.resize(static_cast<std::size_t>(nb));
  for (int o = 0; o < size; ++o)
    for (std::int64_t p = P.first[o], a = 0; p < P.first[o + 1]; ++p) {
      P.within[static_cast<std::size_t>(p)] = a;
      a += P.hdr[static_cast<std::size_t>(p)].degree;
    }
  return P;
}

// The headers to the owners: each owner's nodes in index order, their
// degrees (the lists' offsets) and their indices by global id. Sets L.owned,
// L.by_gid, L.cnt; `seg[r]`: the first owned index of the rows block r sends.
template <class Id>
void receive_headers(MPI_Comm comm, RowPlan& P, OwnedLists<Id>& L, std::vector<std::int64_t>& seg) {
  const int size = comm_size(comm);
  std::vector<int> hcount(size), rrows;
  for (int o = 0; o < size; ++o) hcount[o] = static_cast<int>(P.rows_to[o]);
  const std::vector<RowHeader> got = exchange_packed(comm, std::move(P.hdr), hcount, &rrows);
  if (got.size() > static_cast<std::size_t>(std::numeric_limits<LocalId>::max()))
    throw Error("too many sensors on one rank for 32-bit local ids; use more ranks");
  L.owned.resize(got.size());
  L.by_gid.resize(got.size());
  L.cnt.assign(got.size() + 1, 0);
  for (std::size_t i = 0; i < got.size(); ++i) {
    L.owned[i] = got[i].g;
    L.by_gid[i] = got[i].by_gid;
    L.cnt[i + 1] = L.cnt[i] + got[i].degree;
  }
  if (L.cnt.back() > INT32_MAX) throw Error("graph build: more than 2^31 entries on one rank; use more ranks");
  seg.assign(static_cast<std::size_t>(size) + 1, 0);
  for (int r = 0; r < size; ++r) seg[r + 1] = seg[r] + rrows[r];
}

Rounds plan_rounds(MPI_Comm comm, const RowPlan& P, std::size_t entry_bytes) {
  std::int64_t round_bytes = std::int64_t(64) << 20;
  if (const char* e = std::getenv("SNL_TEST_SETUP_ROUND_BYTES")) round_bytes = std::max(1LL, std::atoll(e));  // tests
  const int size = comm_size(comm), rank = comm_rank(comm);
  long long k = std::max<long long>(1, round_bytes / static_cast<long long>(entry_bytes * std::max(1, size - 1)));
  MPI_Allreduce(MPI_IN_PLACE, &k, 1, MPI_LONG_LONG, MPI_MIN, comm);
  long long most = 0;
  for (int o = 0; o < size; ++o)
    if (o != rank) most = std::max<long long>(most, (P.ents_to[o] + k - 1) / k);
  MPI_Allreduce(MPI_IN_PLACE, &most, 1, MPI_LONG_LONG, MPI_MAX, comm);
  if (most > INT32_MAX) throw Error("graph build: too many rounds");
  return Rounds{k, static_cast<int>(most)};
}

// Calls f(t, j0, j1) for the pieces of block rows (row t's entries j0 .. j1)
// that make up entries [k0, k1) of an owner's part, in pack order; `p`, a
// pack position in that part, moves on with them (a piece may end mid-row).
// The rows are read at random: their offsets and their data (at data(t))
// are fetched ahead.
template <class D, class F>
void for_each_piece(const RowPlan& P, const BlockRows& R, std::int64_t k0, std::int64_t k1, std::int64_t& p, D&& data,
                    F&& f) {
  constexpr std::int64_t kOffsetsAhead = 16, kDataAhead = 8;
  const auto np = static_cast<std::int64_t>(P.row.size());
  while (k0 < k1) {
    if (p + kOffsetsAhead < np) __builtin_prefetch(&R.offsets[P.row[static_cast<std::size_t>(p + kOffsetsAhead)]]);
    if (p + kDataAhead < np) __builtin_prefetch(data(P.row[static_cast<std::size_t>(p + kDataAhead)]));
    const std::int64_t t = P.row[static_cast<std::size_t>(p)], b = P.within[static_cast<std::size_t>(p)];
    const std::int64_t deg = R.offsets[t + 1] - R.offsets[t], j1 = std::min(deg, k1 - b);
    if (j1 > k0 - b) f(t, k0 - b, j1);
    k0 = b + j1;
    if (j1 == deg) ++p;
  }
}

// Entries [k0, k1) of owner o's part with their neighbours' slots, to `dst`:
// by chunks, the ids gathered from their rows, then the slots looked up in
// one stream (fetched ahead). Returns the entries whose ends have different
// owners.
template <class Id>
std::int64_t pack_part(const RowPlan& P, const BlockRows& R, const std::vector<Id>& nbr, NeighbourSlots<Id>& slots,
                       int o, std::int64_t k0, std::int64_t k1, std::int64_t& p, Entry<Id>* dst) {
  constexpr std::int64_t kAhead = 32, kChunk = 1 << 15;  // lookups in flight; entries per chunk (in cache)
  auto ids_at = [&](std::int64_t t) { return nbr.data() + R.offsets[t]; };
  std::int64_t cut = 0;
  for (std::int64_t a = k0; a < k1; a += kChunk) {
    const std::int64_t b = std::min(k1, a + kChunk);
    Entry<Id>* e = dst + (a - k0);
    Entry<Id>* w = e;
    for_each_piece(P, R, a, b, p, ids_at, [&](std::int64_t t, std::int64_t j0, std::int64_t j1) {
      for (const Id* src = nbr.data() + R.offsets[t]; j0 < j1; ++j0) (w++)->nbr = src[j0];
    });
    for (std::int64_t k = 0; k < b - a; ++k) {
      if (k + kAhead < b - a) __builtin_prefetch(slots.address(static_cast<GlobalId>(e[k + kAhead].nbr)));
      const auto& s = slots.at(static_cast<GlobalId>(e[k].nbr));
      e[k].owner = s.owner;
      e[k].index = s.index;
      cut += s.owner != o;
    }
  }
  return cut;
}

// The order in which pack_part reads the parts: this rank's own whole, then
// round by round each other owner's piece; f(o, k0, k1, p).
template <class F>
void for_each_part_piece(const RowPlan& P, const Rounds& rd, int rank, std::vector<std::int64_t>& p, F&& f) {
  const int size = static_cast<int>(P.ents_to.size());
  f(rank, std::int64_t(0), P.ents_to[rank], p[rank]);
  for (int c = 0; c < rd.count; ++c)
    for (int o = 0; o < size; ++o)
      if (o != rank) f(o, c * rd.per_owner, c * rd.per_owner + rd.piece(P.ents_to[o], c), p[o]);
}

// The ids whose slots are asked of sparse blocks, in the order pack_part
// looks them up (NeighbourSlots hands the answers out in that order).
template <class Id>
void ask_slots(MPI_Comm comm, const RowPlan& P, const Rounds& rd, const BlockRows& R, const std::vector<Id>& nbr,
               NeighbourSlots<Id>& slots) {
  std::vector<std::vector<Id>> ask(static_cast<std::size_t>(comm_size(comm)));
  if (slots.asks()) {
    std::vector<std::int64_t> p(P.first.begin(), P.first.end() - 1);
    for_each_part_piece(P, rd, comm_rank(comm), p, [&](int, std::int64_t k0, std::int64_t k1, std::int64_t& q) {
      auto ids_at = [&](std::int64_t t) { return nbr.data() + R.offsets[t]; };
      for_each_piece(P, R, k0, k1, q, ids_at, [&](std::int64_t t, std::int64_t j0, std::int64_t j1) {
        for (const Id* src = nbr.data() + R.offsets[t]; j0 < j1; ++j0)
          if (int r = 0; slots.asked(static_cast<GlobalId>(src[j0]), r)) ask[r].push_back(src[j0]);
      });
    });
  }
  slots.exchange(comm, ask);
}

// Per rank: `count` items of a round and where they begin (items of `width`
// per entry, all below 2^31: receive_headers, plan_rounds).
struct RoundCounts {
  std::vector<int> scount, sdisp, rcount, rdisp;
  explicit RoundCounts(int size) : scount(size), sdisp(size), rcount(size), rdisp(size) {}
};

}  // namespace

// Step 1: every block row to the owner of its node, with its neighbours'
// directory slots (the values follow once the CSR is laid out:
// values_to_csr). Each block's rows arrive in the owner's index order, so a
// sender's part lands where its index range begins in the owner's lists
// (`seg`); a rank's own part is written there, not sent to itself; the
// others go in rounds (Rounds). Neighbours stay in global-id order. `cut`:
// this rank's entries whose ends have different owners
// (each cut edge is counted by both of its rows).
template <class Id>
OwnedLists<Id> rows_to_owners(MPI_Comm comm, const OwnerDirectory& dir, const BlockRows& R, std::vector<Id>& nbr,
                              RowPlan& P, std::vector<std::int64_t>& seg, Rounds& rd, GlobalId& cut,
                              PhaseClock& clock) {
  const int size = comm_size(comm), rank = comm_rank(comm);
  OwnedLists<Id> L;
  L.rank = rank;
  P = plan_rows(dir, R, size);
  receive_headers(comm, P, L, seg);
  rd = plan_rounds(comm, P, sizeof(Entry<Id>));
  NeighbourSlots<Id> slots(comm, dir, nbr);
  ask_slots(comm, P, rd, R, nbr, slots);
  clock.done("slots");
  L.entries.resize(static_cast<std::size_t>(L.cnt.back()));
  std::vector<Entry<Id>> sbuf(static_cast<std::size_t>(rd.largest(P.ents_to, rank)));
  std::vector<std::int64_t> p(P.first.begin(), P.first.end() - 1);
  cut = pack_part(P, R, nbr, slots, rank, 0, P.ents_to[rank], p[rank], L.entries.data() + L.cnt[seg[rank]]);
  MPI_Datatype rec;
  MPI_Type_contiguous(static_cast<int>(sizeof(Entry<Id>)), MPI_BYTE, &rec);
  MPI_Type_commit(&rec);
  RoundCounts n(size);
  for (int c = 0; c < rd.count; ++c) {
    for (int r = 0, s = 0; r < size; ++r) {
      n.scount[r] = r == rank ? 0 : static_cast<int>(rd.piece(P.ents_to[r], c));
      n.sdisp[r] = s;
      s += n.scount[r];
      n.rcount[r] = r == rank ? 0 : static_cast<int>(rd.piece(L.cnt[seg[r + 1]] - L.cnt[seg[r]], c));
      n.rdisp[r] = n.rcount[r] > 0 ? static_cast<int>(L.cnt[seg[r]] + c * rd.per_owner) : 0;
      if (r != rank)
        cut += pack_part(P, R, nbr, slots, r, c * rd.per_owner, c * rd.per_owner + n.scount[r], p[r],
                         sbuf.data() + n.sdisp[r]);
    }
    MPI_Alltoallv(sbuf.data(), n.scount.data(), n.sdisp.data(), rec, L.entries.data(), n.rcount.data(),
                  n.rdisp.data(), rec, comm);
  }
  MPI_Type_free(&rec);
  L.peak_bytes = R.memory_bytes() + static_cast<std::int64_t>(nbr.capacity() * sizeof(Id)) + slots.memory_bytes() +
                 static_cast<std::int64_t>(P.row.size() * 12 + (sbuf.size() + L.entries.size()) * sizeof(Entry<Id>) +
                                           (L.cnt.size() + L.owned.size()) * 8 + L.by_gid.size() * 4);
  release(sbuf);
  clock.done("exchange");
  L.boundary.assign(L.owned.size(), 0);
  for (std::size_t v = 0; v < L.owned.size(); ++v)
    for (auto k = L.cnt[v]; k < L.cnt[v + 1]; ++k)
      if (L.entries[k].owner != rank) {
        L.boundary[v] = 1;
        break;
      }
  return L;
}

// Step 6: the rows' values (`width` per entry) to the owners, straight into
// the CSR's edge values (`values`, laid out: fill_csr): in the same rounds
// and pack order as the entries, each received piece copied to its rows'
// places (row i of the lists is local row owned_to_local[i], in the same
// neighbour order). Where the values waited in the lists beside their
// entries (8 bytes per entry), the CSR was filled from them.
void values_to_csr(MPI_Comm comm, const RowPlan& P, const Rounds& rd, const BlockRows& R,
                   const std::vector<std::int64_t>& cnt, const std::vector<std::int64_t>& seg,
                   const std::vector<LocalId>& owned_to_local, const std::vector<std::int64_t>& offsets,
                   std::vector<double>& values, std::int64_t& peak) {
  const int size = comm_size(comm), rank = comm_rank(comm), width = R.width;
  values.resize(static_cast<std::size_t>(cnt.back()) * static_cast<std::size_t>(width));
  if (width == 0) return;
  const auto w = static_cast<std::size_t>(width);
  // Row i of the lists at its place in the CSR; its offsets are read at
  // random, so they and the place are fetched ahead.
  constexpr std::int64_t kOffsetsAhead = 16, kPlaceAhead = 8;
  const auto n_owned = static_cast<std::int64_t>(owned_to_local.size());
  auto place = [&](std::int64_t i) {
    if (i + kOffsetsAhead < n_owned) __builtin_prefetch(&offsets[owned_to_local[i + kOffsetsAhead]]);
    if (i + kPlaceAhead < n_owned)
      __builtin_prefetch(values.data() + offsets[owned_to_local[i + kPlaceAhead]] * width, 1);
    return values.data() + offsets[owned_to_local[i]] * width;
  };
  auto values_at = [&](std::int64_t t) { return R.values.data() + R.offsets[t] * width; };
  const std::int64_t own_end = P.first[rank + 1];
  for (std::int64_t p = P.first[rank], i = seg[rank]; p < own_end; ++p, ++i) {  // this rank's own rows
    if (p + kOffsetsAhead < own_end) __builtin_prefetch(&R.offsets[P.row[static_cast<std::size_t>(p + kOffsetsAhead)]]);
    if (p + kPlaceAhead < own_end) __builtin_prefetch(values_at(P.row[static_cast<std::size_t>(p + kPlaceAhead)]));
    const std::int64_t t = P.row[static_cast<std::size_t>(p)];
    std::copy(values_at(t), values_at(t + 1), place(i));
  }
  std::vector<std::int64_t> from(static_cast<std::size_t>(size));  // entries from each sender
  for (int r = 0; r < size; ++r) from[r] = cnt[seg[r + 1]] - cnt[seg[r]];
  std::vector<double> sv(static_cast<std::size_t>(rd.largest(P.ents_to, rank)) * w),
      rv(static_cast<std::size_t>(rd.largest(from, rank)) * w);
  peak = std::max<std::int64_t>(peak, R.memory_bytes() + static_cast<std::int64_t>(
                                          P.row.size() * 12 + (sv.size() + rv.size()) * 8 +
                                          owned_to_local.size() * 4 + cnt.size() * 8));
  std::vector<std::int64_t> p(P.first.begin(), P.first.end() - 1), at(seg.begin(), seg.end() - 1);
  RoundCounts n(size);
  for (int c = 0; c < rd.count; ++c) {
    for (int r = 0, s = 0, q = 0; r < size; ++r) {
      const std::int64_t k0 = c * rd.per_owner, sent = r == rank ? 0 : rd.piece(P.ents_to[r], c);
      n.scount[r] = static_cast<int>(sent * width);
      n.sdisp[r] = s;
      n.rcount[r] = r == rank ? 0 : static_cast<int>(rd.piece(from[r], c) * width);
      n.rdisp[r] = q;
      double* dst = sv.data() + s;
      for_each_piece(P, R, k0, k0 + sent, p[r], values_at, [&](std::int64_t t, std::int64_t j0, std::int64_t j1) {
        dst = std::copy(R.values.data() + (R.offsets[t] + j0) * width, R.values.data() + (R.offsets[t] + j1) * width,
                        dst);
      });
      s += n.scount[r];
      q += n.rcount[r];
    }
    MPI_Alltoallv(sv.data(), n.scount.data(), n.sdisp.data(), MPI_DOUBLE, rv.data(), n.rcount.data(),
                  n.rdisp.data(), MPI_DOUBLE, comm);
    for (int r = 0; r < size; ++r) {  // sender r's piece: its entries k .. end of the lists, row by row
      std::int64_t k = cnt[seg[r]] + c * rd.per_owner;
      const std::int64_t end = k + n.rcount[r] / width;
      const double* src = rv.data() + n.rdisp[r];
      for (std::int64_t& i = at[r]; k < end;) {
        const std::int64_t e = std::min(end, cnt[i + 1]);
        std::copy(src, src + (e - k) * width, place(i) + (k - cnt[i]) * width);
        src += (e - k) * width;
        k = e;
        if (k == cnt[i + 1]) ++i;
      }
    }
  }
}

template OwnedLists<std::int32_t> rows_to_owners(MPI_Comm, const OwnerDirectory&, const BlockRows&,
                                                 std::vector<std::int32_t>&, RowPlan&, std::vector<std::int64_t>&,
                                                 Rounds&, GlobalId&, PhaseClock&);
template OwnedLists<std::int64_t> rows_to_owners(MPI_Comm, const OwnerDirectory&, const BlockRows&,
                                                 std::vector<std::int64_t>&, RowPlan&, std::vector<std::int64_t>&,
                                                 Rounds&, GlobalId&, PhaseClock&);

}  // namespace snl::graph_build
