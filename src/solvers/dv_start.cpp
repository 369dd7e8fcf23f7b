// The distance-vector start (dv_start.hpp): anchor path lists by a synchronous
// distributed label-correcting search in distance order, their calibration,
// multilateration.
#include "snl/solvers/dv_start.hpp"

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "core/exact_sum.hpp"
#include "snl/core/mpi_util.hpp"
#include "snl/solvers/solver.hpp"

namespace snl {

namespace {

// A sensor's list: up to k (id, distance) entries ascending by (distance, id),
// one entry per anchor, each with a flag "offered to the neighbours". offer()
// keeps the k best of everything offered, in any order of offers (an anchor
// pushed out never comes back: k better ones stay); a new or shortened entry
// is not yet offered.
struct List {
  std::int32_t* id;
  double* d;
  std::uint8_t* sent;
  int k;
  bool offer(std::int32_t a, double dist) {
    // Beyond a full list's last distance: neither a new entry nor shorter.
    if (id[k - 1] >= 0 && dist > d[k - 1]) return false;
    int at = -1;
    for (int t = 0; t < k && id[t] >= 0; ++t)
      if (id[t] == a) at = t;
    if (at >= 0) {
      if (!(dist < d[at])) return false;
    } else {
      at = k - 1;
      if (id[at] >= 0 && !(dist < d[at] || (dist == d[at] && a < id[at]))) return false;
    }
    // Move the entry up to its place.
    while (at > 0 && (id[at - 1] < 0 || dist < d[at - 1] || (dist == d[at - 1] && a < id[at - 1]))) {
      id[at] = id[at - 1];
      d[at] = d[at - 1];
      sent[at] = sent[at - 1];
      --at;
    }
    id[at] = a;
    d[at] = dist;
    sent[at] = 0;
    return true;
  }
};

// Per ghost (CSR by `offsets`), its owned neighbours and their edge to it:
// the owned lists a ghost's offers go to.
struct GhostEdges {
  struct Edge {
    LocalId owned;
    std::int64_t edge;
  };
  std::vector<std::int64_t> offsets;
  std::vector<Edge> edges;

  explicit GhostEdges(const DistGraph& g) {
    const LocalId n = g.num_owned(), ng = g.num_local() - n;
    const auto& off = g.offsets();
    const auto& adj = g.adjacency();
    offsets.assign(std::size_t(ng) + 1, 0);
    for (LocalId v = g.num_interior(); v < n; ++v)
      for (auto e = off[v]; e < off[v + 1]; ++e)
        if (adj[e] >= n) ++offsets[std::size_t(adj[e] - n) + 1];
    for (LocalId q = 0; q < ng; ++q) offsets[q + 1] += offsets[q];
    edges.resize(std::size_t(offsets[ng]));
    std::vector<std::int64_t> at(offsets.begin(), offsets.end() - 1);
    for (LocalId v = g.num_interior(); v < n; ++v)
      for (auto e = off[v]; e < off[v + 1]; ++e)
        if (adj[e] >= n) edges[std::size_t(at[adj[e] - n]++)] = {v, e};
  }
};

// The search for the k nearest anchors of every owned sensor, a label-
// correcting search in distance order (Delta-stepping's idea, Meyer & Sanders,
// J. Algorithms 49, 2003): an entry is offered once the round's threshold
// reaches its distance, the threshold growing by kStep of the longest range
// per round, or jumping to the nearest entry not yet offered. Bellman-Ford,
// offering every entry at once, ends in the same lists (the k nearest anchors
// by shortest path are the one fixed point whatever the order of the offers,
// and each path's length is summed from its anchor in the same order), but
// most of its entries come on paths of few hops and are replaced by shorter
// ones rounds later: in distance order about a quarter as many are offered,
// for a few more rounds.
//
// rows: a snapshot of the entries each list offers this round (their mask
// last), taken before any list of the round changes, so that each round's
// lists are the k best of the last round's and their neighbours' offers
// whichever rank owns them. Offers are pushed from the lists that offer to
// their neighbours (a ghost's through GhostEdges), so that a round costs what
// it offers. pending: the nearest entry a list has not offered (infinity: none).
class PathSearch {
 public:
  static constexpr double kStep = 0.15;

