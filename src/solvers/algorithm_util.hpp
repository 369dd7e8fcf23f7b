#pragma once
// Small helpers shared by the algorithm implementations (internal header).
#include <algorithm>
#include <vector>

#include "kernels/kernels.hpp"
#include "snl/problem/problem.hpp"

namespace snl::detail {

/// MM's edge and anchor variables at their best values for x (ghost rows
/// included), where the surrogate equals the ML cost (000, Algorithm 1's start;
/// mm-accel's reset): y_e = P_sphere(d_e)(x_i - x_j) in the orientation i < j
/// (global ids), aw_ik = P_sphere(r_ik)(x_i - a_k). y_at(v, e, c) is the
/// address of coordinate c of CSR slot e of owned node v (the layout's).
template <int P, class YAt>
void best_edge_variables(const LocalizationProblem& prob, const double* x, YAt y_at, double* aw) {
  const auto& gr = prob.graph();
  const auto& off = gr.offsets();
  const auto& adj = gr.adjacency();
  const auto& aoff = prob.anchor_offsets();
  for (LocalId v = 0; v < gr.num_owned(); ++v) {
    for (auto e = off[v]; e < off[v + 1]; ++e) {
      const bool fwd = gr.global_id(v) < gr.global_id(adj[e]);
      const LocalId i = fwd ? v : adj[e], j = fwd ? adj[e] : v;
      double y[P];
      for (int c = 0; c < P; ++c) y[c] = x[std::size_t(i) * P + c] - x[std::size_t(j) * P + c];
      project_sphere<P>(gr.edge_value(e), y);
      for (int c = 0; c < P; ++c) *y_at(v, e, c) = y[c];
    }
    for (auto e = aoff[v]; e < aoff[v + 1]; ++e) {
      const double* a = &prob.anchors()[std::size_t(prob.anchor_ids()[e]) * P];
      double* w = &aw[std::size_t(e) * P];
      for (int c = 0; c < P; ++c) w[c] = x[std::size_t(v) * P + c] - a[c];
      project_sphere<P>(prob.anchor_ranges()[e], w);
    }
  }
}

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
