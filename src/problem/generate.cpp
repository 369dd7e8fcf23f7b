// Random geometric networks (seed 003, Sec. V): sensors uniform in [0,L]^p
// (L = 1 up to kReferenceSensors, then constant density), anchors at the
// corners and/or random, exact-degree radius, noise of eq. (28).
#include "snl/problem/generate.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <iomanip>
#include <limits>
#include <sstream>
#include <vector>

#include "snl/core/random.hpp"

namespace snl {

std::string GenerateOptions::validate() const {
  std::ostringstream os;
  if (sensors < 1) {
    os << "--sensors must be at least 1 (got " << sensors << ")";
  } else if (sensors > std::numeric_limits<std::int32_t>::max()) {
    os << "--sensors must be at most " << std::numeric_limits<std::int32_t>::max() << " (got " << sensors << ")";
  } else if (dim < 1 || dim > 3) {
    os << "--dim must be 1, 2 or 3 (got " << dim << ")";
  } else if (avg_degree != kAutoDegree && (!std::isfinite(avg_degree) || avg_degree < 0)) {
    // (kAutoDegree is resolved by default_avg_degree(dim))
    os << "--avg-degree must be a finite number >= 0 (got " << avg_degree << ")";
  } else if (avg_degree != kAutoDegree && avg_degree > static_cast<double>(sensors - 1)) {
    os << "--avg-degree " << avg_degree << " is impossible with " << sensors << " sensors (at most "
       << sensors - 1 << ")";
  } else if (!std::isfinite(sigma) || sigma < 0) {
    os << "--sigma must be a finite number >= 0 (got " << sigma << ")";
  } else if (!std::isfinite(sigma_rel) || sigma_rel < 0) {
    os << "--sigma-rel must be a finite number >= 0 (got " << sigma_rel << ")";
  } else if (!std::isfinite(side) || side > 1e12) {
    os << "--side must be a finite number <= 1e12 (got " << side << ")";
  } else if (num_random_anchors < kAutoAnchors) {
    os << "--anchors must be 'corners' or a positive count (got " << num_random_anchors << ")";
  } else if (!std::isfinite(anchor_radius)) {
    os << "--anchor-radius must be finite (got " << anchor_radius << ")";
  } else if (max_draws < 1) {
    os << "--max-draws must be at least 1 (got " << max_draws << ")";
  }
  if (os.str().empty() && topology == Topology::kStar) return validate_star();
  return os.str();
}

std::string GenerateOptions::validate_star() const {
  std::ostringstream os;
  if (dim != 1) {
    os << "--topology star is the one-dimensional network of 003 Fig. 2: give --dim 1 (got " << dim << ")";
  } else if (sensors != 1) {
    os << "--topology star has one sensor (the hub; its neighbours are the anchors): give --sensors 1 (got "
       << sensors << ")";
  } else if (!std::isfinite(sigma) || sigma < 0) {
    os << "--sigma must be a finite number >= 0 (got " << sigma << ")";
  } else if (sigma_rel != 0) {
    os << "--sigma-rel does not apply to --topology star (no link radius): give --sigma";
  } else if (star_anchors.empty()) {
    os << "--star-anchors needs at least one anchor position";
  } else if (!std::isfinite(star_center) ||
             std::any_of(star_anchors.begin(), star_anchors.end(), [](double a) { return !std::isfinite(a); })) {
    os << "--star-center and --star-anchors must be finite";
  }
  return os.str();
}

double default_avg_degree(int dim) { return dim == 3 ? 24.0 : 16.0; }

double region_side(const GenerateOptions& opt) {
  if (opt.side > 0) return opt.side;
  if (opt.sensors <= kReferenceSensors) return 1.0;
  return std::pow(static_cast<double>(opt.sensors) / static_cast<double>(kReferenceSensors), 1.0 / opt.dim);
}

namespace {

constexpr double kPi = 3.14159265358979323846;

// Mean measure of {y in [0,1]^p : |x - y| <= r} for x uniform in the cube and
// r <= 1: the integral over the ball of prod_d (1 - |z_d|). It accounts for the
// boundary, so the degree estimate is close even for small n.
double mean_ball_fraction(int p, double r) {
  if (p == 1) return 2.0 * r - r * r;  // |[x - r, x + r] & [0, 1]| averaged over x
  if (p == 2) return kPi * r * r - 8.0 / 3.0 * r * r * r + 0.5 * r * r * r * r;
  const double r3 = r * r * r;
  return 4.0 / 3.0 * kPi * r3 - 1.5 * kPi * r3 * r + 1.6 * r3 * r * r - r3 * r3 / 6.0;
}

// Radius with expected degree deg, or 2 (meaning "more than 1") if none <= 1.
double estimate_radius(int p, double n, double deg) {
  if ((n - 1) * mean_ball_fraction(p, 1.0) < deg) return 2.0;
  double lo = 0, hi = 1;
  for (int it = 0; it < 60; ++it) {
    const double mid = 0.5 * (lo + hi);
    ((n - 1) * mean_ball_fraction(p, mid) < deg ? lo : hi) = mid;
  }
  return hi;
}

template <int P>
inline double dist2(const double* a, const double* b) {
  double s = 0;
  for (int d = 0; d < P; ++d) {
    const double t = a[d] - b[d];
    s += t * t;
  }
  return s;
}

// Squared distance of the points scale * a and scale * b, rounded as when
// computed from the scaled coordinates themselves (so ranges match the stored
// truth exactly); dist2 for scale 1.
template <int P>
inline double scaled_dist2(const double* a, const double* b, double scale) {
  if (scale == 1.0) return dist2<P>(a, b);
  double s = 0;
  for (int d = 0; d < P; ++d) {
    const double t = scale * a[d] - scale * b[d];
    s += t * t;
  }
  return s;
}

// Points of [0,1]^P bucketed into g^P cells (counting sort), coordinates copied
// in cell order so the pair search streams through memory.
template <int P>
struct Grid {
  int g = 1;
  std::vector<std::uint32_t> start;  // [cells + 1]
  std::vector<std::int32_t> id;      // point ids in cell order
  std::vector<double> xs;            // [count * P] coordinates in cell order

