// The SDP, ESDP and EDM relaxations (relaxations.hpp) in DSDP's standard form.
#include "solvers/centralized/relaxations.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <map>

#include "snl/core/common.hpp"

namespace snl::detail {

namespace {

using Net = GatheredNetwork;

double sq_norm(const double* a, int p) {
  double s = 0;
  for (int c = 0; c < p; ++c) s += a[c] * a[c];
  return s;
}

// sum over measurements of d^2 / 2: the constant of the lifted cost terms.
double half_sum_sq_ranges(const Net& net) {
  double s = 0;
  for (const auto& e : net.edges) s += 0.5 * e.d * e.d;
  for (const auto& e : net.anchor_edges) s += 0.5 * e.r * e.r;
  return s;
}

// Primal form, shared by sdp and edm: per measurement e a 2x2 block
// T_e = [1 delta_e; delta_e D_e] with T_e(0,0) = 1, cost (D_e - 2 d_e delta_e) / 2;
// returns the constraint of each block's D_e (its lifted-distance terms are
// added by the caller: T_e(1,1) - D_e(Z) = rhs).
int add_measurement_block(SdpProblem& sp, double d) {
  const int blk = sp.add_block(2);
  sp.c.push_back({blk, 1, 1, 0.5});
  sp.c.push_back({blk, 1, 0, -0.5 * d});  // off-diagonal: counted twice in <C, X>
  const int k1 = sp.add_constraint(1.0);
  sp.a[k1].push_back({blk, 0, 0, 1.0});
  const int k2 = sp.add_constraint(0.0);
  sp.a[k2].push_back({blk, 1, 1, 1.0});
  return k2;
}
std::vector<int> add_measurement_blocks(SdpProblem& sp, const Net& net) {
  std::vector<int> link;
  for (const auto& e : net.edges) link.push_back(add_measurement_block(sp, e.d));
  for (const auto& e : net.anchor_edges) link.push_back(add_measurement_block(sp, e.r));
  return link;
}

// Biswas-Ye: Z = [I X; X' Y] (block 0), sensor i at row p + i.
SdpProblem build_sdp(const Net& net) {
  SdpProblem sp;
  const int p = net.p, n = static_cast<int>(net.n);
  const int z = sp.add_block(p + n);
  for (int c = 0; c < p; ++c)
    for (int c2 = 0; c2 <= c; ++c2) {  // Z(1:p, 1:p) = I
      const int k = sp.add_constraint(c == c2 ? 1.0 : 0.0);
      sp.a[k].push_back({z, c, c2, c == c2 ? 1.0 : 0.5});
    }
  const std::vector<int> link = add_measurement_blocks(sp, net);
  std::size_t t = 0;
  for (const auto& e : net.edges) {  // D = Y_ii + Y_jj - 2 Y_ij
    auto& a = sp.a[link[t++]];
    const int i = p + static_cast<int>(e.i), j = p + static_cast<int>(e.j);
    a.push_back({z, i, i, -1.0});
    a.push_back({z, j, j, -1.0});
    a.push_back({z, j, i, 1.0});
  }
  for (const auto& e : net.anchor_edges) {  // D = Y_ii - 2 a'x_i + |a|^2
    const int k = link[t++];
    const double* ak = &net.anchors[std::size_t(e.k) * p];
    const int i = p + static_cast<int>(e.i);
    sp.a[k].push_back({z, i, i, -1.0});
    for (int c = 0; c < p; ++c) sp.a[k].push_back({z, i, c, ak[c]});
    sp.b[k] = sq_norm(ak, p);
  }
  sp.sign = 1.0;
  sp.offset = half_sum_sq_ranges(net);
  return sp;
}

// Oguz-Ekim et al.: the Gram matrix G of sensors 0..n-1 and anchors n..n+m-1,
// centred (G 1 = 0). The centring is written as G = V H V' with H >= 0 of order
// N-1 and V = [I; -1'] (the last point is minus the sum of the others): a
// constraint G 1 = 0 on G itself would leave the SDP without a strictly
// feasible point, and DSDP stalls ("small steps") on such problems.
class EdmBuilder {
 public:
  explicit EdmBuilder(const Net& net)
      : net_(net), p_(net.p), n_(static_cast<int>(net.n)), N_(n_ + static_cast<int>(net.num_anchors())) {}
  SdpProblem build() {
    h_ = sp_.add_block(N_ - 1);
    const std::vector<int> link = add_measurement_blocks(sp_, net_);
    // The anchors' mutual distances, known exactly, enter as measurements:
    // as equality constraints they would confine G to a face of the cone
    // (the anchors are rigid in any dimension), again with no strictly
    // feasible point.
    const int m = N_ - n_;
    double anchor_terms = 0;
    for (int k = 0; k < m; ++k)
      for (int l = k + 1; l < m; ++l) {
        double d2 = 0;
        for (int c = 0; c < p_; ++c)
          d2 += std::pow(net_.anchors[std::size_t(k) * p_ + c] - net_.anchors[std::size_t(l) * p_ + c], 2);
        add_distance(add_measurement_block(sp_, std::sqrt(d2)), n_ + k, n_ + l, -1.0);
        anchor_terms += 0.5 * d2;
      }
    std::size_t t = 0;
    for (const auto& e : net_.edges) add_distance(link[t++], static_cast<int>(e.i), static_cast<int>(e.j), -1.0);
    for (const auto& e : net_.anchor_edges)
      add_distance(link[t++], static_cast<int>(e.i), n_ + static_cast<int>(e.k), -1.0);
    sp_.sign = 1.0;
    sp_.offset = half_sum_sq_ranges(net_) + anchor_terms;
    return std::move(sp_);
  }

