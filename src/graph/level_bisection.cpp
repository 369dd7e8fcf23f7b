// The bfs partition run by every rank on its block of rows: recursive
// bisection by breadth-first level structures (George and Liu), each level of
// every range of one recursion depth expanded at once, with one exchange of
// the visits that cross to another block per level. Nothing of size n on
// any rank, and every rank works (the partition on rank 0 left the others
// waiting and needed the whole graph there).
//
// The partition is a function of the graph and the number of parts alone:
// for each range (its nodes and parts [p0, p1)), in up to kRounds rounds,
//   s = the range's unvisited node of largest degree (smallest id on ties),
//   a probe from s over the unvisited nodes, following from each node only
//   the first kProbeDegree entries of its row (smallest neighbour ids),
//   reaches P; if P holds at least 1/kProbeShare of the range's unvisited nodes,
//   r = P's node of smallest id among those farthest from s in the probe;
//   otherwise (a probe that died out early) a pass from s over all the
//   edges reaches s's component, and r = its node of smallest id among
//   those farthest from s;
//   T = r's component (s's) among the unvisited nodes,
//   key(v) = base + (distance from r within T) for v in T, base += the
//   largest distance + 1;
// r only needs to lie far from the middle of T. The probe reads one cache
// line of a row and a quarter of the neighbours' labels, and sends few
// visits to other blocks (the smallest ids of a row are mostly in the lowest
// blocks); on the default 10M network it reaches 40% of the nodes and costs
// a fraction of a full pass (docs/performance.md, "What limits what").
// A round after the first runs only while more than 1/64 of the range is
// unvisited (a bound on the rounds' cost, not on the result: the rest comes
// last whatever its keys, and no split falls in a rest that small); what is
// left gets key = base. The first
// size (pm - p0) / (p1 - p0) nodes by (key, id) go to [p0, pm), the others
// to [pm, p1), pm = p0 + (p1 - p0) / 2, except that a level boundary within
// size / 256 of that count is taken instead (see split).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "graph/partition_detail.hpp"
#include "snl/core/mpi_util.hpp"

namespace snl::detail {
namespace {

constexpr int kRounds = 8;           // passes per range and depth: components handled one by one
constexpr std::int64_t kBins = 256;  // bins per round of the distributed selection
constexpr std::int64_t kProbeDegree = 4;  // row entries a probe follows
constexpr long long kProbeShare = 8;       // a probe reaching less of its range died out early
// A node's label: kStages * (its range) + its stage in the round.
constexpr int kStages = 4;
enum Stage : std::int32_t { kUnvisited = 0, kProbed = 1, kSwept = 2, kOrdered = 3 };
// Labels of one byte up to 127 parts: at most 63 ranges per depth, labels up
// to 4 * 62 + 3 = 251, and 255 for done.
constexpr int kByteLabelParts = 127;
constexpr std::int64_t kLevelSlack = 256;  // a split at a level boundary may miss the proportional count by size / 256

// A visit that crosses to another block: the node's offset in that block and
// the label it gets (its range's, at the pass's stage) if it carries one of
// the same range at an earlier stage.
struct Visit {
  std::int32_t v, to;
};

// One recursion depth's range.
struct Range {
  GlobalId size;
  int p0, p1;
};

template <class Index, class Label>
class LevelBisection {
 public:
  LevelBisection(MPI_Comm comm, const Blocks& blocks, const std::vector<std::int64_t>& lx,
                 const std::vector<Index>& ladj, std::int64_t max_levels)
      : comm_(comm),
        blocks_(blocks),
        lx_(lx),
        ladj_(ladj),
        rank_(comm_rank(comm)),
        size_(comm_size(comm)),
        first_(blocks.first[rank_]),
        nb_(static_cast<std::int32_t>(lx.size() - 1)),
        max_levels_(max_levels),
        label_(static_cast<std::size_t>(nb_), 0),
        level_(static_cast<std::size_t>(nb_), 0),
        frontier_(static_cast<std::size_t>(nb_)),
        next_(static_cast<std::size_t>(nb_)),
        scount_(size_),
        rcount_(size_),
        sdisp_(size_),
        rdisp_(size_),
        sinfo_(2 * static_cast<std::size_t>(size_)),
        rinfo_(2 * static_cast<std::size_t>(size_)) {
    MPI_Type_contiguous(2, MPI_INT32_T, &visit_type_);
    MPI_Type_commit(&visit_type_);
  }
  ~LevelBisection() { MPI_Type_free(&visit_type_); }
  LevelBisection(const LevelBisection&) = delete;
  LevelBisection& operator=(const LevelBisection&) = delete;