  int coord_cell(double x) const {
    const int c = static_cast<int>(x * g);
    return c < 0 ? 0 : (c >= g ? g - 1 : c);
  }
  std::size_t cell_of(const double* x) const {
    std::size_t c = 0;
    for (int d = P - 1; d >= 0; --d) c = c * g + coord_cell(x[d]);
    return c;
  }

  // cell size >= min_size; at most about max_cells cells.
  void build(const std::vector<double>& pts, double min_size, double max_cells) {
    const std::size_t count = pts.size() / P;
    double gd = min_size > 0 ? std::floor(1.0 / min_size) : 1e9;
    gd = std::min(gd, std::floor(std::pow(std::max(max_cells, 1.0), 1.0 / P)));
    g = static_cast<int>(std::max(1.0, gd));
    std::size_t cells = 1;
    for (int d = 0; d < P; ++d) cells *= static_cast<std::size_t>(g);
    start.assign(cells + 1, 0);
    std::vector<std::uint32_t> cell(count);
    for (std::size_t i = 0; i < count; ++i) {
      cell[i] = static_cast<std::uint32_t>(cell_of(&pts[i * P]));
      ++start[cell[i] + 1];
    }
    for (std::size_t c = 0; c < cells; ++c) start[c + 1] += start[c];
    id.resize(count);
    xs.resize(count * P);
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (std::size_t i = 0; i < count; ++i) {
      const std::uint32_t pos = fill[cell[i]]++;
      id[pos] = static_cast<std::int32_t>(i);
      for (int d = 0; d < P; ++d) xs[pos * P + d] = pts[i * P + d];
    }
  }

