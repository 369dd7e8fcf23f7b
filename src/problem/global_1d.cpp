#include "snl/problem/global_1d.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <limits>

#include "snl/core/common.hpp"

namespace snl {

std::string GlobalOptimum1DOptions::validate() const {
  if (max_terms < 1 || max_terms > 40) return "max_terms must be in [1, 40], got " + std::to_string(max_terms);
  return "";
}

namespace {

// One measurement as a least-squares row: coefficient +1 at i, -1 at j (j < 0:
// an anchor row), target base + s rho.
struct Term {
  std::int64_t i, j;
  double base, rho;
};

std::vector<Term> collect_terms(const Network& net) {
  std::vector<Term> t;
  for (std::size_t e = 0; e < net.sensor_ranges.size(); ++e)
    t.push_back({net.sensor_edges[2 * e], net.sensor_edges[2 * e + 1], 0.0, net.sensor_ranges[e]});
  for (std::size_t e = 0; e < net.anchor_ranges.size(); ++e)
    t.push_back({net.anchor_edges[2 * e], -1, net.anchors[std::size_t(net.anchor_edges[2 * e + 1])], net.anchor_ranges[e]});
  return t;
}

// The ML cost f(x) itself (003 eq. 2 on the line).
double ml_cost(const std::vector<Term>& terms, const Eigen::VectorXd& x) {
  double f = 0;
  for (const Term& t : terms) {
    const double z = x[t.i] - (t.j >= 0 ? x[t.j] : t.base);
    f += 0.5 * (std::abs(z) - t.rho) * (std::abs(z) - t.rho);
  }
  return f;
}

// b = A^T c_s and c_s^T c_s of pattern `s` (bit k set: sign -1 on term k).
void pattern_rhs(const std::vector<Term>& terms, std::uint64_t s, Eigen::VectorXd& b, double& cc) {
  b.setZero();
  cc = 0;
  for (std::size_t k = 0; k < terms.size(); ++k) {
    const Term& t = terms[k];
    const double c = t.base + (((s >> k) & 1) ? -t.rho : t.rho);
    b[t.i] += c;
    if (t.j >= 0) b[t.j] -= c;
    cc += c * c;
  }
}

}  // namespace

GlobalOptimum1D global_ml_optimum_1d(const Network& net, const GlobalOptimum1DOptions& opt) {
  if (const std::string m = opt.validate(); !m.empty()) throw Error("global optimum: " + m);
  if (net.dim != 1) throw Error("the exact global optimum is for one-dimensional networks (dim 1), got dim " + std::to_string(net.dim));
  const std::vector<Term> terms = collect_terms(net);
  const auto T = static_cast<int>(terms.size());
  if (T > opt.max_terms)
    throw Error("the exact global optimum enumerates 2^T sign patterns: this network has T = " + std::to_string(T) +
                " measurements, more than the limit " + std::to_string(opt.max_terms));
  const auto n = static_cast<Eigen::Index>(net.num_sensors);
  Eigen::MatrixXd AtA = Eigen::MatrixXd::Zero(n, n);
  for (const Term& t : terms) {
    AtA(t.i, t.i) += 1;
    if (t.j >= 0) {
      AtA(t.j, t.j) += 1;
      AtA(t.i, t.j) -= 1;
      AtA(t.j, t.i) -= 1;
    }
  }
  Eigen::LLT<Eigen::MatrixXd> llt(AtA);
  if (llt.info() != Eigen::Success || n == 0)
    throw Error("the exact global optimum needs every connected component to measure an anchor (A^T A is singular)");
  const Eigen::MatrixXd M = llt.solve(Eigen::MatrixXd::Identity(n, n));

  // Gray-code walk: step g flips the sign of term ctz(g). b, u = M b and c^T c
  // are updated in O(n) and refreshed exactly every kRefresh steps.
  constexpr std::uint64_t kRefresh = 4096;
  const std::uint64_t count = std::uint64_t(1) << T;
  Eigen::VectorXd b(n), u(n);
  double cc = 0, best = std::numeric_limits<double>::infinity();
  std::uint64_t best_s = 0, s = 0;
  for (std::uint64_t g = 0; g < count; ++g) {
    if (g > 0) {
      const int k = __builtin_ctzll(g);
      s ^= std::uint64_t(1) << k;
      if (g % kRefresh != 0) {
        const Term& t = terms[std::size_t(k)];
        const double c_new = t.base + (((s >> k) & 1) ? -t.rho : t.rho), c_old = 2 * t.base - c_new;
        const double dc = c_new - c_old;
        cc += c_new * c_new - c_old * c_old;
        b[t.i] += dc;
        u += dc * M.col(t.i);
        if (t.j >= 0) {
          b[t.j] -= dc;
          u -= dc * M.col(t.j);
        }
      }
    }
    if (g % kRefresh == 0) {
      pattern_rhs(terms, s, b, cc);
      u = M * b;
    }
    const double q = 0.5 * (cc - b.dot(u));
    if (q < best) {
      best = q;
      best_s = s;
    }
  }
  pattern_rhs(terms, best_s, b, cc);
  const Eigen::VectorXd x = M * b;
  GlobalOptimum1D r;
  r.positions.assign(x.data(), x.data() + n);
  r.cost = ml_cost(terms, x);
  r.patterns = count;
  return r;
}

}  // namespace snl
