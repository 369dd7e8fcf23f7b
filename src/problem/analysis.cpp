// Whole-network analyses: degrees, localizability (connectivity, anchoring,
// measurement counts, infinitesimal rigidity) and the Cramér-Rao bound. One
// file because the rigidity test and the bound share the Fisher-information
// assembly and its sparse factorization.
#include "snl/problem/analysis.hpp"

#include <Eigen/Sparse>
#include <Eigen/MetisSupport>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <sstream>
#include <vector>

#include "snl/core/random.hpp"

namespace snl {

DegreeStats degree_stats(const Network& net) {
  DegreeStats s;
  const auto n = static_cast<std::size_t>(net.num_sensors);
  if (n == 0) return s;
  std::vector<GlobalId> deg(n, 0), adeg(n, 0);
  for (std::size_t e = 0; e + 1 < net.sensor_edges.size(); e += 2) {
    ++deg[static_cast<std::size_t>(net.sensor_edges[e])];
    ++deg[static_cast<std::size_t>(net.sensor_edges[e + 1])];
  }
  for (std::size_t e = 0; e + 1 < net.anchor_edges.size(); e += 2) ++adeg[static_cast<std::size_t>(net.anchor_edges[e])];
  s.min = static_cast<double>(deg[0]);
  double sum = 0, asum = 0;
  for (std::size_t i = 0; i < n; ++i) {
    sum += static_cast<double>(deg[i]);
    asum += static_cast<double>(adeg[i]);
    s.min = std::min(s.min, static_cast<double>(deg[i]));
    s.max = std::max(s.max, static_cast<double>(deg[i]));
    s.max_anchor = std::max(s.max_anchor, adeg[i]);
    if (deg[i] == 0 && adeg[i] == 0) ++s.isolated;
  }
  s.mean = sum / static_cast<double>(n);
  s.mean_anchor = asum / static_cast<double>(n);
  return s;
}

namespace {

// Union-find with path halving and union by size.
struct UnionFind {
  std::vector<std::int64_t> parent, size;
  explicit UnionFind(std::size_t n) : parent(n), size(n, 1) { std::iota(parent.begin(), parent.end(), 0); }
  std::int64_t find(std::int64_t a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
  }
  void unite(std::int64_t a, std::int64_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return;
    if (size[a] < size[b]) std::swap(a, b);
    parent[b] = a;
    size[a] += size[b];
  }
};

// Number of distinct measurements per sensor (a pair measured twice counts once).
std::vector<GlobalId> distinct_measurements(const Network& net) {
  const auto n = static_cast<std::size_t>(net.num_sensors);
  const std::size_t E = net.sensor_edges.size() / 2, Ea = net.anchor_edges.size() / 2;
  std::vector<GlobalId> cnt(n, 0);
  // Fast path: canonical edges strictly sorted have no duplicates (the generator's output).
  bool sorted = true;
  for (std::size_t e = 0; e < E && sorted; ++e) {
    const GlobalId i = net.sensor_edges[2 * e], j = net.sensor_edges[2 * e + 1];
    if (i >= j) sorted = false;
    if (e > 0) {
      const GlobalId pi = net.sensor_edges[2 * e - 2], pj = net.sensor_edges[2 * e - 1];
      if (pi > i || (pi == i && pj >= j)) sorted = false;
    }
  }
  for (std::size_t e = 1; e < Ea && sorted; ++e) {
    const GlobalId pi = net.anchor_edges[2 * e - 2], pk = net.anchor_edges[2 * e - 1];
    const GlobalId i = net.anchor_edges[2 * e], k = net.anchor_edges[2 * e + 1];
    if (pi > i || (pi == i && pk >= k)) sorted = false;
  }
  if (sorted) {
    for (std::size_t e = 0; e < E; ++e) {
      ++cnt[static_cast<std::size_t>(net.sensor_edges[2 * e])];
      ++cnt[static_cast<std::size_t>(net.sensor_edges[2 * e + 1])];
    }
    for (std::size_t e = 0; e < Ea; ++e) ++cnt[static_cast<std::size_t>(net.anchor_edges[2 * e])];
    return cnt;
  }
  // General case: CSR of neighbours (anchor k encoded as n + k), sort, unique.
  std::vector<std::size_t> off(n + 1, 0);
  for (std::size_t e = 0; e < E; ++e) {
    const GlobalId i = net.sensor_edges[2 * e], j = net.sensor_edges[2 * e + 1];
    if (i == j) continue;
    ++off[static_cast<std::size_t>(i) + 1];
    ++off[static_cast<std::size_t>(j) + 1];
  }
  for (std::size_t e = 0; e < Ea; ++e) ++off[static_cast<std::size_t>(net.anchor_edges[2 * e]) + 1];
  for (std::size_t i = 0; i < n; ++i) off[i + 1] += off[i];
  std::vector<GlobalId> nb(off[n]);
  std::vector<std::size_t> fill(off.begin(), off.end() - 1);
  for (std::size_t e = 0; e < E; ++e) {
    const GlobalId i = net.sensor_edges[2 * e], j = net.sensor_edges[2 * e + 1];
    if (i == j) continue;
    nb[fill[static_cast<std::size_t>(i)]++] = j;
    nb[fill[static_cast<std::size_t>(j)]++] = i;
  }
  for (std::size_t e = 0; e < Ea; ++e)
    nb[fill[static_cast<std::size_t>(net.anchor_edges[2 * e])]++] = net.num_sensors + net.anchor_edges[2 * e + 1];
  for (std::size_t i = 0; i < n; ++i) {
    std::sort(nb.begin() + off[i], nb.begin() + off[i + 1]);
    cnt[i] = std::unique(nb.begin() + off[i], nb.begin() + off[i + 1]) - (nb.begin() + off[i]);
  }
  return cnt;
}

using SpMat = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

// Fisher information matrix at positions x (Patwari et al. 2005; spec
// "Cramér-Rao lower bound"): J_ii += w u u^T per measurement of i, J_ij = -w u u^T
// per sensor pair, w = 1/sigma^2 of the measurement (1 when `sw`/`aw` are
// empty). Only the sensors with index[i] >= 0 take part, as rows index[i];
// measurements to other sensors are left out. Zero-length pairs carry no
// direction: skipped.
SpMat fisher_information(const Network& net, const std::vector<double>& x, const std::vector<int>& index, int m,
                         const std::vector<double>& sw = {}, const std::vector<double>& aw = {}) {
  const int p = net.dim;
  std::vector<Eigen::Triplet<double, int>> trip;
  trip.reserve(net.sensor_edges.size() / 2 * 4 * p * p + net.anchor_edges.size() / 2 * p * p + std::size_t(m) * p);
  for (std::size_t r = 0; r < std::size_t(m) * p; ++r) trip.emplace_back(int(r), int(r), 0.0);  // keep the diagonal structural
  double u[3];
  auto unit = [&](const double* a, const double* b) {
    double s = 0;
    for (int d = 0; d < p; ++d) {
      u[d] = a[d] - b[d];
      s += u[d] * u[d];
    }
    if (!(s > 0)) return false;
    s = 1.0 / std::sqrt(s);
    for (int d = 0; d < p; ++d) u[d] *= s;
    return true;
  };
  for (std::size_t e = 0; e + 1 < net.sensor_edges.size(); e += 2) {
    const auto i = static_cast<std::size_t>(net.sensor_edges[e]), j = static_cast<std::size_t>(net.sensor_edges[e + 1]);
    const int ci = index[i], cj = index[j];
    if (i == j || ci < 0 || cj < 0 || !unit(&x[i * p], &x[j * p])) continue;
    const double w = sw.empty() ? 1.0 : sw[e / 2];
    for (int a = 0; a < p; ++a)
      for (int b = 0; b < p; ++b) {
        const double v = sw.empty() ? u[a] * u[b] : w * u[a] * u[b];
        trip.emplace_back(ci * p + a, ci * p + b, v);
        trip.emplace_back(cj * p + a, cj * p + b, v);
        trip.emplace_back(ci * p + a, cj * p + b, -v);
        trip.emplace_back(cj * p + a, ci * p + b, -v);
      }
  }
  for (std::size_t e = 0; e + 1 < net.anchor_edges.size(); e += 2) {
    const auto i = static_cast<std::size_t>(net.anchor_edges[e]), k = static_cast<std::size_t>(net.anchor_edges[e + 1]);
    const int ci = index[i];
    if (ci < 0 || !unit(&x[i * p], &net.anchors[k * p])) continue;
    const double w = aw.empty() ? 1.0 : aw[e / 2];
    for (int a = 0; a < p; ++a)
      for (int b = 0; b < p; ++b) trip.emplace_back(ci * p + a, ci * p + b, aw.empty() ? u[a] * u[b] : w * u[a] * u[b]);
  }
  SpMat J(m * p, m * p);
  J.setFromTriplets(trip.begin(), trip.end());
  return J;
}

// The whole network: every sensor, index i.
SpMat fisher_information(const Network& net, const std::vector<double>& x) {
  std::vector<int> index(static_cast<std::size_t>(net.num_sensors));
  std::iota(index.begin(), index.end(), 0);
  return fisher_information(net, x, index, static_cast<int>(net.num_sensors));
}

// SimplicialLDLT that exposes the symbolic factor after analyzePattern, so the
// cost of a factorisation can be judged before paying for it. METIS' nested
// dissection: on a default 100,000-sensor network 0.6 of AMD's work (5.2e9
// against 8.8e9), as expected for a planar-like graph.
class Ldlt : public Eigen::SimplicialLDLT<SpMat, Eigen::Lower, Eigen::MetisOrdering<int>> {
 public:
  // Work of the numeric factorisation (and of the selected inversion): sum over
  // columns of nnz(L_j)^2. Valid after analyzePattern.
  double symbolic_work() const {
    const int* outer = this->m_matrix.outerIndexPtr();
    double w = 0;
    for (Eigen::Index j = 0; j < this->m_matrix.cols(); ++j) {
      const double c = outer[j + 1] - outer[j];
      w += c * c;
    }
    return w;
  }
};

// Above this work (sum nnz(L_j)^2; the CRLB of a default 100,000-sensor
// network, work 5.2e9, took 21 s of CPU and 0.5 GB) rigidity and the CRLB are
// refused rather than stalling a run: dense or 3D networks fill in heavily.
constexpr double kFactorWorkLimit = 2e10;

// Factorises J unless that is too expensive; false when refused.
bool factorize_within_budget(const SpMat& J, Ldlt& ldlt, double* work = nullptr) {
  ldlt.analyzePattern(J);
  const double w = ldlt.symbolic_work();
  if (work) *work = w;
  if (w > kFactorWorkLimit) return false;
  ldlt.factorize(J);
  return true;
}

// Positive definite up to roundoff: the factorisation succeeded and every pivot
// of D is positive and above 1e-10 of the largest (an exactly singular J gives
// roundoff-sized pivots; a rigid but badly shaped framework stays far above).
bool positive_definite(const Ldlt& ldlt) {
  if (ldlt.info() != Eigen::Success) return false;
  const auto& D = ldlt.vectorD();
  if (D.size() == 0) return true;
  const double dmax = D.maxCoeff(), dmin = D.minCoeff();
  return dmax > 0 && dmin > 1e-10 * dmax;
}

// Sensors that move in some infinitesimal motion, i.e. the support of the null
// space of J: inverse iteration on J + eps I from random starts amplifies the
// null-space directions by (lambda / eps)^k over every other eigenvector.
std::vector<GlobalId> flexible_sensors(const SpMat& J, int p) {
  const int N = static_cast<int>(J.rows());
  double dmax = 0;
  for (int c = 0; c < N; ++c) dmax = std::max(dmax, J.coeff(c, c));
  if (dmax <= 0) dmax = 1;
  SpMat I(N, N);
  I.setIdentity();
  const SpMat Jr = J + (1e-9 * dmax) * I;
  Ldlt ldlt;
  ldlt.compute(Jr);
  std::vector<char> flex(static_cast<std::size_t>(N / p), 0);
  if (ldlt.info() != Eigen::Success) return {};
  for (std::uint64_t trial = 0; trial < 2; ++trial) {
    Eigen::VectorXd v(N);
    for (int r = 0; r < N; ++r) v[r] = standard_normal(0x5eed, RngStream::kInit, trial * N + r);
    for (int it = 0; it < 8; ++it) {
      v = ldlt.solve(v);
      v /= v.norm();
    }
    double bmax = 0;
    std::vector<double> b(static_cast<std::size_t>(N / p));
    for (int i = 0; i < N / p; ++i) {
      b[i] = v.segment(i * p, p).norm();
      bmax = std::max(bmax, b[i]);
    }
    for (int i = 0; i < N / p; ++i)
      if (b[i] > 1e-6 * bmax) flex[i] = 1;
  }
  std::vector<GlobalId> out;
  for (int i = 0; i < N / p; ++i)
    if (flex[i]) out.push_back(i);
  return out;
}

// Selected inversion (Takahashi equations) of the factor C = L D L^T of the
// permuted matrix C = P J P^T: Z = C^-1 satisfies Z = D^-1 L^-1 + (I - L^T) Z,
// evaluated backwards only on the pattern of L, which is closed under the
// recurrence: for rows r_a < r_b of column j, Z(r_b, r_a) sits in column r_a,
// whose rows (sorted) include every later row of column j, so one merge walk
// per r_a finds them all. On return z[a] = Z(inner[a], column of a) for every
// stored entry of L and zd[j] = Z(j, j); the trace is summed from j = N-1 down.
// Cost sum_j nnz(L_j)^2 / 2.
double selected_inverse(const Ldlt& ldlt, std::vector<double>& z, std::vector<double>& zd) {
  const SpMat& L = ldlt.matrixL().nestedExpression();
  const auto& D = ldlt.vectorD();
  const int N = static_cast<int>(L.cols());
  const int* outer = L.outerIndexPtr();
  const int* inner = L.innerIndexPtr();
  const int* nnz = L.innerNonZeroPtr();  // null when compressed
  const double* lx = L.valuePtr();
  auto col_end = [&](int c) { return nnz ? outer[c] + nnz[c] : outer[c + 1]; };
  z.assign(static_cast<std::size_t>(outer[N]), 0.0);
  zd.assign(static_cast<std::size_t>(N), 0.0);
  double trace = 0;
  for (int j = N - 1; j >= 0; --j) {
    const int s = outer[j], e = col_end(j);
    for (int a = s; a < e; ++a) z[a] = -lx[a] * zd[inner[a]];
    for (int a = s; a < e; ++a) {
      const int ra = inner[a];
      int q = outer[ra];
      const int qe = col_end(ra);
      for (int b = a + 1; b < e; ++b) {
        const int rb = inner[b];
        while (q < qe && inner[q] < rb) ++q;
        if (q == qe) break;
        if (inner[q] != rb) continue;  // cannot happen for a symbolic factor
        const double zab = z[q];       // Z(r_b, r_a)
        z[a] -= lx[b] * zab;
        z[b] -= lx[a] * zab;
      }
    }
    double diag = 1.0 / D[j];
    for (int a = s; a < e; ++a) diag -= lx[a] * z[a];
    zd[j] = diag;
    trace += diag;
  }
  return trace;
}

// The p x p diagonal blocks of J^-1 from the selected inverse of its factor:
// J^-1(r, c) = Z(P r, P c), and Z(r, c) for r > c is the entry of row r in
// column c of L (binary search; a block of J is structurally dense, so its
// entries are on the pattern of L).
void diagonal_blocks(const Ldlt& ldlt, int p, const std::vector<double>& z, const std::vector<double>& zd,
                     std::vector<double>& blocks) {
  const SpMat& L = ldlt.matrixL().nestedExpression();
  const int* outer = L.outerIndexPtr();
  const int* inner = L.innerIndexPtr();
  const int* nnz = L.innerNonZeroPtr();
  const auto& perm = ldlt.permutationP().indices();
  const int N = static_cast<int>(L.cols());
  blocks.assign(static_cast<std::size_t>(N) * p, 0.0);
  auto entry = [&](int r, int c) {
    if (r == c) return zd[r];
    if (r < c) std::swap(r, c);
    const int* b = inner + outer[c];
    const int* e = inner + (nnz ? outer[c] + nnz[c] : outer[c + 1]);
    const int* f = std::lower_bound(b, e, r);
    return (f != e && *f == r) ? z[static_cast<std::size_t>(f - inner)] : 0.0;
  };
  for (int i = 0; i < N / p; ++i)
    for (int a = 0; a < p; ++a)
      for (int c = 0; c < p; ++c)
        blocks[(static_cast<std::size_t>(i) * p + a) * p + c] = entry(perm[i * p + a], perm[i * p + c]);
}

const std::vector<double>* positions_or_truth(const Network& net, const std::vector<double>* positions) {
  const auto want = static_cast<std::size_t>(net.num_sensors) * static_cast<std::size_t>(net.dim);
  if (positions) return positions->size() == want ? positions : nullptr;
  if (net.has_truth && net.truth.size() == want) return &net.truth;
  return nullptr;
}

}  // namespace

LocalizabilityReport analyze_localizability(const Network& net, bool check_rigidity,
                                            const std::vector<double>* positions) {
  LocalizabilityReport r;
  const auto n = static_cast<std::size_t>(net.num_sensors);
  const int p = net.dim;
  r.flags.assign(n, 0);
  if (n == 0) return r;

  // Connected components of the sensor graph, and which of them see an anchor.
  UnionFind uf(n);
  for (std::size_t e = 0; e + 1 < net.sensor_edges.size(); e += 2) uf.unite(net.sensor_edges[e], net.sensor_edges[e + 1]);
  std::vector<char> anchored(n, 0);
  for (std::size_t e = 0; e + 1 < net.anchor_edges.size(); e += 2) anchored[uf.find(net.anchor_edges[e])] = 1;
  for (std::size_t i = 0; i < n; ++i) {
    const auto root = static_cast<std::size_t>(uf.find(static_cast<std::int64_t>(i)));
    if (root == i) {
      ++r.components;
      if (!anchored[i]) ++r.unanchored_components;
    }
    if (!anchored[root]) {
      r.unanchored.push_back(static_cast<GlobalId>(i));
      r.flags[i] |= kUnanchoredComponent;
    }
  }

  // p+1 distinct measurements are necessary to fix a sensor in R^p.
  const std::vector<GlobalId> cnt = distinct_measurements(net);
  for (std::size_t i = 0; i < n; ++i)
    if (cnt[i] < p + 1) {
      r.few_measurements.push_back(static_cast<GlobalId>(i));
      r.flags[i] |= kFewMeasurements;
    }

  // Infinitesimal rigidity of the anchored framework <=> J positive definite.
  const std::vector<double>* x = positions_or_truth(net, positions);
  if (check_rigidity && x && net.num_sensors <= kRigidityLimit) {
    const SpMat J = fisher_information(net, *x);
    Ldlt ldlt;
    if (factorize_within_budget(J, ldlt)) {
      r.rigidity_checked = true;
      r.rigid = positive_definite(ldlt);
      if (!r.rigid) {
        r.not_rigid = flexible_sensors(J, p);
        for (const GlobalId i : r.not_rigid) r.flags[static_cast<std::size_t>(i)] |= kNotRigid;
      }
    }
  }
  return r;
}

bool LocalizabilityReport::localizable() const {
  return unanchored.empty() && few_measurements.empty() && (!rigidity_checked || rigid);
}

namespace {
void list_ids(std::ostringstream& os, const std::vector<GlobalId>& ids) {
  os << " (";
  for (std::size_t a = 0; a < ids.size() && a < 10; ++a) os << (a ? ", " : "") << ids[a];
  if (ids.size() > 10) os << ", ...";
  os << ")";
}
}  // namespace

std::string LocalizabilityReport::summary() const {
  std::ostringstream os;
  os << flags.size() << " sensors in " << components << " connected component(s). ";
  if (unanchored_components > 0) {
    os << unanchored_components << " component(s) with no anchor measurement hold " << unanchored.size()
       << " sensor(s)";
    list_ids(os, unanchored);
    os << ". ";
  }
  if (!few_measurements.empty()) {
    os << few_measurements.size() << " sensor(s) have fewer than p+1 distinct measurements";
    list_ids(os, few_measurements);
    os << ". ";
  }
  if (!rigidity_checked) {
    os << "Rigidity not checked. ";
  } else if (rigid) {
    os << "The anchored framework is infinitesimally rigid. ";
  } else {
    os << "The anchored framework is not rigid (singular Fisher information)";
    if (!not_rigid.empty()) {
      os << "; " << not_rigid.size() << " sensor(s) in flexible parts";
      list_ids(os, not_rigid);
    }
    os << ". ";
  }
  os << (localizable() ? "Localizable." : "Not localizable.");
  return os.str();
}

namespace {

// Sensors of the components of the sensor graph that see an anchor.
std::vector<char> anchored_sensors(const Network& net) {
  const auto n = static_cast<std::size_t>(net.num_sensors);
  UnionFind uf(n);
  for (std::size_t e = 0; e + 1 < net.sensor_edges.size(); e += 2) uf.unite(net.sensor_edges[e], net.sensor_edges[e + 1]);
  std::vector<char> root_anchored(n, 0), in(n, 0);
  for (std::size_t e = 0; e + 1 < net.anchor_edges.size(); e += 2) root_anchored[uf.find(net.anchor_edges[e])] = 1;
  for (std::size_t i = 0; i < n; ++i) in[i] = root_anchored[uf.find(static_cast<std::int64_t>(i))];
  return in;
}

// Removes from `in`, repeatedly, every sensor with fewer than p measurements to
// sensors in the part or to anchors: it has a free direction whatever the rest
// does (a duplicate row counts twice, which only peels less; the numeric test
// decides). A queue of the sensors whose count dropped keeps this linear.
void peel_few_measurements(const Network& net, std::vector<char>& in) {
  const auto n = static_cast<std::size_t>(net.num_sensors);
  const int p = net.dim;
  std::vector<std::size_t> off(n + 1, 0);
  for (std::size_t e = 0; e + 1 < net.sensor_edges.size(); e += 2) {
    if (net.sensor_edges[e] == net.sensor_edges[e + 1]) continue;
    ++off[static_cast<std::size_t>(net.sensor_edges[e]) + 1];
    ++off[static_cast<std::size_t>(net.sensor_edges[e + 1]) + 1];
  }
  for (std::size_t i = 0; i < n; ++i) off[i + 1] += off[i];
  std::vector<GlobalId> nb(off[n]);
  std::vector<std::size_t> fill(off.begin(), off.end() - 1);
  for (std::size_t e = 0; e + 1 < net.sensor_edges.size(); e += 2) {
    const GlobalId i = net.sensor_edges[e], j = net.sensor_edges[e + 1];
    if (i == j) continue;
    nb[fill[static_cast<std::size_t>(i)]++] = j;
    nb[fill[static_cast<std::size_t>(j)]++] = i;
  }
  std::vector<GlobalId> cnt(n, 0);
  for (std::size_t e = 0; e + 1 < net.anchor_edges.size(); e += 2) ++cnt[static_cast<std::size_t>(net.anchor_edges[e])];
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t q = off[i]; q < off[i + 1]; ++q) cnt[i] += in[static_cast<std::size_t>(nb[q])] ? 1 : 0;
  std::vector<std::size_t> queue;
  for (std::size_t i = 0; i < n; ++i)
    if (in[i] && cnt[i] < p) queue.push_back(i);
  while (!queue.empty()) {
    const std::size_t i = queue.back();
    queue.pop_back();
    if (!in[i]) continue;
    in[i] = 0;
    for (std::size_t q = off[i]; q < off[i + 1]; ++q) {
      const auto j = static_cast<std::size_t>(nb[q]);
      if (in[j] && --cnt[j] < p) queue.push_back(j);
    }
  }
}

// Compact index of the sensors in the part (-1 outside); returns their count.
int compact_index(const std::vector<char>& in, std::vector<int>& index) {
  index.assign(in.size(), -1);
  int m = 0;
  for (std::size_t i = 0; i < in.size(); ++i)
    if (in[i]) index[i] = m++;
  return m;
}

constexpr int kMaxRigidRounds = 50;

// rigid_anchored_part, leaving the part's factorisation in `ldlt` (and its
// index) for the CRLB that follows.
RigidPart find_rigid_part(const Network& net, const std::vector<double>& x, const std::vector<double>& sw,
                          const std::vector<double>& aw, Ldlt& ldlt, std::vector<int>& index, int& m) {
  RigidPart r;
  const int p = net.dim;
  std::vector<char> in = anchored_sensors(net);
  m = 0;
  for (; r.rounds < kMaxRigidRounds; ++r.rounds) {
    peel_few_measurements(net, in);
    m = compact_index(in, index);
    if (m == 0) {
      r.identified = true;
      break;
    }
    const SpMat J = fisher_information(net, x, index, m, sw, aw);
    double work = 0;
    if (!factorize_within_budget(J, ldlt, &work)) {
      std::ostringstream os;
      os << "the sparse factor of the Fisher information is too dense (work " << work << " > " << kFactorWorkLimit
         << ")";
      r.reason = os.str();
      break;
    }
    if (positive_definite(ldlt)) {
      r.identified = true;
      ++r.rounds;
      break;
    }
    const std::vector<GlobalId> flex = flexible_sensors(J, p);  // compact ids
    if (flex.empty()) {
      r.reason = "the Fisher information is singular but its null space was not found";
      break;
    }
    std::vector<int> back(static_cast<std::size_t>(m));
    for (std::size_t i = 0; i < index.size(); ++i)
      if (index[i] >= 0) back[static_cast<std::size_t>(index[i])] = static_cast<int>(i);
    for (const GlobalId c : flex) in[static_cast<std::size_t>(back[static_cast<std::size_t>(c)])] = 0;
  }
  if (r.rounds == kMaxRigidRounds && !r.identified) r.reason = "no rigid part found within the round limit";
  if (!r.identified) m = 0, std::fill(in.begin(), in.end(), 0);
  for (std::size_t i = 0; i < in.size(); ++i) (in[i] ? r.covered : r.outside).push_back(static_cast<GlobalId>(i));
  return r;
}

// Per-measurement weights 1/sigma^2 for opt.sigma < 0 (empty when every
// range has the network's scalar sigma); throws-free: a reason on failure.
bool measurement_weights(const Network& net, std::vector<double>& sw, std::vector<double>& aw, double& scalar,
                         std::string& reason) {
  scalar = net.sigma ? *net.sigma : -1;
  const bool ps = !net.sensor_sigmas.empty(), pa = !net.anchor_sigmas.empty();
  if (!ps && !pa) {
    if (!(scalar > 0) || !std::isfinite(scalar)) {
      reason = "sigma unknown (give --sigma) or zero";
      return false;
    }
    return true;  // uniform: the caller scales by the scalar
  }
  if ((!ps && !net.sensor_ranges.empty()) || (!pa && !net.anchor_ranges.empty())) {
    if (!(scalar > 0) || !std::isfinite(scalar)) {
      reason = std::string("no sigma for the ") + (ps ? "anchor" : "sensor") +
               " ranges (the network has per-measurement sigmas for the others only and no scalar sigma)";
      return false;
    }
  }
  auto fill = [&](const std::vector<double>& sig, std::size_t rows, std::vector<double>& w) {
    w.assign(rows, 1.0 / (scalar * scalar));
    for (std::size_t e = 0; e < sig.size() && e < rows; ++e) w[e] = 1.0 / (sig[e] * sig[e]);
  };
  fill(net.sensor_sigmas, net.sensor_ranges.size(), sw);
  fill(net.anchor_sigmas, net.anchor_ranges.size(), aw);
  for (const auto* w : {&sw, &aw})
    for (const double v : *w)
      if (!(v > 0) || !std::isfinite(v)) {
        reason = "a per-measurement sigma is not a positive finite number";
        return false;
      }
  return true;
}

}  // namespace