  // Calls f(a, b, d2) (positions in cell order) once for every unordered pair
  // in the same or adjacent cells with d2 <= lim2: each cell meets only the
  // lexicographically positive half of its neighbours.
  template <class F>
  void visit_pairs(double lim2, F&& f) const {
    std::vector<std::array<int, 3>> offs;
    const int lo3 = P == 3 ? -1 : 0, hi3 = P == 3 ? 1 : 0;
    const int lo2 = P >= 2 ? -1 : 0, hi2 = P >= 2 ? 1 : 0;
    for (int dz = lo3; dz <= hi3; ++dz)
      for (int dy = lo2; dy <= hi2; ++dy)
        for (int dx = -1; dx <= 1; ++dx)
          if (dz > 0 || (dz == 0 && (dy > 0 || (dy == 0 && dx > 0)))) offs.push_back({dx, dy, dz});
    const int gz = P == 3 ? g : 1, gy = P >= 2 ? g : 1;
    for (int cz = 0; cz < gz; ++cz)
      for (int cy = 0; cy < gy; ++cy)
        for (int cx = 0; cx < g; ++cx) {
          const std::size_t c = (static_cast<std::size_t>(cz) * g + cy) * g + cx;
          const std::uint32_t s0 = start[c], e0 = start[c + 1];
          if (s0 == e0) continue;
          for (std::uint32_t a = s0; a < e0; ++a)
            for (std::uint32_t b = a + 1; b < e0; ++b) {
              const double d2 = dist2<P>(&xs[std::size_t(a) * P], &xs[std::size_t(b) * P]);
              if (d2 <= lim2) f(a, b, d2);
            }
          for (const auto& o : offs) {
            const int nx = cx + o[0], ny = cy + o[1], nz = cz + o[2];
            if (nx < 0 || nx >= g || ny < 0 || ny >= gy || nz < 0 || nz >= gz) continue;
            const std::size_t nc = (static_cast<std::size_t>(nz) * g + ny) * g + nx;
            const std::uint32_t s1 = start[nc], e1 = start[nc + 1];
            for (std::uint32_t a = s0; a < e0; ++a) {
              const double* xa = &xs[std::size_t(a) * P];
              for (std::uint32_t b = s1; b < e1; ++b) {
                const double d2 = dist2<P>(xa, &xs[std::size_t(b) * P]);
                if (d2 <= lim2) f(a, b, d2);
              }
            }
          }
        }
  }
};

// Sensor-sensor adjacency before noise: CSR by the smaller id i, neighbours j > i
// sorted, true distances alongside.
struct EdgeCsr {
  std::vector<std::uint32_t> offset;  // [n + 1]
  std::vector<std::int32_t> col;
  std::vector<double> dist;
  double r2 = 0;
};

// Sorts each row of the CSR by column (rows are short: insertion sort).
void sort_rows(EdgeCsr& csr) {
  const std::size_t n = csr.offset.size() - 1;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t s = csr.offset[i], e = csr.offset[i + 1];
    for (std::uint32_t a = s + 1; a < e; ++a) {
      const std::int32_t c = csr.col[a];
      const double d = csr.dist[a];
      std::uint32_t b = a;
      for (; b > s && csr.col[b - 1] > c; --b) {
        csr.col[b] = csr.col[b - 1];
        csr.dist[b] = csr.dist[b - 1];
      }
      csr.col[b] = c;
      csr.dist[b] = d;
    }
  }
}

// Exact-degree edge set by spatial hashing, O(n) expected.
template <int P>
EdgeCsr sensor_edges_grid(const std::vector<double>& x, std::size_t n, std::uint64_t k) {
  EdgeCsr csr;
  csr.offset.assign(n + 1, 0);
  if (k == 0) return csr;
  if (k > 0xF0000000ULL) throw Error("generate: too many edges requested (more than 4e9)");
  const double diam = std::sqrt(static_cast<double>(P));
  const double r_est = estimate_radius(P, static_cast<double>(n), 2.0 * static_cast<double>(k) / n);
  // Margin: 5% for the estimate, plus the relative fluctuation of the pair count.
  double rc = r_est * (1.05 + 3.0 / std::sqrt(static_cast<double>(k)));
  Grid<P> grid;
  std::vector<float> cand;
  float t = 0;
  for (;;) {
    rc = std::min(rc, diam * 1.001);
    // Cells slightly larger than rc, so that every pair whose float squared
    // distance can tie with a candidate's lies in adjacent cells.
    grid.build(x, rc * (1 + 1e-5), 2.0 * static_cast<double>(n) + 16);
    cand.clear();
    cand.reserve(static_cast<std::size_t>(1.3 * static_cast<double>(k)) + 16);
    const double rc2 = rc * rc;
    grid.visit_pairs(rc2, [&](std::uint32_t, std::uint32_t, double d2) { cand.push_back(static_cast<float>(d2)); });
    if (cand.size() >= k) break;
    rc *= 1.5;  // too few candidates (a rare fluctuation): search further.
  }
  std::nth_element(cand.begin(), cand.begin() + (k - 1), cand.end());
  t = cand[k - 1];
  std::vector<float>().swap(cand);

  // Count per smaller id, and the exact double threshold R2.
  // Every pair with float(d2) <= t <= float(rc^2) has d2 <= rc^2 (1 + 2^-23) < lim2,
  // and lies in the same or adjacent cells (cells >= rc (1 + 1e-5), or one cell).
  const double lim2 = rc * rc * (1 + 1e-5);
  double r2 = 0;
  grid.visit_pairs(lim2, [&](std::uint32_t a, std::uint32_t b, double d2) {
    if (static_cast<float>(d2) <= t) {
      ++csr.offset[std::min(grid.id[a], grid.id[b]) + 1];
      r2 = std::max(r2, d2);
    }
  });
  for (std::size_t i = 0; i < n; ++i) csr.offset[i + 1] += csr.offset[i];
  csr.col.resize(csr.offset[n]);
  csr.dist.resize(csr.offset[n]);
  std::vector<std::uint32_t> fill(csr.offset.begin(), csr.offset.end() - 1);
  grid.visit_pairs(r2, [&](std::uint32_t a, std::uint32_t b, double d2) {
    const std::int32_t ia = grid.id[a], ib = grid.id[b];
    const std::int32_t i = std::min(ia, ib), j = std::max(ia, ib);
    const std::uint32_t pos = fill[i]++;
    csr.col[pos] = j;
    csr.dist[pos] = std::sqrt(d2);
  });
  csr.r2 = r2;
  sort_rows(csr);
  return csr;
}

// The same edge set from all n(n-1)/2 pairs: the reference twin for tests.
template <int P>
EdgeCsr sensor_edges_brute(const std::vector<double>& x, std::size_t n, std::uint64_t k) {
  EdgeCsr csr;
  csr.offset.assign(n + 1, 0);
  if (k == 0) return csr;
  std::vector<float> all;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j) all.push_back(static_cast<float>(dist2<P>(&x[i * P], &x[j * P])));
  std::nth_element(all.begin(), all.begin() + (k - 1), all.end());
  const float t = all[k - 1];
  double r2 = 0;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = i + 1; j < n; ++j) {
      const double d2 = dist2<P>(&x[i * P], &x[j * P]);
      if (static_cast<float>(d2) <= t) {
        csr.col.push_back(static_cast<std::int32_t>(j));
        csr.dist.push_back(std::sqrt(d2));
        r2 = std::max(r2, d2);
      }
    }
    csr.offset[i + 1] = static_cast<std::uint32_t>(csr.col.size());
  }
  csr.r2 = r2;
  return csr;
}