  PathSearch(LocalizationProblem& prob, int k)
      : prob_(prob), g_(prob.graph()), k_(k), w_(2 * k + 1), n_(g_.num_owned()), ghosts_(g_) {
    out_.k = k;
    out_.ids.assign(std::size_t(n_) * k, -1);
    out_.dist.assign(std::size_t(n_) * k, 0.0);
    sent_.assign(std::size_t(n_) * k, 0);
    rows_.assign(std::size_t(g_.num_local()) * w_, -1.0);  // ids -1: no entry
    for (LocalId u = 0; u < g_.num_local(); ++u) rows_[std::size_t(u) * w_ + 2 * k] = 0;  // masks
    is_changed_.assign(n_, 0);
  }

  /// Round 0: each sensor's own anchor measurements. Returns the threshold's step.
  double seed_lists() {
    const auto& aoff = prob_.anchor_offsets();
    double longest = 0;  // the longest measured range
    for (LocalId v = 0; v < n_; ++v) {
      List l = list(v);
      for (auto e = aoff[v]; e < aoff[v + 1]; ++e) {
        l.offer(prob_.anchor_ids()[e], prob_.anchor_ranges()[e]);
        longest = std::max(longest, prob_.anchor_ranges()[e]);
      }
    }
    for (std::size_t e = 0; e < g_.adjacency().size(); ++e) longest = std::max(longest, g_.edge_value(e));
    MPI_Allreduce(MPI_IN_PLACE, &longest, 1, MPI_DOUBLE, MPI_MAX, prob_.comm());
    pending_.resize(n_);
    for (LocalId v = 0; v < n_; ++v) pending_[v] = nearest_unsent(v);
    return kStep * longest;
  }

  /// The entries within `reach` not yet offered go into their lists' rows,
  /// marked offered; the rows go to the ranks that hold them as ghosts.
  void post(double reach) {
    for (const LocalId v : senders_) rows_[std::size_t(v) * w_ + 2 * k_] = 0;  // last round's masks, cleared
    senders_.clear();
    for (LocalId v = 0; v < n_; ++v) {
      if (!(pending_[v] <= reach)) continue;
      List l = list(v);
      unsigned m = 0;
      for (int t = 0; t < k_ && l.id[t] >= 0; ++t)
        if (!l.sent[t] && l.d[t] <= reach) {
          m |= 1u << t;
          l.sent[t] = 1;
        }
      double* r = &rows_[std::size_t(v) * w_];
      for (unsigned b = m; b; b &= b - 1) {
        const int t = __builtin_ctz(b);
        r[2 * t] = l.id[t];
        r[2 * t + 1] = l.d[t];
      }
      r[2 * k_] = m;
      senders_.push_back(v);
      pending_[v] = nearest_unsent(v);
    }
    g_.halo().exchange(rows_.data(), w_);
    ++out_.rounds;
  }

  /// The posted entries offered to every neighbouring owned list.
  void push() {
    const auto& off = g_.offsets();
    const auto& adj = g_.adjacency();
    for (const LocalId u : senders_) {
      const double* r = &rows_[std::size_t(u) * w_];
      const auto m = static_cast<unsigned>(r[2 * k_]);
      for (auto e = off[u]; e < off[u + 1]; ++e)
        if (adj[e] < n_) offer(r, m, adj[e], g_.edge_value(e));
    }
    for (LocalId q = 0; q < g_.num_local() - n_; ++q) {
      const double* r = &rows_[std::size_t(n_ + q) * w_];
      const auto m = static_cast<unsigned>(r[2 * k_]);
      if (!m) continue;
      for (auto j = ghosts_.offsets[q]; j < ghosts_.offsets[q + 1]; ++j) {
        const GhostEdges::Edge& ge = ghosts_.edges[std::size_t(j)];
        offer(r, m, ge.owned, g_.edge_value(ge.edge));
      }
    }
    for (const LocalId v : changed_) {
      is_changed_[v] = 0;
      pending_[v] = nearest_unsent(v);
    }
    changed_.clear();
  }

