#pragma once
// Small helpers shared by the algorithm implementations (internal header).
#include <algorithm>
#include <vector>

#include "snl/problem/problem.hpp"

namespace snl::detail {

/// A local array [num_local * p] holding the owned rows of x (ghost rows zero).
inline std::vector<double> with_ghost_rows(const LocalizationProblem& prob, const std::vector<double>& x) {
  std::vector<double> out(std::size_t(prob.num_local()) * prob.dim(), 0.0);
  std::copy(x.begin(), x.begin() + std::size_t(prob.num_owned()) * prob.dim(), out.begin());
  return out;
}

/// Over owned rows: *d = ||now - before||^2, *s = ||now||^2 (the relative-improvement test).
inline void diff_norms(const LocalizationProblem& prob, const double* now, const double* before, double* d,
                       double* s) {
  const std::size_t m = std::size_t(prob.num_owned()) * prob.dim();
  double dd = 0, ss = 0;
  for (std::size_t t = 0; t < m; ++t) {
    const double q = now[t] - before[t];
    dd += q * q;
    ss += now[t] * now[t];
  }
  *d = dd;
  *s = ss;
}

}  // namespace snl::detail