  // Owners of this block's nodes into `owner`; false (on every rank) when a
  // pass ran past max_levels.
  bool run(int nparts, std::vector<int>& owner);
  // After run: each node's key in the split that decided its part (its
  // breadth-first distance from that range's r). A copy: the levels moved
  // out outlived the other arrays, and that heap layout raised the resident
  // peak of the graph build by 366 MiB at 10M on 2 ranks.
  std::vector<std::int32_t> keys() const { return level_; }

  std::int64_t bytes() const {
    return static_cast<std::int64_t>(label_.capacity() * sizeof(Label) + level_.capacity() * 4 + frontier_.capacity() * 4 +
                                     next_.capacity() * 4 + (remote_.capacity() + sent_.capacity()) * sizeof(Remote) +
                                     (sbuf_.capacity() + rbuf_.capacity()) * sizeof(Visit));
  }

 private:
  std::int64_t range_of(std::int32_t v) const { return label_[v] / kStages; }
  GlobalId gid(std::int32_t v) const { return first_ + v; }
  bool rounds(std::vector<std::int32_t>& base);
  bool far_roots(const std::vector<GlobalId>& s, const std::vector<long long>& left,
                 const std::vector<std::int32_t>& zero, std::vector<GlobalId>& r);
  bool pass(const std::vector<GlobalId>& roots, const std::vector<std::int32_t>& start, Stage stage,
            std::vector<std::int32_t>& far_level, std::vector<GlobalId>& far_gid, std::vector<long long>* reach);
  void visit(Label* lab, std::int32_t* lev, std::int32_t u, std::int32_t to, std::int32_t level);
  bool exchange(std::size_t nf);
  template <class Items>
  void select(const std::vector<std::int64_t>& need, std::vector<std::int64_t> hi, std::vector<std::int64_t>& t,
              std::vector<std::int64_t>& below, std::vector<std::int64_t>& at, Items&& items);
  void split(const std::vector<std::int32_t>& base, std::vector<int>& owner);