// Anchor edges (i, k) with ||x_i - a_k||^2 <= ar2, sorted by (i, k); anchors
// bucketed in a grid so that many random anchors stay cheap.
// x and anchors in unit-cube coordinates; true distances are scale times theirs.
template <int P>
void anchor_edges(const std::vector<double>& x, std::size_t n, const std::vector<double>& anchors, double ar2,
                  double scale, std::uint64_t seed, double sigma, Network& net) {
  const std::size_t m = anchors.size() / P;
  if (m == 0 || ar2 < 0) return;
  const double ar = std::sqrt(ar2);
  Grid<P> grid;
  grid.build(anchors, ar, 2.0 * static_cast<double>(m) + 16);
  std::vector<std::int32_t> hits;
  for (std::size_t i = 0; i < n; ++i) {
    const double* xi = &x[i * P];
    int lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    for (int d = 0; d < P; ++d) {
      lo[d] = grid.coord_cell(xi[d] - ar);
      hi[d] = grid.coord_cell(xi[d] + ar);
    }
    hits.clear();
    for (int cz = lo[2]; cz <= hi[2]; ++cz)
      for (int cy = lo[1]; cy <= hi[1]; ++cy)
        for (int cx = lo[0]; cx <= hi[0]; ++cx) {
          const std::size_t c = (static_cast<std::size_t>(cz) * grid.g + cy) * grid.g + cx;
          for (std::uint32_t b = grid.start[c]; b < grid.start[c + 1]; ++b)
            if (dist2<P>(xi, &grid.xs[std::size_t(b) * P]) <= ar2) hits.push_back(grid.id[b]);
        }
    std::sort(hits.begin(), hits.end());
    for (const std::int32_t kk : hits) {
      const double d = std::sqrt(scaled_dist2<P>(xi, &anchors[std::size_t(kk) * P], scale));
      const std::uint64_t counter = static_cast<std::uint64_t>(i) * m + static_cast<std::uint64_t>(kk);
      net.anchor_edges.push_back(static_cast<GlobalId>(i));
      net.anchor_edges.push_back(kk);
      // 003, eq. (28): the absolute value keeps ranges non-negative.
      net.anchor_ranges.push_back(sigma > 0 ? std::abs(d + sigma * standard_normal(seed, RngStream::kAnchorNoise, counter))
                                            : d);
    }
  }
}