  /// Collective: the nearest entry not yet offered on any rank, and whether any is left.
  std::pair<double, bool> nearest_pending() const {
    double mine[2] = {INFINITY, 0};  // the nearest entry not offered; minus the lists with one
    for (LocalId v = 0; v < n_; ++v)
      if (pending_[v] < INFINITY) {
        mine[0] = std::min(mine[0], pending_[v]);
        mine[1] -= 1;
      }
    MPI_Allreduce(MPI_IN_PLACE, mine, 2, MPI_DOUBLE, MPI_MIN, prob_.comm());
    return {mine[0], mine[1] != 0};
  }

  AnchorPaths take() { return std::move(out_); }

 private:
  List list(LocalId v) {
    const std::size_t at = std::size_t(v) * k_;
    return List{&out_.ids[at], &out_.dist[at], &sent_[at], k_};
  }
  double nearest_unsent(LocalId v) {
    const List l = list(v);
    for (int t = 0; t < k_ && l.id[t] >= 0; ++t)
      if (!l.sent[t]) return l.d[t];  // ascending: the first is the nearest
    return INFINITY;
  }
  // The entries of row r in mask m offered to v across a range dvu (a pair's
  // range is the same from either end).
  void offer(const double* r, unsigned m, LocalId v, double dvu) {
    List l = list(v);
    bool any = false;
    for (unsigned b = m; b; b &= b - 1) {  // the set bits, lowest first
      const int t = __builtin_ctz(b);
      any |= l.offer(static_cast<std::int32_t>(r[2 * t]), r[2 * t + 1] + dvu);
    }
    if (any && !is_changed_[v]) {
      is_changed_[v] = 1;
      changed_.push_back(v);
    }
  }

