#include "consensus_reference.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>

namespace snl::reference {

namespace {

using consensus::Family;
using consensus::ProblemData;
using LD = long double;

// F, its gradient and Hessian at x, summed over nodes (and samples) in long double.
LD evaluate(const ProblemData& d, const std::vector<LD>& x, std::vector<LD>* g, std::vector<LD>* h) {
  const int q = d.dim;
  if (g) g->assign(q, 0);
  if (h) h->assign(static_cast<std::size_t>(q) * q, 0);
  LD f = 0;
  if (d.family == Family::kExp) {
    for (GlobalId p = 0; p < d.num_nodes; ++p) {
      const LD e1 = d.exp_a[p] * std::exp(LD(d.exp_b[p]) * x[0]), e2 = d.exp_c[p] * std::exp(-LD(d.exp_d[p]) * x[0]);
      f += e1 + e2;
      if (g) (*g)[0] += d.exp_b[p] * e1 - d.exp_d[p] * e2;
      if (h) (*h)[0] += LD(d.exp_b[p]) * d.exp_b[p] * e1 + LD(d.exp_d[p]) * d.exp_d[p] * e2;
    }
    return f;
  }
  // logistic: sum_s log(1 + e^(-y a.x)) + lambda/2 x.x (n nodes of lambda/2n each)
  for (int k = 0; k < q; ++k) {
    f += LD(d.lambda) / 2 * x[k] * x[k];
    if (g) (*g)[k] += d.lambda * x[k];
    if (h) (*h)[k * q + k] += d.lambda;
  }
  for (std::int64_t s = 0; s < d.num_samples(); ++s) {
    const double* a = &d.features[static_cast<std::size_t>(s) * q];
    LD t = 0;
    for (int k = 0; k < q; ++k) t += LD(a[k]) * x[k];
    const LD m = -LD(d.labels[s]) * t;  // log(1 + e^m)
    f += m > 0 ? m + std::log1p(std::exp(-m)) : std::log1p(std::exp(m));
    const LD sig = 1 / (1 + std::exp(-m));  // d/dm log(1 + e^m)
    for (int k = 0; k < q; ++k) {
      if (g) (*g)[k] += sig * -LD(d.labels[s]) * a[k];
      if (h)
        for (int j = 0; j < q; ++j) (*h)[k * q + j] += sig * (1 - sig) * a[k] * a[j];
    }
  }
  return f;
}

}  // namespace

std::vector<double> consensus_optimum(const ProblemData& d) {
  const int q = d.dim;
  if (d.family == Family::kQuadratic) {  // x*_k = sum_p h_pk r_pk / sum_p h_pk
    std::vector<double> x(q);
    for (int k = 0; k < q; ++k) {
      LD num = 0, den = 0;
      for (GlobalId p = 0; p < d.num_nodes; ++p) {
        num += LD(d.quad_h[p * q + k]) * d.quad_r[p * q + k];
        den += d.quad_h[p * q + k];
      }
      x[k] = static_cast<double>(num / den);
    }
    return x;
  }
  if (d.family == Family::kLeastSquares) {
    // Normal equations of sum_s (a_s.x - b_s)^2 + lambda/2 x.x (n nodes of lambda/2n each):
    // (2 sum_s a_s a_s^T + lambda I) x = 2 sum_s b_s a_s, accumulated and solved in long double.
    using MatL = Eigen::Matrix<LD, Eigen::Dynamic, Eigen::Dynamic>;
    using VecL = Eigen::Matrix<LD, Eigen::Dynamic, 1>;
    MatL H = MatL::Identity(q, q) * LD(d.lambda);
    VecL r = VecL::Zero(q);
    for (std::int64_t s = 0; s < d.num_samples(); ++s) {
      const double* a = &d.features[static_cast<std::size_t>(s) * q];
      for (int k = 0; k < q; ++k) {
        r(k) += 2 * LD(d.labels[s]) * a[k];
        for (int j = 0; j < q; ++j) H(k, j) += 2 * LD(a[k]) * a[j];
      }
    }
    const VecL x = H.ldlt().solve(r);
    std::vector<double> out(q);
    for (int k = 0; k < q; ++k) out[k] = static_cast<double>(x(k));
    return out;
  }
  std::vector<LD> x(q, 0), g, h, trial(q);
  LD prev = INFINITY;
  for (int it = 0; it < 200; ++it) {
    const LD f = evaluate(d, x, &g, &h);
    Eigen::MatrixXd H(q, q);
    Eigen::VectorXd G(q);
    for (int k = 0; k < q; ++k) {
      G(k) = static_cast<double>(g[k]);
      for (int j = 0; j < q; ++j) H(k, j) = static_cast<double>(h[k * q + j]);
    }
    const Eigen::VectorXd dx = -H.ldlt().solve(G);
    const LD dec2 = -(G.dot(dx));
    // Done at rounding level: tiny, or no longer decreasing once small (quadratic phase over).
    if (dec2 <= 1e-32L * (1 + std::fabs(f)) || (dec2 >= prev && dec2 <= 1e-24L * (1 + std::fabs(f))))
      return std::vector<double>(x.begin(), x.end());
    prev = dec2;
    LD t = 1;  // backtracking on F; full steps once the decrease is near F's rounding
    for (int j = 0; j < 80 && dec2 > 1e-8L * (1 + std::fabs(f)); ++j, t /= 2) {
      for (int k = 0; k < q; ++k) trial[k] = x[k] + t * dx(k);
      if (evaluate(d, trial, nullptr, nullptr) <= f - t * dec2 / 4) break;
    }
    for (int k = 0; k < q; ++k) trial[k] = x[k] + t * dx(k);
    x = trial;
  }
  throw std::runtime_error("reference consensus optimum: Newton did not reach rounding level in 200 iterations");
}

}  // namespace snl::reference