template <int P>
Network draw_network(const GenerateOptions& opt, std::uint64_t seed, bool brute, GenerateReport& rep) {
  const std::size_t n = static_cast<std::size_t>(opt.sensors);
  Network net;
  net.dim = P;
  net.num_sensors = opt.sensors;
  net.has_truth = true;
  // Everything is drawn and linked in the unit cube, then scaled by L (exact for L = 1).
  const double L = region_side(opt);
  net.truth.resize(n * P);
  for (std::size_t c = 0; c < n * P; ++c) net.truth[c] = uniform01(seed, RngStream::kSensorPositions, c);

  if (opt.num_random_anchors <= 0) {
    // The 2^p corners of the unit square/cube (003, Sec. V): bit d of k is coordinate d.
    for (int k = 0; k < (1 << P); ++k)
      for (int d = 0; d < P; ++d) net.anchors.push_back(static_cast<double>((k >> d) & 1));
  }
  const std::size_t m = opt.num_random_anchors > 0 ? static_cast<std::size_t>(opt.num_random_anchors)
                        : opt.num_random_anchors == kAutoAnchors ? n / 100
                                                                 : 0;
  for (std::size_t c = 0; c < m * P; ++c) net.anchors.push_back(uniform01(seed, RngStream::kAnchorPositions, c));

  const auto k = static_cast<std::uint64_t>(std::llround(opt.avg_degree * static_cast<double>(n) / 2.0));
  EdgeCsr csr = brute ? sensor_edges_brute<P>(net.truth, n, k) : sensor_edges_grid<P>(net.truth, n, k);
  const std::size_t E = csr.col.size();
  const double sigma = opt.sigma_rel > 0 ? opt.sigma_rel * L * std::sqrt(csr.r2) : opt.sigma;
  net.sigma = sigma;
  net.sensor_edges.resize(2 * E);
  net.sensor_ranges.resize(E);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::uint32_t e = csr.offset[i]; e < csr.offset[i + 1]; ++e) {
      const auto j = static_cast<std::uint64_t>(csr.col[e]);
      net.sensor_edges[2 * e] = static_cast<GlobalId>(i);
      net.sensor_edges[2 * e + 1] = static_cast<GlobalId>(j);
      // 003, eq. (28); the counter depends on the pair only, not on its row.
      const double d = L == 1.0 ? csr.dist[e] : std::sqrt(scaled_dist2<P>(&net.truth[i * P], &net.truth[j * P], L));
      net.sensor_ranges[e] =
          sigma > 0 ? std::abs(d + sigma * standard_normal(seed, RngStream::kSensorNoise, i * n + j)) : d;
    }
  }
  const double r2 = csr.r2;
  csr = EdgeCsr();

  const double ar_unit = opt.anchor_radius / L;
  const double ar2 = opt.anchor_radius < 0 ? r2 : ar_unit * ar_unit;
  anchor_edges<P>(net.truth, n, net.anchors, ar2, L, seed, sigma, net);
  if (L != 1.0) {
    for (double& v : net.truth) v *= L;
    for (double& v : net.anchors) v *= L;
  }

  net.total_sensor_edges = net.local_sensor_edges();
  net.total_anchor_edges = net.local_anchor_edges();
  rep.radius = L * std::sqrt(r2);
  rep.anchor_radius = L * std::sqrt(ar2);
  rep.side = L;
  rep.sigma = sigma;
  rep.achieved_avg_degree = 2.0 * static_cast<double>(E) / static_cast<double>(n);
  rep.draw_seed = seed;
  return net;
}