  LocalizationProblem& prob_;
  DistGraph& g_;
  const int k_, w_;  // w_: the exchanged row, (id, distance) x k, then the mask of entries offered
  const LocalId n_;
  const GhostEdges ghosts_;
  AnchorPaths out_;
  std::vector<std::uint8_t> sent_;  // per entry: offered to the neighbours
  std::vector<double> rows_, pending_;
  std::vector<LocalId> senders_, changed_;  // this round's lists that offer; lists that took an offer
  std::vector<std::uint8_t> is_changed_;
};

}  // namespace

int dv_start_anchors(int dim) { return 3 * dim; }

AnchorPaths nearest_anchor_paths(LocalizationProblem& prob, int k) {
  PathSearch search(prob, k);
  const double step = search.seed_lists();
  double reach = step;  // the round's threshold
  for (;;) {
    search.post(reach);
    search.push();
    const auto [nearest, left] = search.nearest_pending();
    if (!left) break;  // every entry offered, none taken since
    reach = std::max(reach + step, nearest);
  }
  return search.take();
}

namespace {
struct PairPath {
  std::int64_t key;  // a * m + b, a < b
  double path;
};
}  // namespace

double path_correction(LocalizationProblem& prob, const AnchorPaths& paths) {
  const int P = comm_size(prob.comm()), p = prob.dim(), k = paths.k;
  const std::int64_t m = prob.num_anchors();
  const auto& aoff = prob.anchor_offsets();
  // This rank's shortest a -> b paths: a measured by a sensor, b in its list.
  std::vector<PairPath> mine;
  for (LocalId v = 0; v < prob.num_owned(); ++v)
    for (auto e = aoff[v]; e < aoff[v + 1]; ++e) {
      const std::int64_t a = prob.anchor_ids()[e];
      for (int t = 0; t < k; ++t) {
        const std::int64_t b = paths.ids[std::size_t(v) * k + t];
        if (b < 0 || b == a) continue;
        mine.push_back({std::min(a, b) * m + std::max(a, b), prob.anchor_ranges()[e] + paths.dist[std::size_t(v) * k + t]});
      }
    }
  auto shortest = [](std::vector<PairPath>& v) {
    std::sort(v.begin(), v.end(), [](const PairPath& x, const PairPath& y) {
      return x.key < y.key || (x.key == y.key && x.path < y.path);
    });
    v.erase(std::unique(v.begin(), v.end(), [](const PairPath& x, const PairPath& y) { return x.key == y.key; }),
            v.end());
  };
  shortest(mine);
  std::vector<std::vector<PairPath>> out(P);
  for (const auto& q : mine) out[static_cast<std::size_t>(q.key % P)].push_back(q);
  mine.clear();
  std::vector<PairPath> got = exchange_records(prob.comm(), out);
  shortest(got);
  detail::ExactSum sums[2];  // straight, path: the same factor for any partition
  const auto& an = prob.anchors();
  for (const auto& q : got) {
    const std::int64_t a = q.key / m, b = q.key % m;
    double s = 0;
    for (int c = 0; c < p; ++c) s += (an[a * p + c] - an[b * p + c]) * (an[a * p + c] - an[b * p + c]);
    sums[0].add(std::sqrt(s));
    sums[1].add(q.path);
  }
  detail::allreduce_exact(sums, 2, prob.comm());
  const double c = sums[0].value() / sums[1].value();
  return std::isfinite(c) && c > 0 ? c : 1.0;
}

namespace {

// Solves the p x p system H s = g (p <= 3) by Gaussian elimination with partial pivoting.
template <int P>
void solve_small(double (&H)[P][P], double (&g)[P], double (&s)[P]) {
  for (int i = 0; i < P; ++i) {
    int piv = i;
    for (int r = i + 1; r < P; ++r)
      if (std::fabs(H[r][i]) > std::fabs(H[piv][i])) piv = r;
    for (int c = 0; c < P; ++c) std::swap(H[i][c], H[piv][c]);
    std::swap(g[i], g[piv]);
    for (int r = i + 1; r < P; ++r) {
      const double f = H[r][i] / H[i][i];
      for (int c = i; c < P; ++c) H[r][c] -= f * H[i][c];
      g[r] -= f * g[i];
    }
  }
  for (int i = P - 1; i >= 0; --i) {
    double t = g[i];
    for (int c = i + 1; c < P; ++c) t -= H[i][c] * s[c];
    s[i] = t / H[i][i];
  }
}

// min_x sum_t w_t (|x - a_t| - r_t)^2, w_t = 1 / r_t^2 (near anchors count
// most: their paths are nearly straight), from the weighted centroid by
// damped Gauss-Newton (Levenberg's 0.1 tr(H) on the diagonal: with anchors
// on one side the normal matrix is nearly singular), each step at most half
// the shortest range so that no step jumps across an anchor.
template <int P>
void place(const double* an, const std::int32_t* id, const double* dist, int k, double c, double* x) {
  double wsum = 0, rmin = INFINITY, cen[P] = {};
  double r[16], wt[16];
  int cnt = 0;
  for (int t = 0; t < k && id[t] >= 0; ++t, ++cnt) {
    r[t] = c * dist[t];
    wt[t] = 1.0 / std::max(r[t] * r[t], 1e-300);
    rmin = std::min(rmin, r[t]);
    wsum += wt[t];
    for (int q = 0; q < P; ++q) cen[q] += wt[t] * an[std::size_t(id[t]) * P + q];
  }
  for (int q = 0; q < P; ++q) x[q] = cen[q] / wsum;
  constexpr int kSteps = 20;
  for (int it = 0; it < kSteps; ++it) {
    double H[P][P] = {}, g[P] = {}, s[P] = {};
    for (int t = 0; t < cnt; ++t) {
      double z[P], nz = 0;
      for (int q = 0; q < P; ++q) {
        z[q] = x[q] - an[std::size_t(id[t]) * P + q];
        nz += z[q] * z[q];
      }
      nz = std::sqrt(nz);
      if (!(nz > 0)) continue;  // on the anchor: no direction
      for (int q = 0; q < P; ++q) z[q] /= nz;
      for (int a = 0; a < P; ++a) {
        g[a] += wt[t] * (nz - r[t]) * z[a];
        for (int b = 0; b < P; ++b) H[a][b] += wt[t] * z[a] * z[b];
      }
    }
    double tr = 0;
    for (int a = 0; a < P; ++a) tr += H[a][a];
    if (!(tr > 0)) break;
    for (int a = 0; a < P; ++a) H[a][a] += 0.1 * tr;
    solve_small<P>(H, g, s);
    double ns = 0;
    for (int a = 0; a < P; ++a) ns += s[a] * s[a];
    ns = std::sqrt(ns);
    const double scale = ns > 0.5 * rmin ? 0.5 * rmin / ns : 1.0;
    bool moved = false;
    for (int a = 0; a < P; ++a) {
      const double xa = x[a] - scale * s[a];
      moved |= xa != x[a];
      x[a] = xa;
    }
    if (!moved) break;  // a fixed point: the remaining steps would repeat this one
  }
}

}  // namespace

std::vector<double> multilaterate(const LocalizationProblem& prob, const AnchorPaths& paths, double correction,
                                  const std::vector<double>& fallback) {
  const int p = prob.dim(), k = paths.k;
  if (k > 16) throw Error("multilaterate: at most 16 anchors per sensor");
  std::vector<double> x(fallback.begin(), fallback.begin() + std::size_t(prob.num_owned()) * p);
  for (LocalId v = 0; v < prob.num_owned(); ++v) {
    const std::int32_t* id = &paths.ids[std::size_t(v) * k];
    if (id[0] < 0) continue;
    const double* d = &paths.dist[std::size_t(v) * k];
    double* xv = &x[std::size_t(v) * p];
    const double* an = prob.anchors().data();
    switch (p) {
      case 1: place<1>(an, id, d, k, correction, xv); break;
      case 2: place<2>(an, id, d, k, correction, xv); break;
      case 3: place<3>(an, id, d, k, correction, xv); break;
      default: throw Error("multilaterate: dimension must be 1, 2 or 3");
    }
  }
  return x;
}

std::vector<double> dv_initial_positions(LocalizationProblem& prob, std::uint64_t seed, DvStartReport* report) {
  const double t0 = MPI_Wtime();
  HaloPlan& halo = prob.graph().halo();
  const std::int64_t b0 = halo.bytes_sent();
  const AnchorPaths paths = nearest_anchor_paths(prob, dv_start_anchors(prob.dim()));
  const std::int64_t b1 = halo.bytes_sent() - b0;
  const double t1 = MPI_Wtime();
  const double c = path_correction(prob, paths);
  const double t2 = MPI_Wtime();
  std::vector<double> x = multilaterate(prob, paths, c, random_initial_positions(prob, seed));
  if (report) {
    long long none = 0, bytes = b1, all[2];
    for (LocalId v = 0; v < prob.num_owned(); ++v) none += paths.ids[std::size_t(v) * paths.k] < 0;
    long long mine[2] = {none, bytes};
    MPI_Allreduce(mine, all, 2, MPI_LONG_LONG, MPI_SUM, prob.comm());
    report->rounds = paths.rounds;
    report->correction = c;
    report->without_anchor = all[0];
    report->mpi_bytes = all[1];
    report->seconds = MPI_Wtime() - t0;
    report->paths_seconds = t1 - t0;
    report->correction_seconds = t2 - t1;
    report->multilateration_seconds = MPI_Wtime() - t2;
  }
  return x;
}

}  // namespace snl
