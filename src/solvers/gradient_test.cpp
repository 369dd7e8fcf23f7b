#include "solvers/gradient_test.hpp"

#include <cmath>

#include "core/dim_dispatch.hpp"
#include "core/exact_sum.hpp"

namespace snl::detail {

namespace {

// This rank's anchor terms of 2 f(x), (|x_v - a_k| - r_vk)^2, in plain doubles.
template <int P>
double anchor_terms(const LocalizationProblem& prob, const double* x) {
  const auto& aoff = prob.anchor_offsets();
  const auto& aid = prob.anchor_ids();
  const auto& ar = prob.anchor_ranges();
  const double* anc = prob.anchors().data();
  double s = 0;
  for (LocalId v = 0; v < prob.num_owned(); ++v)
    for (auto e = aoff[v]; e < aoff[v + 1]; ++e) {
      double z2 = 0;
      for (int c = 0; c < P; ++c) {
        const double z = x[std::size_t(v) * P + c] - anc[std::size_t(aid[e]) * P + c];
        z2 += z * z;
      }
      const double m = std::sqrt(z2) - ar[e];
      s += m * m;
    }
  return s;
}

// A plain sum of N terms >= 0, each within u of its exact value (or a
// subnormal within 2^-1074 of it), in any order, is within gamma_N of the
// exact sum (Higham 2002, sec. 4.2), below 2 (N + 2) u of it; twice that,
// plus N 2^-1070 for the subnormal terms, leaves room for the rounding of
// the bound itself and of the ranks' exact total.
double rounding_bound(double sum, double terms) {
  return 4.0 * (terms + 8.0) * 0x1p-53 * sum + (terms + 8.0) * 0x1p-1070;
}

}  // namespace

GradientBounds bound_relative_gradient(const LocalizationProblem& prob, const NodeLanes& nl, const double* x,
                                       bool relaxed, double* scratch) {
  const int C = nl.lanes, p = prob.dim();
  // ||grad c||^2: the kernel's per-node gradient g (slots in global-id order,
  // then anchors: the scalar gradient's bits), its squares summed per lane.
  // The exact test sums fl(sum_c g_c^2) per node exactly; both sums are
  // within (N + p) u of sum g_c^2 in exact arithmetic, N = p n_owned.
  double norms[3 * kMaxLanes] = {};
  RelaxStep st{x, x, scratch, scratch, 1.0, 0.0, norms};
  st.ml = !relaxed;
  relax_chunks(prob, nl, 0, nl.size(), st);
  double G = 0;
  for (int L = 0; L < C; ++L) G += norms[2 * C + L];
  // f: each term (|x_v - x_u| - rho)^2 with the same bits as the exact sum's
  // (0.5 (|z| - rho)^2 is half of it exactly), each sensor pair at its
  // forward slot, so once over all ranks; then the anchor pairs.
  double Fl[kMaxLanes] = {}, fl[kMaxLanes] = {};
  for (std::int64_t c = 0; c < nl.size(); ++c) mm_cost_chunk(nl, p, c, x, nullptr, Fl, fl);
  double f = 0;
  for (int L = 0; L < C; ++L) f += fl[L];
  f += with_dim(p, [&](auto P) { return anchor_terms<decltype(P)::value>(prob, x); });
  f *= 0.5;
  const double nG = double(p) * double(prob.num_owned()) + C + p;
  const double nf = double(prob.graph().adjacency().size() + prob.anchor_ranges().size()) + C;
  ExactSum sums[4];
  sums[0].add(G);
  sums[1].add(rounding_bound(G, nG));
  sums[2].add(f);
  sums[3].add(rounding_bound(f, nf));
  allreduce_exact(sums, 4, prob.comm());
  const double Gs = sums[0].value(), eG = sums[1].value(), fs = sums[2].value(), ef = sums[3].value();
  // 1e-12: the roundings of the totals, of the exact test's sqrt and
  // division, and of this interval's own arithmetic, with a wide margin.
  constexpr double kSlack = 1e-12;
  const double Glo = std::max(0.0, Gs - eG) * (1 - kSlack), Ghi = (Gs + eG) * (1 + kSlack);
  const double flo = (fs - ef) * (1 - kSlack), fhi = (fs + ef) * (1 + kSlack);
  GradientBounds b;
  if (!(flo > 0) || !std::isfinite(Ghi) || !std::isfinite(fhi)) return b;
  b.lo = std::sqrt(Glo) / (2.0 * std::sqrt(fhi)) * (1 - kSlack);
  b.hi = std::sqrt(Ghi) / (2.0 * std::sqrt(flo)) * (1 + kSlack);
  b.valid = std::isfinite(b.hi);
  return b;
}

}  // namespace snl::detail