// Sensors with at least one localizability flag.
std::size_t count_flagged(const std::vector<std::uint8_t>& flags) {
  return static_cast<std::size_t>(std::count_if(flags.begin(), flags.end(), [](std::uint8_t f) { return f != 0; }));
}

// The warning for a network returned although not (fully) localizable: the
// numbers, and what to change. Empty when at most 1% of the sensors are
// affected after a run that was not asked to redraw, or none at all.
std::string localizability_warning(const GenerateOptions& opt, const GenerateReport& rep, bool redrew,
                                   GlobalId num_anchors) {
  const LocalizabilityReport& lr = rep.localizability;
  const std::size_t bad = count_flagged(lr.flags), n = lr.flags.size();
  if (bad == 0 || (!redrew && 100 * bad <= n)) return "";
  std::ostringstream os;
  os << "warning: ";
  if (redrew) os << "no fully localizable network in " << rep.draws << " draw(s); the last draw is written. ";
  os << bad << " of " << n << " sensors (" << std::setprecision(3) << 100.0 * static_cast<double>(bad) / static_cast<double>(n)
     << "%) cannot be localized: " << lr.unanchored.size() << " in components without anchors, "
     << lr.few_measurements.size() << " with fewer than " << opt.dim + 1 << " measurements, " << lr.not_rigid.size()
     << " in flexible parts" << (lr.rigidity_checked ? "" : " (rigidity not checked)") << ". Average degree "
     << std::setprecision(4) << rep.achieved_avg_degree << ", " << num_anchors
     << " anchors. Raise --avg-degree (the default, " << default_avg_degree(opt.dim)
     << ", leaves at most a few sensors in 10^4 unlocalizable at any n; docs/generator.md), add anchors (--anchors K), "
        "or give --localizable yes to insist.";
  return os.str();
}

