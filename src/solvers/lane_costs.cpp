#include "solvers/lane_costs.hpp"

#include <algorithm>
#include <cmath>

#include "core/dim_dispatch.hpp"
#include "core/exact_sum.hpp"
#include "kernels/kernels.hpp"

namespace snl::detail {

namespace {

// metrics.cpp's terms for the unweighted l2 model: per sensor pair (at its
// forward slot, so once over all ranks) and per anchor pair, with nz = |z|:
// 0.5 (nz - rho)^2 into f; into f_hat where nz > rho, else into the
// certificate (003, eq. 22); 0.5 rho^2 into the a-priori bound (eq. 23).
template <unsigned M>
struct Terms {
  ExactSum t[4];
  void add(double nz, double rho) {
    if (M & (kMlSum | kCertificateSum) || ((M & kRelaxedSum) && nz > rho)) {
      const double ml = 0.5 * (nz - rho) * (nz - rho);
      if (M & kMlSum) t[0].add(ml);
      if (nz > rho) {
        if (M & kRelaxedSum) t[1].add(ml);
      } else if (M & kCertificateSum) {
        t[2].add(ml);
      }
    }
    if (M & kAprioriSum) t[3].add(0.5 * rho * rho);
  }
};

template <int P>
double norm_of_difference(const double* a, const double* b) {
  double s = 0;
  for (int k = 0; k < P; ++k) s += (a[k] - b[k]) * (a[k] - b[k]);
  return std::sqrt(s);
}

// Chunk c's terms: its forward sensor slots, then its anchor pairs.
template <int P, unsigned M>
void add_chunk_terms(const LocalizationProblem& prob, const NodeLanes& nl, std::int64_t c, const double* x,
                     Terms<M>& t) {
  const int C = nl.lanes;
  const double* own = x + std::size_t(nl.first[c]) * P;
  for (std::int64_t g = nl.group_off[c]; g < nl.group_off[c + 1]; ++g) {
    for (unsigned mask = nl.real[g] & nl.fwd[g]; mask; mask &= mask - 1) {  // the forward slots
      const int L = __builtin_ctz(mask);
      const int q = NodeLanes::lane_node(L, C);
      t.add(norm_of_difference<P>(own + P * q, x + std::size_t(nl.adj[g * C + q]) * P), nl.rho[g * C + L]);
    }
  }
  const double* anc = prob.anchors().data();
  for (auto e = nl.anchor_off[c]; e < nl.anchor_off[c + 1]; ++e)
    t.add(norm_of_difference<P>(own + P * nl.anchor_q[e], anc + std::size_t(prob.anchor_ids()[e]) * P),
          prob.anchor_ranges()[e]);
}

template <int P, unsigned M>
CostTerms lane_costs(const LocalizationProblem& prob, const NodeLanes& nl, const double* x) {
  Terms<M> t;
  for (std::int64_t c = 0; c < nl.size(); ++c) add_chunk_terms<P>(prob, nl, c, x, t);
  allreduce_exact(t.t, 4, prob.comm());
  return {t.t[0].value(), t.t[1].value(), t.t[2].value(), t.t[3].value()};
}

}  // namespace

bool lane_costs_apply(const LocalizationProblem& prob) {
  return !prob.model().active() && prob.dim() >= 2 && prob.derived_cache() != nullptr;
}

CostTerms exact_costs(const LocalizationProblem& prob, const double* x, unsigned sums) {
  if (!lane_costs_apply(prob)) {
    return sums == kMlSum        ? CostTerms{evaluate_ml_cost(prob, x), 0, 0, 0}
           : sums == kRelaxedSum ? CostTerms{0, evaluate_relaxed_cost(prob, x), 0, 0}
                                 : evaluate_costs(prob, x);
  }
  const NodeLanes& nl = *shared_lanes(prob);
  return with_dim(prob.dim(), [&](auto P) {
    constexpr int p = decltype(P)::value;
    return sums == kMlSum        ? lane_costs<p, kMlSum>(prob, nl, x)
           : sums == kRelaxedSum ? lane_costs<p, kRelaxedSum>(prob, nl, x)
                                 : lane_costs<p, kAllSums>(prob, nl, x);
  });
}

double exact_ml_cost_and_gradient(const LocalizationProblem& prob, const double* x, double* g, bool relaxed) {
  if (!lane_costs_apply(prob)) return ml_cost_and_gradient(prob, x, g, relaxed);
  const NodeLanes& nl = *shared_lanes(prob);
  double norms[3 * kMaxLanes] = {};
  // x(k) and w(k+1) go to g too, and are overwritten by the gradient.
  RelaxStep st{x, x, g, g, 1.0, 0.0, norms};
  st.ml = !relaxed;
  st.g = g;
  Terms<kMlSum> t;
  constexpr std::int64_t kBlock = 16;  // chunks: the terms read their rows from cache
  for (std::int64_t c0 = 0; c0 < nl.size(); c0 += kBlock) {
    const std::int64_t c1 = std::min(nl.size(), c0 + kBlock);
    relax_chunks(prob, nl, c0, c1, st);
    with_dim(prob.dim(), [&](auto P) {
      for (std::int64_t c = c0; c < c1; ++c) add_chunk_terms<decltype(P)::value>(prob, nl, c, x, t);
    });
  }
  allreduce_exact(t.t, 1, prob.comm());
  return t.t[0].value();
}

}  // namespace snl::detail