 private:
  // Adds coef * (G_aa + G_bb - 2 G_ab) to constraint k, in terms of H.
  void add_distance(int k, int a, int b, double coef) {
    std::map<std::pair<int, int>, double> acc;
    add_g(acc, a, a, coef);
    add_g(acc, b, b, coef);
    add_g(acc, a, b, -2.0 * coef);
    for (const auto& kv : acc)
      if (kv.second != 0) sp_.a[k].push_back({h_, kv.first.first, kv.first.second, kv.second});
  }
  // c * G_ab = c * sum_{k,l} V_ak V_bl H_kl, into lower-triangle entries of the
  // symmetric form (an off-diagonal entry v stands for 2 v H_kl).
  void add_g(std::map<std::pair<int, int>, double>& acc, int a, int b, double c) {
    auto rows = [&](int q) {  // (index, weight) of row q of V
      std::vector<std::pair<int, double>> r;
      if (q < N_ - 1) r.push_back({q, 1.0});
      else
        for (int s = 0; s < N_ - 1; ++s) r.push_back({s, -1.0});
      return r;
    };
    for (const auto& ka : rows(a))
      for (const auto& lb : rows(b)) {
        const int i = std::max(ka.first, lb.first), j = std::min(ka.first, lb.first);
        acc[{i, j}] += (i == j ? 1.0 : 0.5) * c * ka.second * lb.second;
      }
  }

  const Net& net_;
  int p_, n_, N_;
  int h_ = 0;
  SdpProblem sp_;
};

// Wang-Zheng-Boyd-Ye, in the dual (LMI) form: free variables y, objective
// min c'y (so b = -c), LMIs F0 + sum_k y_k F_k >= 0 (so C = F0, A_k = -F_k).
class EsdpBuilder {
 public:
  explicit EsdpBuilder(const Net& net)
      : net_(net), p_(net.p), n_(static_cast<int>(net.n)), ne_(static_cast<int>(net.edges.size())) {
    const int nm = ne_ + static_cast<int>(net.anchor_edges.size());
    sp_.a.resize(std::size_t(n_) * p_ + n_ + ne_ + nm);
    sp_.b.assign(sp_.a.size(), 0.0);
  }
  SdpProblem build() {
    for (int e = 0; e < ne_; ++e) edge_block(e);
    for (int i = 0; i < n_; ++i) node_block(i);
    int t = 0;
    for (const auto& e : net_.edges) {  // D = Y_ii + Y_jj - 2 Y_ij
      const int blk = measurement_block(t, e.d);
      const int i = static_cast<int>(e.i), j = static_cast<int>(e.j);
      f(yii(i), blk, 1, 1, 1.0);
      f(yii(j), blk, 1, 1, 1.0);
      f(yij(t), blk, 1, 1, -2.0);
      cost(yii(i), 0.5), cost(yii(j), 0.5), cost(yij(t), -1.0);
      ++t;
    }
    double offset = 0;
    for (const auto& e : net_.anchor_edges) {  // D = Y_ii - 2 a'x_i + |a|^2
      const int blk = measurement_block(t, e.r);
      const int i = static_cast<int>(e.i);
      const double* a = &net_.anchors[std::size_t(e.k) * p_];
      f(yii(i), blk, 1, 1, 1.0);
      cost(yii(i), 0.5);
      for (int c = 0; c < p_; ++c) f(xv(i, c), blk, 1, 1, -2.0 * a[c]), cost(xv(i, c), -a[c]);
      sp_.c.push_back({blk, 1, 1, sq_norm(a, p_)});
      offset += 0.5 * sq_norm(a, p_);
      ++t;
    }
    sp_.sign = -1.0;  // maximizing b'y = -c'y
    sp_.offset = offset + half_sum_sq_ranges(net_);
    return std::move(sp_);
  }