  MPI_Comm comm_;
  const Blocks& blocks_;
  const std::vector<std::int64_t>& lx_;
  const std::vector<Index>& ladj_;
  int rank_, size_;
  GlobalId first_;
  std::int32_t nb_;
  std::int64_t max_levels_;
  int depth_ = 0;
  // label: kStages i + stage for a node of active range i (Stage: unvisited,
  // reached by the probe or the pass from s, ordered from r), kDone once its
  // part is known.
  // One byte where the labels fit: the passes read it at random once per
  // edge, and a quarter of the bytes stays in cache.
  static constexpr Label kDone = std::numeric_limits<Label>::max();
  std::vector<Label> label_;
  std::vector<std::int32_t> level_;
  std::vector<Range> ranges_;
  std::vector<std::int32_t> frontier_, next_;  // nb each: a level holds each node once
  std::size_t n_next_ = 0;
  // Per pass: the farthest level of each range, the smallest id there, and
  // the nodes visited.
  std::vector<std::int32_t> far_level_;
  std::vector<long long> visited_;
  std::vector<GlobalId> far_gid_;
  std::int32_t step_ = 0;
  std::vector<std::int32_t> start_;
  // This level's visits to other blocks.
  struct Remote {
    GlobalId u;
    std::int32_t to;
  };
  std::vector<Remote> remote_;
  std::size_t n_remote_ = 0;
  // The visits to other blocks sent this pass, by (node, to), in a
  // direct-mapped table: a node of another block is reached by each of its
  // neighbours in this block (half of them on average at degree 16 on 2
  // ranks, the numbering being random), and its owner ignores every visit
  // after the first (which marks it, or finds it carrying another label for
  // the rest of the pass). Lossy: a visit the table has forgotten is sent
  // again, which changes nothing but the traffic.
  static constexpr int kSentBits = 15;
  std::vector<Remote> sent_;
  std::vector<Visit> sbuf_, rbuf_;
  std::vector<int> scount_, rcount_, sdisp_, rdisp_, sinfo_, rinfo_;
  MPI_Datatype visit_type_;
};

// Marks u visited (label `to`) at `level` if it carries a label of to's
// range at an earlier stage; raw pointers, because a store through a
// one-byte label may alias everything else and would make the compiler
// reload every vector's data each time.
template <class Index, class Label>
inline void LevelBisection<Index, Label>::visit(Label* lab, std::int32_t* lev, std::int32_t u, std::int32_t to,
                                                std::int32_t level) {
  const std::int32_t l = lab[u];
  if (l >= to || l < to - to % kStages) return;  // kDone is above every label
  lab[u] = static_cast<Label>(to);
  lev[u] = level;
  next_[n_next_++] = u;
  far_level_[to / kStages] = level;  // levels only grow within a pass
  ++visited_[to / kStages];
}

// The visits of this level to other blocks (remote_), by destination, in one
// all-to-all; applied here. Each rank's frontier size nf rides along with its
// counts: false, with nothing sent, when every rank's frontier was empty (one
// collective fewer per level than a separate test).
template <class Index, class Label>
bool LevelBisection<Index, Label>::exchange(std::size_t nf) {
  std::fill(scount_.begin(), scount_.end(), 0);
  for (std::size_t k = 0; k < n_remote_; ++k) ++scount_[blocks_.of(remote_[k].u)];
  std::int64_t stot = 0;
  for (int r = 0; r < size_; ++r) {
    sdisp_[r] = static_cast<int>(stot);
    stot += scount_[r];
  }
  if (stot > std::numeric_limits<int>::max()) throw Error("bfs partition: over 2^31 visits of one level on a rank");
  sbuf_.resize(static_cast<std::size_t>(stot));
  std::copy(sdisp_.begin(), sdisp_.end(), rdisp_.begin());  // fill cursors
  for (std::size_t k = 0; k < n_remote_; ++k) {
    const int r = blocks_.of(remote_[k].u);
    sbuf_[rdisp_[r]++] = {static_cast<std::int32_t>(remote_[k].u - blocks_.first[r]), remote_[k].to};
  }
  for (int r = 0; r < size_; ++r) {
    sinfo_[2 * r] = scount_[r];
    sinfo_[2 * r + 1] = static_cast<int>(nf);
  }
  MPI_Alltoall(sinfo_.data(), 2, MPI_INT, rinfo_.data(), 2, MPI_INT, comm_);
  std::int64_t rtot = 0, frontiers = 0;
  for (int r = 0; r < size_; ++r) {
    rcount_[r] = rinfo_[2 * r];
    frontiers += rinfo_[2 * r + 1];
    rdisp_[r] = static_cast<int>(rtot);
    rtot += rcount_[r];
  }
  if (frontiers == 0) return false;
  if (rtot > std::numeric_limits<int>::max()) throw Error("bfs partition: over 2^31 visits of one level on a rank");
  rbuf_.resize(static_cast<std::size_t>(rtot));
  MPI_Alltoallv(sbuf_.data(), scount_.data(), sdisp_.data(), visit_type_, rbuf_.data(), rcount_.data(), rdisp_.data(),
                visit_type_, comm_);
  Label* lab = label_.data();
  std::int32_t* lev = level_.data();
  for (const Visit& x : rbuf_) visit(lab, lev, x.v, x.to, start_[x.to / kStages] + step_);
  return true;
}

// One breadth-first pass of every range with a root (roots[i] >= 0) to
// `stage`, over the nodes of the range at an earlier stage, levels counted
// from start[i]; a probe (kProbed) follows the first kProbeDegree entries of
// each row only. far_level (every range's largest level), far_gid (the
// smallest id there) and, where asked, reach (the nodes visited) over all
// ranks. Collective; false when it ran past max_levels (on every rank).
template <class Index, class Label>
bool LevelBisection<Index, Label>::pass(const std::vector<GlobalId>& roots, const std::vector<std::int32_t>& start,
                                        Stage stage, std::vector<std::int32_t>& far_level,
                                        std::vector<GlobalId>& far_gid, std::vector<long long>* reach) {
  const std::size_t nr = ranges_.size();
  far_level_.assign(nr, -1);
  visited_.assign(nr, 0);
  start_ = start;
  n_next_ = 0;
  step_ = 0;
  Label* lab = label_.data();
  std::int32_t* lev = level_.data();
  const std::int64_t* off = lx_.data();
  const Index* adj = ladj_.data();
  const std::int64_t row_cap = stage == kProbed ? kProbeDegree : std::numeric_limits<std::int64_t>::max();
  auto row_end = [&](std::int32_t v) { return off[v + 1] - off[v] > row_cap ? off[v] + row_cap : off[v + 1]; };
  sent_.assign(std::size_t{1} << kSentBits, Remote{-1, -1});
  Remote* sent = sent_.data();
  for (std::size_t i = 0; i < nr; ++i)
    if (roots[i] >= first_ && roots[i] < first_ + nb_)
      visit(lab, lev, static_cast<std::int32_t>(roots[i] - first_), static_cast<std::int32_t>(kStages * i + stage),
            start[i]);
  for (std::int64_t level = 0;; ++level) {
    frontier_.swap(next_);
    const std::size_t nf = n_next_;
    const std::int32_t* fr = frontier_.data();
    n_next_ = 0;
    n_remote_ = 0;
    step_ = static_cast<std::int32_t>(level + 1);
    // The frontier is in no useful order: offsets, rows and the neighbours'
    // labels are fetched a few nodes ahead, as in bfs_partition.
    for (std::size_t h = 0; h < nf; ++h) {
      if (h + 12 < nf) __builtin_prefetch(off + fr[h + 12]);
      if (h + 6 < nf) __builtin_prefetch(adj + off[fr[h + 6]]);
      if (h + 3 < nf)
        for (std::int64_t k = off[fr[h + 3]], e = row_end(fr[h + 3]); k < e; ++k) {
          const auto d = static_cast<std::uint64_t>(static_cast<GlobalId>(adj[k]) - first_);
          if (d < static_cast<std::uint64_t>(nb_)) __builtin_prefetch(lab + d);
        }
      const std::int32_t v = fr[h], to = static_cast<std::int32_t>(lab[v]), lv = start_[to / kStages] + step_;
      const std::int64_t k0 = off[v], k1 = row_end(v);
      if (n_remote_ + static_cast<std::size_t>(k1 - k0) > remote_.size())
        remote_.resize(std::max(2 * remote_.size(), n_remote_ + static_cast<std::size_t>(k1 - k0)));
      Remote* rem = remote_.data();
      for (std::int64_t k = k0; k < k1; ++k) {
        const GlobalId u = static_cast<GlobalId>(adj[k]);
        const auto d = static_cast<std::uint64_t>(u - first_);
        if (d < static_cast<std::uint64_t>(nb_)) {
          visit(lab, lev, static_cast<std::int32_t>(d), to, lv);
          continue;
        }
        Remote& s = sent[(static_cast<std::uint64_t>(u) * 0x9E3779B97F4A7C15ULL ^
                          static_cast<std::uint64_t>(to) * 0xC2B2AE3D27D4EB4FULL) >>
                         (64 - kSentBits)];
        if (s.u == u && s.to == to) continue;
        s = {u, to};
        rem[n_remote_++] = {u, to};
      }
    }
    if (!exchange(nf)) break;
    if (level > max_levels_) return false;  // every rank: the frontiers' sum is global
  }
  far_level.resize(nr);
  far_gid.resize(nr);
  MPI_Allreduce(far_level_.data(), far_level.data(), static_cast<int>(nr), MPI_INT32_T, MPI_MAX, comm_);
  // The smallest id at each range's largest level, and the nodes reached.
  far_gid_.assign(nr, std::numeric_limits<GlobalId>::max());
  for (std::int32_t v = 0; v < nb_; ++v) {
    if (lab[v] == kDone || lab[v] % kStages != stage) continue;
    const auto i = static_cast<std::size_t>(range_of(v));
    if (lev[v] == far_level[i] && gid(v) < far_gid_[i]) far_gid_[i] = gid(v);
  }
  MPI_Allreduce(far_gid_.data(), far_gid.data(), static_cast<int>(nr), MPI_INT64_T, MPI_MIN, comm_);
  std::vector<long long> all(nr, 0);
  MPI_Allreduce(visited_.data(), all.data(), static_cast<int>(nr), MPI_LONG_LONG, MPI_SUM, comm_);
  if (reach) *reach = all;
  return true;
}

// The rounds of one depth: each range's components, a probe (or, where it
// died out early, a pass) from s and a pass from r each; base[i] the key
// after the last. False past max_levels.
template <class Index, class Label>
bool LevelBisection<Index, Label>::rounds(std::vector<std::int32_t>& base) {
  const std::size_t nr = ranges_.size();
  base.assign(nr, 0);
  std::vector<long long> left(nr), left_all(nr);
  std::vector<std::int64_t> deg(nr), deg_all(nr);
  std::vector<GlobalId> s(nr), r(nr), far_gid;
  std::vector<std::int32_t> far_level, zero(nr, 0);
  for (int round = 0; round < kRounds; ++round) {
    // s: the unvisited node of largest degree, smallest id on ties.
    std::fill(left.begin(), left.end(), 0);
    std::fill(deg.begin(), deg.end(), -1);
    std::fill(s.begin(), s.end(), std::numeric_limits<GlobalId>::max());
    for (std::int32_t v = 0; v < nb_; ++v) {
      if (label_[v] == kDone || label_[v] % kStages != kUnvisited) continue;
      const auto i = static_cast<std::size_t>(range_of(v));
      ++left[i];
      const std::int64_t d = lx_[v + 1] - lx_[v];
      if (d > deg[i]) deg[i] = d, s[i] = gid(v);  // ascending v: the first of a degree has the smallest id
    }
    MPI_Allreduce(left.data(), left_all.data(), static_cast<int>(nr), MPI_LONG_LONG, MPI_SUM, comm_);
    MPI_Allreduce(deg.data(), deg_all.data(), static_cast<int>(nr), MPI_INT64_T, MPI_MAX, comm_);
    bool any = false;
    for (std::size_t i = 0; i < nr; ++i) {
      const bool go = left_all[i] > 0 && (round == 0 || left_all[i] * 64 > ranges_[i].size);
      if (!go || deg[i] != deg_all[i]) s[i] = std::numeric_limits<GlobalId>::max();
      if (go) any = true;
    }
    if (!any) break;
    std::vector<GlobalId> roots(nr);
    MPI_Allreduce(s.data(), roots.data(), static_cast<int>(nr), MPI_INT64_T, MPI_MIN, comm_);
    for (std::size_t i = 0; i < nr; ++i)
      if (roots[i] == std::numeric_limits<GlobalId>::max()) roots[i] = -1;
    if (!far_roots(roots, left_all, zero, r)) return false;
    if (!pass(r, base, kOrdered, far_level, far_gid, nullptr)) return false;
    for (std::size_t i = 0; i < nr; ++i)
      if (r[i] >= 0) base[i] = far_level[i] + 1;
  }
  return true;
}

// r[i]: range i's node of smallest id farthest from s[i] (-1 where s[i] is),
// by the probe where it reached at least 1/kProbeShare of the left[i] unvisited
// nodes, else by a full pass from s[i] (also where the probe ran past
// max_levels: the nodes it marked are taken again). False where that pass
// did.
template <class Index, class Label>
bool LevelBisection<Index, Label>::far_roots(const std::vector<GlobalId>& s, const std::vector<long long>& left,
                                             const std::vector<std::int32_t>& zero, std::vector<GlobalId>& r) {
  const std::size_t nr = ranges_.size();
  std::vector<std::int32_t> far_level;
  std::vector<GlobalId> far_gid, again(nr, -1);
  std::vector<long long> reach;
  const bool probed = pass(s, zero, kProbed, far_level, far_gid, &reach);
  bool any = false;
  for (std::size_t i = 0; i < nr; ++i) {
    r[i] = -1;
    if (s[i] < 0) continue;
    if (probed && kProbeShare * reach[i] >= left[i]) {
      r[i] = far_gid[i];
    } else {
      again[i] = s[i];
      any = true;
    }
  }
  if (!any) return true;
  if (!pass(again, zero, kSwept, far_level, far_gid, nullptr)) return false;
  for (std::size_t i = 0; i < nr; ++i)
    if (again[i] >= 0) r[i] = far_gid[i];
  return true;
}

// For each range i with need[i] > 0: t[i], the smallest value in [0, hi[i]]
// with at least need[i] items of i at or below it; below[i] and at[i], the
// items of i under it and at it. items(f) calls f(i, value) for every local item. A
// multiway search: each round counts the items in kBins bins of the interval
// left and keeps the bin where the count is reached.
template <class Index, class Label>
template <class Items>
void LevelBisection<Index, Label>::select(const std::vector<std::int64_t>& need, std::vector<std::int64_t> hi,
                                          std::vector<std::int64_t>& t, std::vector<std::int64_t>& below,
                                          std::vector<std::int64_t>& at, Items&& items) {
  const std::size_t nr = need.size();
  const std::size_t w = static_cast<std::size_t>(kBins) + 1;  // [0]: items under lo
  std::vector<std::int64_t> lo(nr, 0), width(nr, 1);
  std::vector<long long> cnt(nr * w), all(nr * w);
  std::vector<char> open(nr);
  t.assign(nr, -1);
  below.assign(nr, 0);
  at.assign(nr, 0);
  for (std::size_t i = 0; i < nr; ++i) open[i] = need[i] > 0;
  while (std::find(open.begin(), open.end(), 1) != open.end()) {
    for (std::size_t i = 0; i < nr; ++i) width[i] = std::max<std::int64_t>(1, (hi[i] - lo[i] + kBins) / kBins);
    std::fill(cnt.begin(), cnt.end(), 0);
    items([&](std::size_t i, std::int64_t x) {
      if (!open[i] || x > hi[i]) return;
      ++cnt[i * w + (x < lo[i] ? 0 : 1 + static_cast<std::size_t>((x - lo[i]) / width[i]))];
    });
    MPI_Allreduce(cnt.data(), all.data(), static_cast<int>(cnt.size()), MPI_LONG_LONG, MPI_SUM, comm_);
    for (std::size_t i = 0; i < nr; ++i) {
      if (!open[i]) continue;
      long long c = all[i * w];
      std::size_t b = 0;
      while (b + 1 < static_cast<std::size_t>(kBins) && c + all[i * w + 1 + b] < need[i]) c += all[i * w + 1 + b++];
      lo[i] += static_cast<std::int64_t>(b) * width[i];
      if (width[i] == 1) {
        t[i] = lo[i];
        below[i] = c;
        at[i] = all[i * w + 1 + b];
        open[i] = 0;
      } else {
        hi[i] = std::min(hi[i], lo[i] + width[i] - 1);
      }
    }
  }
}

// Each range's first nodes by (key, id) to its lower parts; the next depth's
// ranges, and the owners of the nodes whose range has one part. Where a
// level boundary is within size / kLevelSlack of the proportional count, the
// split is there instead: splitting a level by id leaves a random half of it
// on each side (edge cut +15% at 10M sensors, +48% at 1M, on 2 ranks;
// docs/design.md, "Partitioning").
template <class Index, class Label>
void LevelBisection<Index, Label>::split(const std::vector<std::int32_t>& base, std::vector<int>& owner) {
  const std::size_t nr = ranges_.size();
  std::vector<std::int64_t> need(nr), hi(nr), kt, kbelow, kat, gt, gbelow, gat;
  for (std::size_t i = 0; i < nr; ++i) {
    const Range& g = ranges_[i];
    const int pm = g.p0 + (g.p1 - g.p0) / 2;
    need[i] = g.size * (pm - g.p0) / (g.p1 - g.p0);
    hi[i] = base[i];
  }
  auto key = [&](std::int32_t v) -> std::int64_t {
    return label_[v] % kStages == kOrdered ? level_[v] : base[range_of(v)];
  };
  select(need, hi, kt, kbelow, kat, [&](auto&& f) {
    for (std::int32_t v = 0; v < nb_; ++v)
      if (label_[v] != kDone) f(static_cast<std::size_t>(range_of(v)), key(v));
  });
  // lower: the count of the lower half; mode: 0 by (key, id), 1 key < t, 2 key <= t.
  std::vector<std::int64_t> lower(need), need_id(nr, 0);
  std::vector<int> mode(nr, 0);
  for (std::size_t i = 0; i < nr; ++i) {
    if (need[i] == 0) continue;
    const std::int64_t slack = ranges_[i].size / kLevelSlack, lo = kbelow[i], up = kbelow[i] + kat[i];
    if (need[i] - lo <= slack || up - need[i] <= slack) {
      mode[i] = need[i] - lo <= up - need[i] ? 1 : 2;
      lower[i] = mode[i] == 1 ? lo : up;
    } else {
      need_id[i] = need[i] - kbelow[i];
    }
  }
  // Otherwise, among the nodes at the key t, those of smallest id.
  std::vector<std::int64_t> hi_id(nr, blocks_.first.back() - 1);
  select(need_id, hi_id, gt, gbelow, gat, [&](auto&& f) {
    for (std::int32_t v = 0; v < nb_; ++v)
      if (label_[v] != kDone && key(v) == kt[range_of(v)]) f(static_cast<std::size_t>(range_of(v)), gid(v));
  });
  // Children: lower then upper half of each range; those of one part (or no
  // node) are done.
  std::vector<Range> next;
  std::vector<std::int32_t> child(2 * nr, -1);
  for (std::size_t i = 0; i < nr; ++i) {
    const Range& g = ranges_[i];
    const int pm = g.p0 + (g.p1 - g.p0) / 2;
    const Range half[2] = {{lower[i], g.p0, pm}, {g.size - lower[i], pm, g.p1}};
    for (int c = 0; c < 2; ++c)
      if (half[c].p1 - half[c].p0 > 1 && half[c].size > 0) {
        child[2 * i + c] = static_cast<std::int32_t>(next.size());
        next.push_back(half[c]);
      }
  }
  for (std::int32_t v = 0; v < nb_; ++v) {
    if (label_[v] == kDone) continue;
    const auto i = static_cast<std::size_t>(range_of(v));
    const std::int64_t k = key(v);
    const bool low = mode[i] == 1   ? k < kt[i]
                     : mode[i] == 2 ? k <= kt[i]
                                    : need[i] > 0 && (k < kt[i] || (k == kt[i] && gid(v) <= gt[i]));
    const int c = low ? 0 : 1;
    const Range& g = ranges_[i];
    if (child[2 * i + c] >= 0) {
      label_[v] = static_cast<Label>(kStages * child[2 * i + c]);
    } else {
      owner[v] = low ? g.p0 : g.p0 + (g.p1 - g.p0) / 2;
      label_[v] = kDone;
      level_[v] = static_cast<std::int32_t>(k);  // the key its part was decided by (keys())
    }
  }
  ranges_ = std::move(next);
}

template <class Index, class Label>
bool LevelBisection<Index, Label>::run(int nparts, std::vector<int>& owner) {
  owner.assign(static_cast<std::size_t>(nb_), 0);
  const GlobalId n = blocks_.first.back();
  if (nparts <= 1 || n == 0) return true;
  ranges_ = {{n, 0, nparts}};
  std::vector<std::int32_t> base;
  while (!ranges_.empty()) {
    if (!rounds(base)) return false;
    split(base, owner);
    ++depth_;
  }
  return true;
}

}  // namespace

template <class Index>
bool level_bisection(MPI_Comm comm, const Blocks& blocks, const std::vector<std::int64_t>& lx,
                     const std::vector<Index>& ladj, int nparts, std::int64_t max_levels, std::vector<int>& owner,
                     std::int64_t& bytes, std::vector<std::int32_t>* keys) {
  auto run = [&](auto& lb) {
    const bool ok = lb.run(nparts, owner);
    bytes = lb.bytes() + static_cast<std::int64_t>(owner.capacity() * sizeof(int));
    if (ok && keys) *keys = lb.keys();
    return ok;
  };
  if (nparts <= kByteLabelParts) {
    LevelBisection<Index, std::uint8_t> lb(comm, blocks, lx, ladj, max_levels);
    return run(lb);
  }
  LevelBisection<Index, std::int32_t> lb(comm, blocks, lx, ladj, max_levels);
  return run(lb);
}

template bool level_bisection<std::int32_t>(MPI_Comm, const Blocks&, const std::vector<std::int64_t>&,
                                            const std::vector<std::int32_t>&, int, std::int64_t, std::vector<int>&,
                                            std::int64_t&, std::vector<std::int32_t>*);
template bool level_bisection<GlobalId>(MPI_Comm, const Blocks&, const std::vector<std::int64_t>&,
                                        const std::vector<GlobalId>&, int, std::int64_t, std::vector<int>&,
                                        std::int64_t&, std::vector<std::int32_t>*);

std::int64_t default_max_levels(GlobalId n) {
  return std::max<std::int64_t>(std::int64_t{1} << 14, static_cast<std::int64_t>(4 * std::sqrt(static_cast<double>(n))));
}

}  // namespace snl::detail