// 003 Fig. 2 / Table I: one sensor (the hub) at star_center on the line, every
// anchor its neighbour, ranges with the noise of eq. (28) under the same
// counters as the random networks (kAnchorNoise, i m + k with i = 0).
Network star_network(const GenerateOptions& opt, GenerateReport& rep) {
  Network net;
  net.dim = 1;
  net.num_sensors = 1;
  net.has_truth = true;
  net.truth = {opt.star_center};
  net.anchors = opt.star_anchors;
  net.sigma = opt.sigma;
  double reach = 0;
  for (std::size_t k = 0; k < net.anchors.size(); ++k) {
    const double d = std::abs(opt.star_center - net.anchors[k]);
    reach = std::max(reach, d);
    net.anchor_edges.push_back(0);
    net.anchor_edges.push_back(static_cast<GlobalId>(k));
    net.anchor_ranges.push_back(opt.sigma > 0 ? std::abs(d + opt.sigma * standard_normal(opt.seed, RngStream::kAnchorNoise, k))
                                              : d);
  }
  net.total_sensor_edges = 0;
  net.total_anchor_edges = net.local_anchor_edges();
  rep.anchor_radius = reach;
  rep.sigma = opt.sigma;
  rep.draw_seed = opt.seed;
  rep.localizability = analyze_localizability(net, true);
  net.localizability = rep.localizability.flags;
  return net;
}

Network generate_impl(const GenerateOptions& options, GenerateReport* report, bool brute) {
  std::string msg = options.validate();
  GenerateOptions opt = options;
  if (opt.avg_degree == kAutoDegree) {
    // Small networks: at most the complete graph.
    opt.avg_degree = std::min(default_avg_degree(opt.dim), static_cast<double>(std::max<GlobalId>(opt.sensors - 1, 0)));
  }
  if (!msg.empty()) throw Error("generate: " + msg);
  if (opt.topology == GenerateOptions::Topology::kStar) {
    GenerateReport rep;
    Network net = star_network(opt, rep);
    if (report) *report = rep;
    return net;
  }
  using L = GenerateOptions::Localizable;
  const GlobalId n = opt.sensors;
  const bool redraw = opt.localizable == L::kYes || (opt.localizable == L::kAuto && n <= kRigidityLimit);
  const int limit = opt.localizable == L::kYes ? opt.max_draws
                    : redraw                    ? std::min(opt.max_draws, kAutoMaxDraws)
                                                : 1;
  GenerateReport rep;
  Network net;
  for (int d = 0; d < limit; ++d) {
    const std::uint64_t seed =
        d == 0 ? opt.seed : random_bits(opt.seed, RngStream::kRedraw, static_cast<std::uint64_t>(d));
    net = opt.dim == 1   ? draw_network<1>(opt, seed, brute, rep)
          : opt.dim == 2 ? draw_network<2>(opt, seed, brute, rep)
                         : draw_network<3>(opt, seed, brute, rep);
    rep.draws = d + 1;
    // Cheap tests first; the rigidity check (n <= kRigidityLimit) only when they pass.
    rep.localizability = analyze_localizability(net, false);
    if (rep.localizability.localizable() && n <= kRigidityLimit) rep.localizability = analyze_localizability(net, true);
    if (!redraw || rep.localizability.localizable()) break;
  }
  if (redraw && !rep.localizability.localizable()) {
    if (opt.localizable == L::kYes) {
      std::ostringstream os;
      os << "generate: no localizable network in " << rep.draws << " draw(s) (n = " << n
         << ", avg degree " << opt.avg_degree << "); raise --avg-degree or the draw limit. Last draw: "
         << rep.localizability.summary();
      throw Error(os.str());
    }
  }
  if (n <= kRigidityLimit && !rep.localizability.rigidity_checked)
    rep.localizability = analyze_localizability(net, true);
  net.localizability = rep.localizability.flags;
  rep.warning = localizability_warning(opt, rep, redraw, net.num_anchors());
  if (report) *report = rep;
  return net;
}

}  // namespace

Network generate_network(const GenerateOptions& opt, GenerateReport* report) {
  return generate_impl(opt, report, false);
}

Network generate_network_reference(const GenerateOptions& opt, GenerateReport* report) {
  return generate_impl(opt, report, true);
}

}  // namespace snl
