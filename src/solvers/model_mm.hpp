#pragma once
// MM's step under a measurement model other than unweighted l2 (weights
// 1/sigma^2, Huber loss; weights.hpp), on plain pointers so that plain MM
// (ModelMM, weighted.cpp) and its accelerated form (mm_accel.cpp) run the
// same arithmetic (internal header). One node at a time in CSR order; each
// node sums its neighbours in global-id order, then its anchors in id order:
// bit-identical for any number of ranks. Derivation: weighted.cpp, ModelMM.
#include <cstdint>
#include <vector>

#include "core/exact_sum.hpp"
#include "snl/problem/problem.hpp"

namespace snl::detail {

class ModelMMKernel {
 public:
  explicit ModelMMKernel(const LocalizationProblem& prob);
  /// 2 max_i sum_j w_ij + max_i sum_k w_ik + 2: the reported constant (the steps are per node).
  double lipschitz() const { return L_; }
  /// What the kernel itself holds (1/D_x per owned node).
  std::int64_t bytes() const { return static_cast<std::int64_t>(sizeof(double) * dinv_.capacity()); }
  /// y (p per CSR slot) and aw (p per anchor measurement) at their best
  /// values for x (ghost rows included): y_e = P_sphere(d_e)(x_i - x_j) in the
  /// orientation i < j (global ids), aw_ik = P_sphere(r_ik)(x_i - a_k). There
  /// the surrogate equals the ML cost.
  void init(const double* x, double* y, double* aw) const;
  /// One MM step from (x, y, aw): x(t+1) into xn (owned rows), y and aw in
  /// place; *d = ||xn - x||^2 and *s = ||xn||^2 over the owned rows (where given).
  void step(const double* x, double* xn, double* y, double* aw, double* d, double* s) const;
  /// Owned nodes [v0, v1): the surrogate's terms w rho(|dz - y|) into *F and,
  /// if f is given, the ML cost's w rho(||dz| - d|) into *f; each sensor edge
  /// at its smaller end (so once over all ranks), then the anchor edges.
  void terms(const double* x, const double* y, const double* aw, LocalId v0, LocalId v1, ExactSum* F,
             ExactSum* f) const;

 private:
  template <int P>
  void init_p(const double* x, double* y, double* aw) const;
  template <int P>
  void step_p(const double* x, double* xn, double* y, double* aw, double* d, double* s) const;
  template <int P>
  void terms_p(const double* x, const double* y, const double* aw, LocalId v0, LocalId v1, ExactSum* F,
               ExactSum* f) const;

  const LocalizationProblem& prob_;
  double L_;
  std::vector<double> dinv_;  // 1 / D_x per owned node
};

}  // namespace snl::detail
