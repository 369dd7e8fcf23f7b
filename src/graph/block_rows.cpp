// The graph by blocks of rows (BlockRows): each edge's two half-edges go to
// the block holders of their nodes, which bucket them into rows and sort each
// row by neighbour id. The partition and the graph build both read these rows,
// so the edges are routed, bucketed and sorted once.
#include <algorithm>
#include <cstring>
#include <functional>
#include <limits>
#include <numeric>
#include <stdexcept>

#include "graph/partition_detail.hpp"
#include "snl/core/mpi_util.hpp"
#include "snl/graph/dist_graph.hpp"

namespace snl {

namespace {

// A half-edge on its way to the block holder of its node: the node's offset
// in that block and the neighbour (Id: 32-bit below 2^31 nodes).
template <class Id>
struct Half {
  std::int32_t v;
  Id u;
};

inline void copy_row_values(const double* src, double* dst, int width) {
  for (int c = 0; c < width; ++c) dst[c] = src[c];
}

// The values per row entry: fixed at compile time for the usual 0, 1 and 2
// (the packing loop over every half-edge then copies them without a loop or
// a multiplication; docs/performance.md), read at run time otherwise (W = -1).
template <int W>
struct Width {
  int n;
  constexpr int get() const { return W >= 0 ? W : n; }
};

template <class F>
void with_width(int width, F&& f) {
  switch (width) {
    case 0: f(Width<0>{0}); break;
    case 1: f(Width<1>{1}); break;
    case 2: f(Width<2>{2}); break;
    default: f(Width<-1>{width});
  }
}

// The halves bound for one block arrive grouped by bucket of consecutive
// rows (few write streams when the rows are filled; a bucket's rows fit in
// cache): 1024 buckets at most, 2^shift rows each.
struct Buckets {
  int shift = 0;
  std::int64_t count = 1;
  explicit Buckets(std::int64_t rows) {
    while ((rows >> shift) >= 1024) ++shift;
    count = (rows >> shift) + 1;
  }
};

// The halves on this rank after step 1: those of its own block (keep) and
// those received (got, rank order), values alongside, each group ordered by
// bucket; kstart[k], and gstart[s][k] for sender s, where bucket k begins.
template <class Id>
struct RoutedHalves {
  std::vector<Half<Id>> keep, got;
  std::vector<double> keep_vals, got_vals;
  std::vector<std::int64_t> kstart;
  std::vector<std::vector<std::int64_t>> gstart;
  int rank = 0;
};

// Step 1: the half-edges of this rank's pairs (ne pairs, ends[2e] and
// ends[2e + 1]; vals(e, dst) writes pair e's values) to the block holders of
// their nodes, packed by destination and, within it, by the destination's
// bucket (Buckets); those of its own block stay. So no rank copies the halves
// once more to bucket them. `packed` is called once the pairs are read.
template <class Id, class Vals>
void route_halves(MPI_Comm comm, const detail::Blocks& blocks, const GlobalId* ends, std::size_t ne, Vals&& vals,
                  const std::function<void()>& packed, RoutedHalves<Id>& H, BlockRows& R, std::vector<Id>& nbr) {
  const int width = R.width;
  const int size = blocks.size(), rank = comm_rank(comm);
  const auto w = static_cast<std::size_t>(width);
  std::vector<int> shift(size);
  std::vector<std::int64_t> kfirst(static_cast<std::size_t>(size) + 1, 0);  // rank r's buckets in `at`
  for (int r = 0; r < size; ++r) {
    const Buckets b(blocks.first[r + 1] - blocks.first[r]);
    shift[r] = b.shift;
    kfirst[r + 1] = kfirst[r] + b.count;
  }
  std::vector<std::int64_t> at(static_cast<std::size_t>(kfirst[size]) + 1, 0);
  auto slot = [&](GlobalId v, int& r, std::int32_t& off) {
    r = blocks.of(v);
    off = static_cast<std::int32_t>(v - blocks.first[r]);
    return static_cast<std::size_t>(kfirst[r] + (off >> shift[r]));
  };
  for (std::size_t k = 0; k < 2 * ne; ++k) {
    int r;
    std::int32_t off;
    ++at[slot(ends[k], r, off) + 1];
  }
  // Counts per bucket (sent along), then places: the kept halves from 0 in
  // their own array, the others by destination in the send buffer.
  std::vector<std::int64_t> bcount(at.begin() + 1, at.end());
  std::vector<std::int64_t> start(static_cast<std::size_t>(size) + 1, 0);
  for (int r = 0; r < size; ++r)
    for (auto k = kfirst[r]; k < kfirst[r + 1]; ++k) start[r + 1] += bcount[k];
  std::vector<int> scount, vcount(size);
  const std::int64_t n_keep = start[rank + 1];
  start[rank + 1] = 0;
  pack_offsets(start, scount, std::max(width, 1), "block rows");
  for (int r = 0; r < size; ++r) vcount[r] = scount[r] * width;
  for (int r = 0; r < size; ++r)
    for (std::int64_t k = kfirst[r], p = r == rank ? 0 : start[r]; k < kfirst[r + 1]; ++k) {
      at[k] = p;
      p += bcount[k];
    }
  H.keep.resize(static_cast<std::size_t>(n_keep));
  H.keep_vals.resize(static_cast<std::size_t>(n_keep) * w);
  std::vector<Half<Id>> sbuf(static_cast<std::size_t>(start[size]));
  std::vector<double> svals(sbuf.size() * w), v(std::max<std::size_t>(w, 1));
  with_width(width, [&](auto wd) {
    const auto ws = static_cast<std::size_t>(wd.get());
    auto put = [&](GlobalId a, GlobalId b) {
      int r;
      std::int32_t off;
      const auto p = static_cast<std::size_t>(at[slot(a, r, off)]++);
      const Half<Id> h{off, static_cast<Id>(b)};
      if (r == rank) {
        copy_row_values(v.data(), H.keep_vals.data() + p * ws, wd.get());
        H.keep[p] = h;
      } else {
        copy_row_values(v.data(), svals.data() + p * ws, wd.get());
        sbuf[p] = h;
      }
    };
    for (std::size_t e = 0; e < ne; ++e) {
      vals(e, v.data());
      put(ends[2 * e], ends[2 * e + 1]);
      put(ends[2 * e + 1], ends[2 * e]);
    }
  });
  if (packed) packed();
  // Each sender's bucket counts for this rank's block, then the halves.
  const std::int64_t nk = kfirst[rank + 1] - kfirst[rank];
  std::vector<int> ccount(size), cdisp(size), rccount(size, static_cast<int>(nk)), rcdisp(size);
  for (int r = 0; r < size; ++r) {
    ccount[r] = r == rank ? 0 : static_cast<int>(kfirst[r + 1] - kfirst[r]);
    cdisp[r] = static_cast<int>(kfirst[r]);
    rcdisp[r] = static_cast<int>(r * nk);
  }
  rccount[rank] = 0;
  std::vector<std::int64_t> rc(static_cast<std::size_t>(size * nk), 0);
  MPI_Alltoallv(bcount.data(), ccount.data(), cdisp.data(), MPI_INT64_T, rc.data(), rccount.data(), rcdisp.data(),
                MPI_INT64_T, comm);
  // The rows' arrays before the halves arrive: above the halves and the
  // send buffers in the heap, so that these, freed once the rows are filled,
  // leave one free block for the partition and the graph build (the rows
  // placed in a freed send buffer's gap split it: 0.9 GB more heap on one
  // rank at 10M on 2 ranks, docs/performance.md).
  const std::int64_t total = std::accumulate(rc.begin(), rc.end(), n_keep);
  nbr.resize(static_cast<std::size_t>(total));
  R.values.resize(static_cast<std::size_t>(total) * w);
  R.peak_bytes = static_cast<std::int64_t>((H.keep.size() + 2 * sbuf.size()) * (sizeof(Half<Id>) + 8 * w)) +
                 R.memory_bytes();
  std::vector<int> rcount;
  H.got = exchange_packed(comm, std::move(sbuf), scount, &rcount);
  H.got_vals = exchange_packed(comm, std::move(svals), vcount);
  H.rank = rank;
  H.kstart.assign(static_cast<std::size_t>(nk) + 1, 0);
  for (std::int64_t k = 0; k < nk; ++k) H.kstart[k + 1] = H.kstart[k] + bcount[kfirst[rank] + k];
  H.gstart.assign(static_cast<std::size_t>(size), {});
  for (int s = 0, g = 0; s < size; g += rcount[s++]) {
    auto& gs = H.gstart[s];
    gs.assign(static_cast<std::size_t>(nk) + 1, g);
    if (s != rank)
      for (std::int64_t k = 0; k < nk; ++k) gs[k + 1] = gs[k] + rc[static_cast<std::size_t>(s * nk + k)];
  }
}

// Sorts the entries [b, e) of a row (and their values) by neighbour id:
// insertion sort for the usual few, an index sort for hubs.
template <class Id>
void sort_row(Id* nbr, double* val, int w, std::int64_t b, std::int64_t e, std::vector<double>& tmp,
              std::vector<std::int64_t>& perm) {
  if (e - b <= 32) {
    for (std::int64_t i = b + 1; i < e; ++i) {
      if (!(nbr[i] < nbr[i - 1])) continue;
      const Id x = nbr[i];
      copy_row_values(val + i * w, tmp.data(), w);
      std::int64_t j = i;
      for (; j > b && x < nbr[j - 1]; --j) {
        nbr[j] = nbr[j - 1];
        copy_row_values(val + (j - 1) * w, val + j * w, w);
      }
      nbr[j] = x;
      copy_row_values(tmp.data(), val + j * w, w);
    }
    return;
  }
  perm.resize(static_cast<std::size_t>(e - b));
  std::iota(perm.begin(), perm.end(), b);
  std::sort(perm.begin(), perm.end(), [&](std::int64_t x, std::int64_t y) { return nbr[x] < nbr[y]; });
  std::vector<Id> sn(perm.size());
  std::vector<double> sv(perm.size() * w);
  for (std::size_t t = 0; t < perm.size(); ++t) {
    sn[t] = nbr[perm[t]];
    copy_row_values(val + perm[t] * w, sv.data() + t * w, w);
  }
  std::copy(sn.begin(), sn.end(), nbr + b);
  std::copy(sv.begin(), sv.end(), val + b * w);
}

// Step 2: the rows of this rank's block, bucket by bucket (the bucket's kept
// halves and each sender's): counted, filled in cache and sorted (counting
// and filling straight into the rows waited on a cache miss per half-edge).
// Consumes the halves.
template <class Id>
void fill_rows(BlockRows& R, std::vector<Id>& nbr, RoutedHalves<Id>&& H) {
  const int width = R.width;
  const auto w = static_cast<std::size_t>(width);
  const std::int64_t nb = R.num_rows();
  const Buckets bk(nb);
  for (const auto& h : H.keep) ++R.offsets[h.v + 1];
  for (const auto& h : H.got) ++R.offsets[h.v + 1];
  for (std::int64_t v = 0; v < nb; ++v) R.offsets[v + 1] += R.offsets[v];
  if (nbr.size() != static_cast<std::size_t>(R.offsets[nb]) || R.values.size() != nbr.size() * w)
    throw std::logic_error("block rows: the halves received are not the halves counted");
  R.peak_bytes = std::max<std::int64_t>(
      R.peak_bytes, static_cast<std::int64_t>((H.keep.size() + H.got.size()) * (sizeof(Half<Id>) + 8 * w)) +
                        R.memory_bytes());
  std::vector<std::int64_t> fill, perm;
  std::vector<double> tmp(std::max<std::size_t>(w, 1));
  auto place = [&](const std::vector<Half<Id>>& hs, const std::vector<double>& vs, std::int64_t b, std::int64_t e,
                   std::int64_t v0) {
    for (auto p = b; p < e; ++p) {
      const auto q = static_cast<std::size_t>(fill[hs[p].v - v0]++);
      nbr[q] = hs[p].u;
      copy_row_values(vs.data() + p * width, R.values.data() + q * w, width);
    }
  };
  for (std::int64_t k = 0; k < bk.count; ++k) {
    const std::int64_t v0 = k << bk.shift, v1 = std::min(nb, (k + 1) << bk.shift);
    if (v0 >= v1) continue;
    fill.assign(R.offsets.begin() + v0, R.offsets.begin() + v1);
    for (std::size_t r = 0; r < H.gstart.size(); ++r)  // in rank order: a sorted file's rows come sorted
      if (static_cast<int>(r) == H.rank)
        place(H.keep, H.keep_vals, H.kstart[k], H.kstart[k + 1], v0);
      else
        place(H.got, H.got_vals, H.gstart[r][k], H.gstart[r][k + 1], v0);
    for (auto v = v0; v < v1; ++v)
      sort_row(nbr.data(), R.values.data(), width, R.offsets[v], R.offsets[v + 1], tmp, perm);
  }
  H = RoutedHalves<Id>();
}

// Step 3, where a merge is given: the entries of one pair met more than once
// (duplicate measurements, in either orientation, from any rank) become one.
// A row is sorted by neighbour; the duplicates' values are sorted too, so
// the merge sees them in one order whichever rank held which (and the rows
// of both ends merge alike). Rows shrink in place. Returns the entries
// removed from rows of the pair's smaller end.
template <class Id>
std::int64_t merge_duplicates(BlockRows& R, std::vector<Id>& nbr, const BlockRows::Merge& merge) {
  const int width = R.width;
  const auto w = static_cast<std::size_t>(width);
  const std::int64_t nb = R.num_rows();
  std::int64_t out = 0, removed = 0;
  std::vector<std::int64_t> perm;
  std::vector<double> run;
  for (std::int64_t t = 0, k = 0; t < nb; ++t) {
    const std::int64_t end = R.offsets[t + 1];
    R.offsets[t] = out;
    while (k < end) {
      std::int64_t f = k + 1;
      while (f < end && nbr[f] == nbr[k]) ++f;
      if (f - k > 1) {
        perm.resize(static_cast<std::size_t>(f - k));
        std::iota(perm.begin(), perm.end(), k);
        const double* v = R.values.data();
        std::sort(perm.begin(), perm.end(), [&](std::int64_t x, std::int64_t y) {
          return std::lexicographical_compare(v + x * width, v + (x + 1) * width, v + y * width, v + (y + 1) * width);
        });
        run.resize(perm.size() * w);
        for (std::size_t j = 0; j < perm.size(); ++j) copy_row_values(v + perm[j] * width, run.data() + j * w, width);
        merge(run.data(), f - k, width);
        copy_row_values(run.data(), R.values.data() + k * width, width);
        if (R.begin + t < static_cast<GlobalId>(nbr[k])) removed += f - k - 1;
      }
      nbr[out] = nbr[k];
      copy_row_values(R.values.data() + k * width, R.values.data() + out * width, width);
      ++out;
      k = f;
    }
  }
  R.offsets[nb] = out;
  nbr.resize(static_cast<std::size_t>(out));
  R.values.resize(static_cast<std::size_t>(out) * w);
  return removed;
}

template <class Id, class Vals>
void build_rows(MPI_Comm comm, BlockRows& R, std::vector<Id>& nbr, const GlobalId* ends, std::size_t ne, Vals&& vals,
                const std::function<void()>& packed, const BlockRows::Merge& merge) {
  const detail::Blocks blocks(R.n, comm_size(comm));
  RoutedHalves<Id> H;
  route_halves(comm, blocks, ends, ne, vals, packed, H, R, nbr);
  fill_rows(R, nbr, std::move(H));
  bool dup = false;  // (only where a merge is given: a pass over every entry)
  for (std::int64_t t = 0; t < R.num_rows() && !dup && merge; ++t)
    for (auto k = R.offsets[t] + 1; k < R.offsets[t + 1]; ++k)
      if (nbr[k] == nbr[k - 1]) {
        dup = true;
        break;
      }
  if (dup && merge) R.merged = merge_duplicates(R, nbr, merge);
}

// The rows' block and id width; false where a block holds 2^31 nodes or more.
void start_rows(MPI_Comm comm, BlockRows& R, GlobalId n, int width, bool ok) {
  R.n = n;
  R.width = width;
  GlobalId b, e;
  block_range(n, comm_size(comm), comm_rank(comm), b, e);
  R.begin = b;
  if (!all_ranks(comm, ok && e - b < std::numeric_limits<std::int32_t>::max()))
    throw Error("block rows: over 2^31 nodes on one rank, or values that do not match the pairs");
  R.offsets.assign(static_cast<std::size_t>(e - b) + 1, 0);
  R.wide = setup_wide_ids(comm, n);
}

}  // namespace

BlockRows BlockRows::from_edges(MPI_Comm comm, GlobalId n, std::vector<GlobalId>&& edges, std::vector<double>&& values,
                                int width) {
  BlockRows R;
  start_rows(comm, R, n, width, values.size() == edges.size() / 2 * static_cast<std::size_t>(width));
  const auto w = static_cast<std::size_t>(width);
  auto vals = [&](std::size_t e, double* dst) { copy_row_values(values.data() + e * w, dst, width); };
  auto packed = [&] {
    release(edges);
    release(values);
  };
  if (R.wide) build_rows(comm, R, R.nbr64, edges.data(), edges.size() / 2, vals, packed, Merge());
  else build_rows(comm, R, R.nbr32, edges.data(), edges.size() / 2, vals, packed, Merge());
  return R;
}

BlockRows BlockRows::from_pairs(MPI_Comm comm, GlobalId n, const GlobalId* ends, std::size_t count, const double* col0,
                                const double* col1, int width, const Merge& merge,
                                const std::function<void()>& packed) {
  BlockRows R;
  start_rows(comm, R, n, width, width >= 0 && width <= 2 && (width == 0 || col0 || count == 0));
  auto vals = [&](std::size_t e, double* dst) {
    if (width > 0) dst[0] = col0[e];
    if (width > 1) dst[1] = col1 ? col1[e] : 0.0;
  };
  if (R.wide) build_rows(comm, R, R.nbr64, ends, count, vals, packed, merge);
  else build_rows(comm, R, R.nbr32, ends, count, vals, packed, merge);
  return R;
}

std::vector<GlobalId> BlockRows::edges() const {
  std::vector<GlobalId> out;
  for (std::int64_t t = 0; t < num_rows(); ++t)
    for (auto k = offsets[t]; k < offsets[t + 1]; ++k) {
      const GlobalId g = begin + t, u = wide ? nbr64[k] : static_cast<GlobalId>(nbr32[k]);
      if (g < u) out.insert(out.end(), {g, u});
    }
  return out;
}

}  // namespace snl
