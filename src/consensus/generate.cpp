// Random consensus problems (docs/consensus.md, "Generator"): a random
// geometric graph in the unit square with the requested average degree, made
// connected by linking components through their nearest pairs, an optional
// planted Hamilton path, and random local objectives of one family. Every
// random value is a pure function of (seed, stream, counter): deterministic in
// the seed, independent of drawing order.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <sstream>
#include <tuple>
#include <vector>

#include "consensus/problem_detail.hpp"
#include "snl/consensus/problem.hpp"
#include "snl/core/random.hpp"

namespace snl::consensus {

void GenerateOptions::validate() const {
  std::ostringstream os;
  if (nodes < 2) {
    os << "--nodes must be at least 2 (got " << nodes << ")";
  } else if (nodes > kMaxNodes) {
    os << "--nodes must be at most " << kMaxNodes << " (got " << nodes << ")";
  } else if (!std::isfinite(avg_degree) || avg_degree < 0) {
    os << "--avg-degree must be a finite number >= 0 (got " << avg_degree << ")";
  } else if (avg_degree > static_cast<double>(nodes - 1)) {
    os << "--avg-degree " << avg_degree << " is impossible with " << nodes << " nodes (at most " << nodes - 1 << ")";
  } else if (dim < 1 || dim > kMaxDim) {
    os << "--dim must be in [1, " << kMaxDim << "] (got " << dim << ")";
  } else if (family == Family::kExp && dim != 1) {
    os << "--dim must be 1 for family exp (got " << dim << ")";
  } else if (has_samples(family) && samples_per_node < 0) {
    os << "--samples-per-node must be >= 0 (got " << samples_per_node << ")";
  } else if (has_samples(family) &&
             static_cast<double>(samples_per_node) * static_cast<double>(nodes) * dim > 4e9) {
    os << "--samples-per-node " << samples_per_node << " with " << nodes << " nodes and dim " << dim
       << " would need more than 4e9 feature values";
  } else if (has_samples(family) && (!std::isfinite(lambda) || !(lambda > 0))) {
    os << "--lambda must be a finite number > 0 (got " << lambda << ")";
  }
  if (!os.str().empty()) throw Error(os.str());
}

namespace {

// Streams of the consensus generator, apart from the localization generator's (1..8).
constexpr RngStream kPositions = static_cast<RngStream>(101);
constexpr RngStream kPath = static_cast<RngStream>(102);
constexpr RngStream kParams = static_cast<RngStream>(103);
constexpr RngStream kTrueWeights = static_cast<RngStream>(104);
constexpr RngStream kFeatures = static_cast<RngStream>(105);
constexpr RngStream kLabels = static_cast<RngStream>(106);

constexpr double kPi = 3.14159265358979323846;

// Mean measure of {y in [0,1]^2 : |x - y| <= r} for x uniform in the square and
// r <= 1 (boundary included), as in the localization generator.
double mean_disc_fraction(double r) { return kPi * r * r - 8.0 / 3.0 * r * r * r + 0.5 * r * r * r * r; }

/// Radius whose expected degree is deg; above sqrt(2) (every pair) if none <= 1 is.
double radius_for_degree(double n, double deg) {
  if (deg <= 0) return 0;
  if ((n - 1) * mean_disc_fraction(1.0) < deg) return 1.5;
  double lo = 0, hi = 1;
  for (int it = 0; it < 60; ++it) {
    const double mid = 0.5 * (lo + hi);
    ((n - 1) * mean_disc_fraction(mid) < deg ? lo : hi) = mid;
  }
  return hi;
}

/// Points bucketed into g x g cells of side >= the link radius (counting sort).
struct Grid {
  int g = 1;
  std::vector<std::int64_t> start;  // [g*g + 1]
  std::vector<std::int32_t> id;     // point ids in cell order
  const std::vector<double>* pts = nullptr;

  int coord(double x) const { return std::min(g - 1, std::max(0, static_cast<int>(x * g))); }
  std::size_t cell(int cx, int cy) const { return static_cast<std::size_t>(cy) * g + cx; }

