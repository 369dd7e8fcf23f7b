// The distance-vector start (dv_start.hpp): anchor path lists by a
// synchronous distributed Bellman-Ford, their calibration, multilateration.
#include "snl/solvers/dv_start.hpp"

#include <mpi.h>

#include <algorithm>
#include <cmath>

#include "core/exact_sum.hpp"
#include "snl/core/mpi_util.hpp"
#include "snl/solvers/solver.hpp"

namespace snl {

namespace {

// A sensor's list: up to k (id, distance) entries ascending by (distance, id),
// one entry per anchor. offer() keeps the k best of everything offered, in any
// order of offers (an anchor pushed out never comes back: k better ones stay).
struct List {
  std::int32_t* id;
  double* d;
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
      --at;
    }
    id[at] = a;
    d[at] = dist;
    return true;
  }
};

// Bit t: entry t of l is not in `before` (a row: (id, distance) x k).
std::uint16_t new_entries(const List& l, const double* before) {
  std::uint16_t m = 0;
  for (int t = 0; t < l.k && l.id[t] >= 0; ++t) {
    bool seen = false;
    for (int s = 0; s < l.k && !seen; ++s) seen = before[2 * s] == l.id[t] && before[2 * s + 1] == l.d[t];
    if (!seen) m |= std::uint16_t(1u << t);
  }
  return m;
}

}  // namespace

int dv_start_anchors(int dim) { return 3 * dim; }

AnchorPaths nearest_anchor_paths(LocalizationProblem& prob, int k) {
  const DistGraph& g = prob.graph();
  const LocalId n = g.num_owned(), nl = g.num_local();
  const int w = 2 * k + 1;  // the exchanged row: (id, distance) x k, then "changed last round"
  AnchorPaths out;
  out.k = k;
  out.ids.assign(std::size_t(n) * k, -1);
  out.dist.assign(std::size_t(n) * k, 0.0);
  // Round 0: each sensor's own anchor measurements.
  const auto& aoff = prob.anchor_offsets();
  for (LocalId v = 0; v < n; ++v) {
    List l{&out.ids[std::size_t(v) * k], &out.dist[std::size_t(v) * k], k};
    for (auto e = aoff[v]; e < aoff[v + 1]; ++e) l.offer(prob.anchor_ids()[e], prob.anchor_ranges()[e]);
  }
  // rows: the lists as the previous round left them (a snapshot the round
  // reads, so that every list is updated from its neighbours' previous lists
  // whichever rank owns them), with a mask of the entries that are new since
  // the round before: only those are offered (an entry offered once and
  // refused stays refused, as lists only improve). fresh: that mask per local
  // node, in a small array the neighbour loops read instead of the rows.
  static_assert(sizeof(std::uint16_t) * 8 >= 9, "3p entries in 3D");
  std::vector<double> rows(std::size_t(nl) * w, -1.0);  // ids -1: no entry
  for (LocalId u = 0; u < nl; ++u) rows[std::size_t(u) * w + 2 * k] = 0;  // masks
  std::vector<std::uint16_t> fresh(nl, 0), was(n, 0), next(n, 0);
  for (LocalId v = 0; v < n; ++v)
    for (int t = 0; t < k; ++t)
      if (out.ids[std::size_t(v) * k + t] >= 0) fresh[v] |= std::uint16_t(1u << t);
  const auto& off = g.offsets();
  const auto& adj = g.adjacency();
  HaloPlan& halo = prob.graph().halo();
  for (;;) {
    for (LocalId v = 0; v < n; ++v) {
      if (!fresh[v] && !was[v]) continue;  // the row holds this list, mask 0
      double* r = &rows[std::size_t(v) * w];
      for (int t = 0; t < k; ++t) {
        r[2 * t] = out.ids[std::size_t(v) * k + t];
        r[2 * t + 1] = out.dist[std::size_t(v) * k + t];
      }
      r[2 * k] = fresh[v];
    }
    halo.exchange(rows.data(), w);
    ++out.rounds;
    for (LocalId u = n; u < nl; ++u) fresh[u] = static_cast<std::uint16_t>(rows[std::size_t(u) * w + 2 * k]);
    std::copy(fresh.begin(), fresh.begin() + n, was.begin());  // the masks the rows now hold
    std::int64_t moved = 0;
    for (LocalId v = 0; v < n; ++v) {
      List l{&out.ids[std::size_t(v) * k], &out.dist[std::size_t(v) * k], k};
      bool any = false;
      for (auto e = off[v]; e < off[v + 1]; ++e) {
        const LocalId u = adj[e];
        const unsigned m = fresh[u];
        if (!m) continue;  // nothing new since it was last offered
        const double* r = &rows[std::size_t(u) * w];
        const double dvu = g.edge_value(e);
        for (unsigned b = m; b; b &= b - 1) {  // the set bits, lowest first (a data-dependent test per bit mispredicts)
          const int t = __builtin_ctz(b);
          if (r[2 * t] >= 0) any |= l.offer(static_cast<std::int32_t>(r[2 * t]), r[2 * t + 1] + dvu);
        }
      }
      // Not fresh[v]: later nodes of this round read the previous round's masks.
      next[v] = any ? new_entries(l, &rows[std::size_t(v) * w]) : 0;
      moved += any;
    }
    std::copy(next.begin(), next.end(), fresh.begin());
    long long all = 0, mine = moved;
    MPI_Allreduce(&mine, &all, 1, MPI_LONG_LONG, MPI_SUM, prob.comm());
    if (all == 0) break;
  }
  return out;
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
    for (int a = 0; a < P; ++a) x[a] -= scale * s[a];
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