RigidPart rigid_anchored_part(const Network& net, const std::vector<double>& x, const std::vector<double>& sensor_weights,
                              const std::vector<double>& anchor_weights) {
  Ldlt ldlt;
  std::vector<int> index;
  int m = 0;
  return find_rigid_part(net, x, sensor_weights, anchor_weights, ldlt, index, m);
}

void CrlbOptions::validate() const {
  if (std::isnan(sigma) || std::isinf(sigma)) throw Error("CRLB: sigma must be a finite number");
}

CrlbResult cramer_rao_bound(const Network& net, const CrlbOptions& opt) {
  CrlbResult res;
  const auto n = static_cast<std::size_t>(net.num_sensors);
  const int p = net.dim;
  if (n == 0) {
    res.reason = "the network has no sensors";
    return res;
  }
  const std::vector<double>* x = positions_or_truth(net, opt.positions);
  if (!x) {
    res.reason = opt.positions ? "the positions do not match the network" : "the network has no true positions";
    return res;
  }
  if (!std::isfinite(opt.sigma)) {
    res.reason = "sigma must be a finite number >= 0";
    return res;
  }
  if (net.num_sensors > kCrlbLimit) {
    std::ostringstream os;
    os << "n = " << net.num_sensors << " exceeds the CRLB size limit of " << kCrlbLimit << " sensors";
    res.reason = os.str();
    return res;
  }
  // Uniform sigma: J(sigma) = J(1) / sigma^2, so J^-1(sigma) = sigma^2 J(1)^-1.
  std::vector<double> sw, aw;
  double sigma = opt.sigma;
  if (sigma < 0 && !measurement_weights(net, sw, aw, sigma, res.reason)) return res;
  res.weighted = !sw.empty() || !aw.empty();
  Ldlt ldlt;
  std::vector<int> index;
  int m = 0;
  const RigidPart part = find_rigid_part(net, *x, sw, aw, ldlt, index, m);
  res.outside = part.outside;
  if (!part.identified) {
    res.reason = part.reason + "; the CRLB is refused for this network";
    return res;
  }
  if (m == 0) {
    res.reason = "no sensor is in an anchored rigid part (the Fisher information is singular everywhere)";
    return res;
  }
  std::vector<double> z, zd;
  const double tr = selected_inverse(ldlt, z, zd);
  res.defined = true;
  res.covered = m;
  const double scale = res.weighted ? 1.0 : sigma;
  res.rmse = scale * std::sqrt(tr / static_cast<double>(m));
  if (opt.covariance) {
    std::vector<double> blocks;
    diagonal_blocks(ldlt, p, z, zd, blocks);
    const std::size_t pp = std::size_t(p) * p;
    res.covariance.assign(n * pp, 0.0);
    for (std::size_t i = 0; i < n; ++i)
      if (index[i] >= 0)
        for (std::size_t t = 0; t < pp; ++t)
          res.covariance[i * pp + t] = scale * scale * blocks[static_cast<std::size_t>(index[i]) * pp + t];
  }
  return res;
}

CrlbResult cramer_rao_bound(const Network& net, double sigma) {
  CrlbOptions o;
  o.sigma = sigma;
  if (!(sigma >= 0)) {
    CrlbResult r;
    r.reason = "sigma must be a finite number >= 0";
    return r;
  }
  return cramer_rao_bound(net, o);
}

bool inverse_diagonal_blocks(int N, const std::vector<int>& rows, const std::vector<int>& cols,
                             const std::vector<double>& values, int p, std::vector<double>& blocks, double& trace) {
  std::vector<Eigen::Triplet<double, int>> trip;
  for (std::size_t t = 0; t < values.size(); ++t) trip.emplace_back(rows[t], cols[t], values[t]);
  SpMat A(N, N);
  A.setFromTriplets(trip.begin(), trip.end());
  Ldlt ldlt;
  ldlt.compute(A);
  if (!positive_definite(ldlt)) return false;
  std::vector<double> z, zd;
  trace = selected_inverse(ldlt, z, zd);
  diagonal_blocks(ldlt, p, z, zd, blocks);
  return true;
}

}  // namespace snl