  Grid(const std::vector<double>& p, double r) : pts(&p) {
    const std::size_t n = p.size() / 2;
    double gd = std::floor(std::sqrt(static_cast<double>(n)));  // about one point per cell
    if (r > 0) gd = std::min(gd, std::floor(1.0 / r));
    g = static_cast<int>(std::max(1.0, gd));
    start.assign(static_cast<std::size_t>(g) * g + 1, 0);
    std::vector<std::uint32_t> c(n);
    for (std::size_t i = 0; i < n; ++i) {
      c[i] = static_cast<std::uint32_t>(cell(coord(p[2 * i]), coord(p[2 * i + 1])));
      ++start[c[i] + 1];
    }
    for (std::size_t k = 0; k + 1 < start.size(); ++k) start[k + 1] += start[k];
    id.resize(n);
    std::vector<std::int64_t> fill(start.begin(), start.end() - 1);
    for (std::size_t i = 0; i < n; ++i) id[fill[c[i]]++] = static_cast<std::int32_t>(i);
  }

  double d2(std::int64_t a, std::int64_t b) const {
    const double dx = (*pts)[2 * a] - (*pts)[2 * b], dy = (*pts)[2 * a + 1] - (*pts)[2 * b + 1];
    return dx * dx + dy * dy;
  }
};

/// Key of the undirected link (i, j), i < j: sorting keys sorts links by (i, j).
inline std::uint64_t link_key(GlobalId i, GlobalId j, GlobalId n) {
  if (i > j) std::swap(i, j);
  return static_cast<std::uint64_t>(i) * static_cast<std::uint64_t>(n) + static_cast<std::uint64_t>(j);
}

/// Every pair within distance r: same cell and the four "forward" neighbour cells.
void geometric_links(const Grid& grid, double r, GlobalId n, std::vector<std::uint64_t>& keys) {
  if (r <= 0) return;
  const double r2 = r * r;
  const int off[4][2] = {{1, 0}, {-1, 1}, {0, 1}, {1, 1}};
  for (int cy = 0; cy < grid.g; ++cy)
    for (int cx = 0; cx < grid.g; ++cx) {
      const std::size_t c = grid.cell(cx, cy);
      for (std::int64_t a = grid.start[c]; a < grid.start[c + 1]; ++a) {
        const std::int32_t ia = grid.id[a];
        for (std::int64_t b = a + 1; b < grid.start[c + 1]; ++b)
          if (grid.d2(ia, grid.id[b]) <= r2) keys.push_back(link_key(ia, grid.id[b], n));
        for (const auto& o : off) {
          const int nx = cx + o[0], ny = cy + o[1];
          if (nx < 0 || nx >= grid.g || ny >= grid.g) continue;
          const std::size_t nc = grid.cell(nx, ny);
          for (std::int64_t b = grid.start[nc]; b < grid.start[nc + 1]; ++b)
            if (grid.d2(ia, grid.id[b]) <= r2) keys.push_back(link_key(ia, grid.id[b], n));
        }
      }
    }
}

/// A uniformly random permutation of 0..n-1 (Fisher-Yates on counters).
std::vector<GlobalId> random_permutation(GlobalId n, std::uint64_t seed) {
  std::vector<GlobalId> perm(static_cast<std::size_t>(n));
  std::iota(perm.begin(), perm.end(), GlobalId{0});
  for (GlobalId i = n - 1; i > 0; --i) {
    auto j = static_cast<GlobalId>(uniform01(seed, kPath, static_cast<std::uint64_t>(i)) * static_cast<double>(i + 1));
    std::swap(perm[i], perm[std::min(j, i)]);
  }
  return perm;
}

struct UnionFind {
  std::vector<GlobalId> parent;
  explicit UnionFind(GlobalId n) : parent(static_cast<std::size_t>(n)) { std::iota(parent.begin(), parent.end(), GlobalId{0}); }
  GlobalId find(GlobalId v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  }
  bool unite(GlobalId a, GlobalId b) {
    a = find(a), b = find(b);
    if (a == b) return false;
    parent[std::max(a, b)] = std::min(a, b);
    return true;
  }
};

/// Nearest point to u outside the union-find set `root`, by (squared distance,
/// id): rings of cells around u's cell until no closer point can remain.
/// Returns (d2, v); v = -1 if every point is in the set.
std::pair<double, GlobalId> nearest_outside(const Grid& grid, UnionFind& uf, GlobalId u, GlobalId root) {
  const auto& p = *grid.pts;
  const int cx = grid.coord(p[2 * u]), cy = grid.coord(p[2 * u + 1]);
  const double side = 1.0 / grid.g;
  double best = std::numeric_limits<double>::infinity();
  GlobalId bv = -1;
  for (int rho = 0; rho <= grid.g; ++rho) {
    for (int y = cy - rho; y <= cy + rho; ++y) {
      if (y < 0 || y >= grid.g) continue;
      const bool edge_row = y == cy - rho || y == cy + rho;
      for (int x = cx - rho; x <= cx + rho; x += edge_row ? 1 : 2 * std::max(rho, 1)) {
        if (x < 0 || x >= grid.g) continue;
        const std::size_t c = grid.cell(x, y);
        for (std::int64_t b = grid.start[c]; b < grid.start[c + 1]; ++b) {
          const GlobalId v = grid.id[b];
          if (uf.find(v) == root) continue;
          const double d2 = grid.d2(u, v);
          if (d2 < best || (d2 == best && v < bv)) best = d2, bv = v;
        }
      }
    }
    // Points in rings beyond rho are at least rho cell sides away.
    const double reach = rho * side;
    if (bv >= 0 && best <= reach * reach) break;
  }
  return {best, bv};
}

/// Joins the components: each component other than the largest (in order of
/// its smallest node id) is linked, while its set does not hold the largest
/// component, to the nearest node outside its set by its closest pair.
/// Returns (components before, links added).
std::pair<GlobalId, GlobalId> connect_components(const Grid& grid, GlobalId n, std::vector<std::uint64_t>& keys) {
  UnionFind uf(n);
  for (std::uint64_t k : keys) uf.unite(static_cast<GlobalId>(k / n), static_cast<GlobalId>(k % n));
  // Components numbered by smallest node id; members listed by counting sort.
  std::vector<GlobalId> comp(static_cast<std::size_t>(n)), first_of;
  std::vector<GlobalId> index_of_root(static_cast<std::size_t>(n), -1);
  for (GlobalId i = 0; i < n; ++i) {
    const GlobalId r = uf.find(i);
    if (index_of_root[r] < 0) index_of_root[r] = static_cast<GlobalId>(first_of.size()), first_of.push_back(i);
    comp[i] = index_of_root[r];
  }
  const auto C = static_cast<GlobalId>(first_of.size());
  if (C == 1) return {1, 0};
  std::vector<GlobalId> begin(static_cast<std::size_t>(C) + 1, 0), members(static_cast<std::size_t>(n));
  for (GlobalId i = 0; i < n; ++i) ++begin[comp[i] + 1];
  for (GlobalId c = 0; c < C; ++c) begin[c + 1] += begin[c];
  std::vector<GlobalId> fill(begin.begin(), begin.end() - 1);
  for (GlobalId i = 0; i < n; ++i) members[fill[comp[i]]++] = i;
  GlobalId main = 0;
  for (GlobalId c = 1; c < C; ++c)
    if (begin[c + 1] - begin[c] > begin[main + 1] - begin[main]) main = c;

  GlobalId sets = C, added = 0;
  while (sets > 1) {  // each pass links at least one set (the loop ends)
    for (GlobalId c = 0; c < C && sets > 1; ++c) {
      const GlobalId root = uf.find(first_of[c]);
      if (c == main || root == uf.find(first_of[main])) continue;
      double best = std::numeric_limits<double>::infinity();
      GlobalId bu = -1, bv = -1;
      for (GlobalId k = begin[c]; k < begin[c + 1]; ++k) {
        const auto [d2, v] = nearest_outside(grid, uf, members[k], root);
        if (v >= 0 && (d2 < best || (d2 == best && std::make_pair(members[k], v) < std::make_pair(bu, bv))))
          best = d2, bu = members[k], bv = v;
      }
      keys.push_back(link_key(bu, bv, n));
      uf.unite(bu, bv);
      --sets, ++added;
    }
  }
  return {C, added};
}

void sort_unique(std::vector<std::uint64_t>& keys) {
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
}

// --------------------------------------------------------------------------
// Family parameters (documented in docs/consensus.md, "Generator").

/// exp, the project's reconstruction of 001's Kuramoto-motivated test:
/// a, b, c, d uniform in [0.5, 1.5].
void draw_exp(ProblemData& d, std::uint64_t seed) {
  const auto n = static_cast<std::size_t>(d.num_nodes);
  std::vector<double>* params[] = {&d.exp_a, &d.exp_b, &d.exp_c, &d.exp_d};
  for (std::size_t k = 0; k < 4; ++k) {
    params[k]->resize(n);
    for (std::size_t p = 0; p < n; ++p) (*params[k])[p] = 0.5 + uniform01(seed, kParams, 4 * p + k);
  }
}

/// quadratic: h uniform in [0.5, 2], r uniform in [-1, 1].
void draw_quadratic(ProblemData& d, std::uint64_t seed) {
  const std::size_t m = static_cast<std::size_t>(d.num_nodes) * static_cast<std::size_t>(d.dim);
  d.quad_h.resize(m);
  d.quad_r.resize(m);
  for (std::size_t k = 0; k < m; ++k) {
    d.quad_h[k] = 0.5 + 1.5 * uniform01(seed, kParams, 2 * k);
    d.quad_r[k] = -1.0 + 2.0 * uniform01(seed, kParams, 2 * k + 1);
  }
}

/// logistic and least_squares: a true weight w ~ N(0, I_q); node p owns
/// samples [p spn, (p+1) spn); features a_s ~ N(0, I_q). logistic: y_s = +1
/// with probability sigmoid(w.a_s), else -1; least_squares: the target
/// b_s = w.a_s + 0.1 N(0, 1).
void draw_samples(ProblemData& d, const GenerateOptions& o) {
  const auto q = static_cast<std::size_t>(d.dim);
  const auto S = static_cast<std::size_t>(o.samples_per_node) * static_cast<std::size_t>(d.num_nodes);
  std::vector<double> w(q);
  for (std::size_t k = 0; k < q; ++k) w[k] = standard_normal(o.seed, kTrueWeights, k);
  d.features.resize(S * q);
  d.labels.resize(S);
  d.owner.resize(S);
  d.lambda = o.lambda;
  for (std::size_t s = 0; s < S; ++s) {
    double t = 0;
    for (std::size_t k = 0; k < q; ++k) {
      d.features[s * q + k] = standard_normal(o.seed, kFeatures, s * q + k);
      t += w[k] * d.features[s * q + k];
    }
    if (d.family == Family::kLogistic)
      d.labels[s] = uniform01(o.seed, kLabels, s) < 1.0 / (1.0 + std::exp(-t)) ? 1.0 : -1.0;
    else
      d.labels[s] = t + 0.1 * standard_normal(o.seed, kLabels, s);
    d.owner[s] = static_cast<GlobalId>(s / static_cast<std::size_t>(o.samples_per_node));
  }
}

}  // namespace

ProblemData generate_problem(const GenerateOptions& o) { return generate_problem(o, nullptr); }

ProblemData generate_problem(const GenerateOptions& o, GenerateReport* report) {
  o.validate();
  const GlobalId n = o.nodes;
  GenerateReport rep;
  std::vector<double> pts(2 * static_cast<std::size_t>(n));
  for (std::size_t c = 0; c < pts.size(); ++c) pts[c] = uniform01(o.seed, kPositions, c);
  rep.radius = radius_for_degree(static_cast<double>(n), o.avg_degree);
  const Grid grid(pts, rep.radius);

  std::vector<std::uint64_t> keys;
  keys.reserve(static_cast<std::size_t>(o.avg_degree * static_cast<double>(n) * 0.55) + static_cast<std::size_t>(n));
  geometric_links(grid, rep.radius, n, keys);
  sort_unique(keys);
  rep.geometric_links = static_cast<GlobalId>(keys.size());

  ProblemData d;
  d.num_nodes = n;
  d.dim = o.dim;
  d.family = o.family;
  if (o.hamiltonian) {
    d.truth_path = random_permutation(n, o.seed);
    for (GlobalId k = 1; k < n; ++k) keys.push_back(link_key(d.truth_path[k - 1], d.truth_path[k], n));
    sort_unique(keys);
    rep.path_links = static_cast<GlobalId>(keys.size()) - rep.geometric_links;
  }
  std::tie(rep.components, rep.connect_links) = connect_components(grid, n, keys);
  sort_unique(keys);

  d.edges.resize(2 * keys.size());
  for (std::size_t e = 0; e < keys.size(); ++e) {
    d.edges[2 * e] = static_cast<GlobalId>(keys[e] / static_cast<std::uint64_t>(n));
    d.edges[2 * e + 1] = static_cast<GlobalId>(keys[e] % static_cast<std::uint64_t>(n));
  }
  switch (o.family) {
    case Family::kExp: draw_exp(d, o.seed); break;
    case Family::kQuadratic: draw_quadratic(d, o.seed); break;
    case Family::kLogistic:
    case Family::kLeastSquares: draw_samples(d, o); break;
  }
  if (report) *report = rep;
  return d;
}

}  // namespace snl::consensus