 private:
  int xv(int i, int c) const { return i * p_ + c; }
  int yii(int i) const { return n_ * p_ + i; }
  int yij(int e) const { return n_ * p_ + n_ + e; }
  int delta(int t) const { return n_ * p_ + n_ + ne_ + t; }
  void f(int var, int blk, int i, int j, double v) { sp_.a[var].push_back({blk, i, j, -v}); }
  void cost(int var, double v) { sp_.b[var] -= v; }
  int identity_block(int size) {
    const int blk = sp_.add_block(size);
    for (int c = 0; c < p_; ++c) sp_.c.push_back({blk, c, c, 1.0});
    return blk;
  }
  // [I x_i x_j; x_i' Y_ii Y_ij; x_j' Y_ij Y_jj] >= 0
  void edge_block(int e) {
    const int blk = identity_block(p_ + 2);
    const int i = static_cast<int>(net_.edges[e].i), j = static_cast<int>(net_.edges[e].j);
    for (int c = 0; c < p_; ++c) f(xv(i, c), blk, p_, c, 1.0), f(xv(j, c), blk, p_ + 1, c, 1.0);
    f(yii(i), blk, p_, p_, 1.0);
    f(yii(j), blk, p_ + 1, p_ + 1, 1.0);
    f(yij(e), blk, p_ + 1, p_, 1.0);
  }
  // [I x_i; x_i' Y_ii] >= 0
  void node_block(int i) {
    const int blk = identity_block(p_ + 1);
    for (int c = 0; c < p_; ++c) f(xv(i, c), blk, p_, c, 1.0);
    f(yii(i), blk, p_, p_, 1.0);
  }
  // [1 delta; delta D] >= 0 with cost -d delta (D's terms added by the caller)
  int measurement_block(int t, double d) {
    const int blk = sp_.add_block(2);
    sp_.c.push_back({blk, 0, 0, 1.0});
    f(delta(t), blk, 1, 0, 1.0);
    cost(delta(t), -d);
    return blk;
  }

  const Net& net_;
  int p_, n_, ne_;
  SdpProblem sp_;
};

// Classical MDS of the Gram matrix, then the anchors' rows mapped onto the
// anchors by the orthogonal Procrustes transform (rotation or reflection, and shift).
std::vector<double> edm_positions(const Net& net, const std::vector<double>& hpacked) {
  const int p = net.p, n = static_cast<int>(net.n), m = static_cast<int>(net.num_anchors()), N = n + m;
  Eigen::MatrixXd H(N - 1, N - 1), V = Eigen::MatrixXd::Zero(N, N - 1);
  for (int r = 0; r < N - 1; ++r)
    for (int s = 0; s <= r; ++s) H(r, s) = H(s, r) = hpacked[packed_index(r, s)];
  V.topRows(N - 1).setIdentity();
  V.row(N - 1).setConstant(-1.0);
  const Eigen::MatrixXd G = V * H * V.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(G);
  Eigen::MatrixXd P(N, p);  // eigenvalues ascend: the top p are last
  for (int c = 0; c < p; ++c) {
    const int col = N - 1 - c;
    P.col(c) = es.eigenvectors().col(col) * std::sqrt(std::max(0.0, es.eigenvalues()(col)));
  }
  Eigen::MatrixXd PA = P.bottomRows(m), A(m, p);
  for (int k = 0; k < m; ++k)
    for (int c = 0; c < p; ++c) A(k, c) = net.anchors[std::size_t(k) * p + c];
  const Eigen::RowVectorXd mp = PA.colwise().mean(), ma = A.colwise().mean();
  const Eigen::MatrixXd HA = (PA.rowwise() - mp).transpose() * (A.rowwise() - ma);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(HA, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::MatrixXd R = svd.matrixU() * svd.matrixV().transpose();
  std::vector<double> x(std::size_t(n) * p);
  for (int i = 0; i < n; ++i) {
    const Eigen::RowVectorXd xi = (P.row(i) - mp) * R + ma;
    for (int c = 0; c < p; ++c) x[std::size_t(i) * p + c] = xi(c);
  }
  return x;
}

}  // namespace

SdpProblem build_relaxation(RelaxationKind kind, const GatheredNetwork& net) {
  switch (kind) {
    case RelaxationKind::kSdp: return build_sdp(net);
    case RelaxationKind::kEsdp: return EsdpBuilder(net).build();
    case RelaxationKind::kEdm: return EdmBuilder(net).build();
  }
  throw Error("unknown relaxation");
}

std::vector<double> relaxation_positions(RelaxationKind kind, const GatheredNetwork& net, const SdpSolution& s) {
  const int p = net.p;
  std::vector<double> x(std::size_t(net.n) * p);
  if (kind == RelaxationKind::kEdm) return edm_positions(net, s.x.at(0));
  for (std::int64_t i = 0; i < net.n; ++i)
    for (int c = 0; c < p; ++c)
      x[std::size_t(i) * p + c] = kind == RelaxationKind::kEsdp
                                      ? s.y.at(std::size_t(i) * p + c)
                                      : s.x.at(0).at(packed_index(p + static_cast<int>(i), c));
  return x;
}

}  // namespace snl::detail
