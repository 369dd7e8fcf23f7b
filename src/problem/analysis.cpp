// Whole-network analyses: degrees, localizability (connectivity, anchoring,
// measurement counts, infinitesimal rigidity) and the Cramér-Rao bound.
#include "snl/problem/analysis.hpp"

#include <Eigen/Sparse>
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

// Fisher information matrix at positions x with sigma = 1 (Patwari et al.
// 2005; spec "Cramér-Rao lower bound"): J_ii += u u^T per measurement of i,
// J_ij = -u u^T per sensor pair. Zero-length pairs carry no direction: skipped.
SpMat fisher_information(const Network& net, const std::vector<double>& x) {
  const int p = net.dim;
  const auto n = static_cast<std::size_t>(net.num_sensors);
  std::vector<Eigen::Triplet<double, int>> trip;
  trip.reserve(net.sensor_edges.size() / 2 * 4 * p * p + net.anchor_edges.size() / 2 * p * p + n * p);
  for (std::size_t r = 0; r < n * p; ++r) trip.emplace_back(int(r), int(r), 0.0);  // keep the diagonal structural
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
    if (i == j || !unit(&x[i * p], &x[j * p])) continue;
    for (int a = 0; a < p; ++a)
      for (int b = 0; b < p; ++b) {
        const double v = u[a] * u[b];
        trip.emplace_back(int(i * p + a), int(i * p + b), v);
        trip.emplace_back(int(j * p + a), int(j * p + b), v);
        trip.emplace_back(int(i * p + a), int(j * p + b), -v);
        trip.emplace_back(int(j * p + a), int(i * p + b), -v);
      }
  }
  for (std::size_t e = 0; e + 1 < net.anchor_edges.size(); e += 2) {
    const auto i = static_cast<std::size_t>(net.anchor_edges[e]), k = static_cast<std::size_t>(net.anchor_edges[e + 1]);
    if (!unit(&x[i * p], &net.anchors[k * p])) continue;
    for (int a = 0; a < p; ++a)
      for (int b = 0; b < p; ++b) trip.emplace_back(int(i * p + a), int(i * p + b), u[a] * u[b]);
  }
  SpMat J(int(n * p), int(n * p));
  J.setFromTriplets(trip.begin(), trip.end());
  return J;
}

// SimplicialLDLT that exposes the symbolic factor after analyzePattern, so the
// cost of a factorisation can be judged before paying for it.
class Ldlt : public Eigen::SimplicialLDLT<SpMat, Eigen::Lower, Eigen::AMDOrdering<int>> {
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

// Above this work (sum nnz(L_j)^2: ~2 s to factor, ~10 s for the CRLB trace)
// rigidity and the CRLB are refused rather than stalling a run: dense or 3D
// networks near kRigidityLimit fill in heavily.
constexpr double kFactorWorkLimit = 2e9;

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

// tr(J^-1) from the factor J = P^T L D L^T P by selected inversion (Takahashi
// equations): Z = D^-1 L^-1 + (I - L^T) Z, evaluated backwards only on the
// pattern of L, which is closed under the recurrence: for rows r_a < r_b of
// column j, Z(r_b, r_a) sits in column r_a, whose rows (sorted) include every
// later row of column j, so one merge walk per r_a finds them all.
// Cost sum_j nnz(L_j)^2 / 2.
double trace_of_inverse(const Ldlt& ldlt) {
  const SpMat& L = ldlt.matrixL().nestedExpression();
  const auto& D = ldlt.vectorD();
  const int N = static_cast<int>(L.cols());
  const int* outer = L.outerIndexPtr();
  const int* inner = L.innerIndexPtr();
  const int* nnz = L.innerNonZeroPtr();  // null when compressed
  const double* lx = L.valuePtr();
  auto col_end = [&](int c) { return nnz ? outer[c] + nnz[c] : outer[c + 1]; };
  std::vector<double> z(static_cast<std::size_t>(outer[N]), 0.0), zd(static_cast<std::size_t>(N), 0.0);
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

CrlbResult cramer_rao_bound(const Network& net, double sigma) {
  CrlbResult res;
  const auto n = static_cast<std::size_t>(net.num_sensors);
  if (n == 0) {
    res.reason = "the network has no sensors";
    return res;
  }
  const std::vector<double>* x = positions_or_truth(net, nullptr);
  if (!x) {
    res.reason = "the network has no true positions";
    return res;
  }
  if (!std::isfinite(sigma) || sigma < 0) {
    res.reason = "sigma must be a finite number >= 0";
    return res;
  }
  if (net.num_sensors > kCrlbLimit) {
    std::ostringstream os;
    os << "n = " << net.num_sensors << " exceeds the CRLB size limit of " << kCrlbLimit << " sensors";
    res.reason = os.str();
    return res;
  }
  // J(sigma) = J(1) / sigma^2, so tr(J(sigma)^-1) = sigma^2 tr(J(1)^-1).
  const SpMat J = fisher_information(net, *x);
  Ldlt ldlt;
  double work = 0;
  if (!factorize_within_budget(J, ldlt, &work)) {
    std::ostringstream os;
    os << "the sparse factor of the Fisher information is too dense (work " << work << " > " << kFactorWorkLimit
       << "); the CRLB is refused for this network";
    res.reason = os.str();
    return res;
  }
  if (!positive_definite(ldlt)) {
    res.reason = "anchored network is not rigid (the Fisher information matrix is singular)";
    return res;
  }
  const double tr = trace_of_inverse(ldlt);
  res.defined = true;
  res.rmse = sigma * std::sqrt(tr / static_cast<double>(n));
  return res;
}

}  // namespace snl
