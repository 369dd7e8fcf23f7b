#include "snl/problem/metrics.hpp"

#include <mpi.h>

#include <algorithm>
#include <cstdint>
#include <cstring>

#include "core/dim_dispatch.hpp"
#include "core/exact_sum.hpp"

namespace snl {

namespace {

template <int P>
inline double norm(const double* z) {
  double s = 0;
  for (int c = 0; c < P; ++c) s += z[c] * z[c];
  return std::sqrt(s);
}

// e(z, rho) accumulated into g: z - P_B(rho)(z) = max(0, 1 - rho/|z|) z.
// Branch-free: whether |z| > rho is data dependent (about half the edges near
// a solution), and the mispredictions dominated the kernel. Adding +0.0 where
// the condition fails leaves g bit-identical to the branching form (g starts
// at +0.0 and a sum of doubles is -0.0 only if both terms are), and a
// non-finite z outside the disk still contributes nothing.
template <int P>
inline void add_disk_residual(const double* z, double rho, double* g) {
  const double nz = norm<P>(z);
  const std::uint64_t mask = nz > rho ? ~std::uint64_t(0) : 0;  // becomes a compare mask, not a branch
  const double c = 1.0 - rho / nz;
  for (int k = 0; k < P; ++k) {
    double t = c * z[k];
    std::uint64_t bits;
    std::memcpy(&bits, &t, sizeof bits);
    bits &= mask;
    std::memcpy(&t, &bits, sizeof t);
    g[k] += t;
  }
}

template <int P>
inline void add_ml_residual(const double* z, double rho, double* g) {
  const double nz = norm<P>(z);
  if (nz > 0) {
    const double c = 1.0 - rho / nz;
    for (int k = 0; k < P; ++k) g[k] += c * z[k];
  }
}

// The weighted / Huber term w_e rho'(r)/r e(z) of either gradient (weights.hpp):
// r = |z| - rho for the ML term, the distance to the disk for the relaxed one.
template <int P, bool kRelaxed>
inline void add_model_residual(const double* z, double rho, double w, double delta, double* g) {
  const double nz = norm<P>(z);
  if (!(nz > 0) || (kRelaxed && !(nz > rho))) return;
  const double c = w * huber_factor(delta, std::abs(nz - rho)) * (1.0 - rho / nz);
  for (int k = 0; k < P; ++k) g[k] += c * z[k];
}

template <int P, bool kRelaxed>
void model_gradient_impl(const LocalizationProblem& prob, const double* x, double* g, LocalId begin, LocalId end) {
  const auto& gr = prob.graph();
  const auto& off = gr.offsets();
  const auto& adj = gr.adjacency();
  const auto& ev = gr.edge_values();
  const auto& aoff = prob.anchor_offsets();
  const auto& aid = prob.anchor_ids();
  const auto& ar = prob.anchor_ranges();
  const double* anc = prob.anchors().data();
  const MeasurementModel& mo = prob.model();
  for (LocalId v = begin; v < end; ++v) {
    double acc[P] = {}, z[P];
    const double* xv = x + std::size_t(v) * P;
    for (auto e = off[v]; e < off[v + 1]; ++e) {
      for (int c = 0; c < P; ++c) z[c] = xv[c] - x[std::size_t(adj[e]) * P + c];
      add_model_residual<P, kRelaxed>(z, ev[e], mo.edge_weight(e), mo.huber_delta, acc);
    }
    for (auto e = aoff[v]; e < aoff[v + 1]; ++e) {
      for (int c = 0; c < P; ++c) z[c] = xv[c] - anc[std::size_t(aid[e]) * P + c];
      add_model_residual<P, kRelaxed>(z, ar[e], mo.anchor_weight(e), mo.huber_delta, acc);
    }
    for (int c = 0; c < P; ++c) g[std::size_t(v) * P + c] = acc[c];
  }
}

// Either gradient over [begin, end) and, with `ml`, this rank's terms of f(x)
// in the same pass (costs_impl's terms: each edge at its smaller global id).
template <int P, bool kRelaxed>
void gradient_impl(const LocalizationProblem& prob, const double* x, double* g, LocalId begin, LocalId end,
                   detail::ExactSum* ml = nullptr) {
  if (prob.model().active()) return model_gradient_impl<P, kRelaxed>(prob, x, g, begin, end);
  const auto& gr = prob.graph();
  const auto& off = gr.offsets();
  const auto& adj = gr.adjacency();
  const auto& ev = gr.edge_values();
  const auto& aoff = prob.anchor_offsets();
  const auto& aid = prob.anchor_ids();
  const auto& ar = prob.anchor_ranges();
  const double* anc = prob.anchors().data();
  auto ml_term = [](const double* z, double rho) {
    const double nz = norm<P>(z);
    return 0.5 * (nz - rho) * (nz - rho);
  };
  for (LocalId v = begin; v < end; ++v) {
    double acc[P] = {};
    const double* xv = x + std::size_t(v) * P;
    const GlobalId gv = ml ? gr.global_id(v) : 0;
    for (auto e = off[v]; e < off[v + 1]; ++e) {
      const double* xu = x + std::size_t(adj[e]) * P;
      double z[P];
      for (int c = 0; c < P; ++c) z[c] = xv[c] - xu[c];
      if (ml && gr.global_id(adj[e]) > gv) ml->add(ml_term(z, ev[e]));
      if (kRelaxed)
        add_disk_residual<P>(z, ev[e], acc);
      else
        add_ml_residual<P>(z, ev[e], acc);
    }
    for (auto e = aoff[v]; e < aoff[v + 1]; ++e) {
      const double* a = anc + std::size_t(aid[e]) * P;
      double z[P];
      for (int c = 0; c < P; ++c) z[c] = xv[c] - a[c];
      if (ml) ml->add(ml_term(z, ar[e]));
      if (kRelaxed)
        add_disk_residual<P>(z, ar[e], acc);
      else
        add_ml_residual<P>(z, ar[e], acc);
    }
    for (int c = 0; c < P; ++c) g[std::size_t(v) * P + c] = acc[c];
  }
}

// Which sums costs_impl forms: the solver's tests and records need one of them,
// and each exact add costs about as much as the edge's arithmetic.
enum CostMask : unsigned { kMl = 1, kRelaxed = 2, kCertificate = 4, kApriori = 8, kAllCosts = 15 };

template <int P, unsigned M>
CostTerms costs_impl(const LocalizationProblem& prob, const double* x) {
  const auto& gr = prob.graph();
  const auto& off = gr.offsets();
  const auto& adj = gr.adjacency();
  const auto& ev = gr.edge_values();
  const auto& aoff = prob.anchor_offsets();
  const auto& aid = prob.anchor_ids();
  const auto& ar = prob.anchor_ranges();
  const double* anc = prob.anchors().data();
  // Exact sums of the per-edge terms: the same costs for any partition. Being
  // exact, each sum is the same whichever others are formed beside it.
  detail::ExactSum t[4];  // ml, relaxed, certificate, apriori
  const MeasurementModel& mo = prob.model();
  // Weighted / Huber terms w rho(r) (weights.hpp); with the unweighted l2
  // model the expressions below, as they always were.
  auto term = [&](const double* z, double rho, double w) {
    const double nz = norm<P>(z);
    if (M & (kMl | kCertificate) || ((M & kRelaxed) && nz > rho)) {
      const double ml = mo.active() ? w * loss_value(mo.huber_delta, std::abs(nz - rho)) : 0.5 * (nz - rho) * (nz - rho);
      if (M & kMl) t[0].add(ml);
      if (nz > rho) {
        if (M & kRelaxed) t[1].add(ml);  // d_B(rho)(z)^2 / 2 = (|z| - rho)^2 / 2 outside the ball
      } else if (M & kCertificate) {
        t[2].add(ml);  // relaxed term is zero: eq. (22) collects the nonconvex one
      }
    }
    if (M & kApriori) t[3].add(mo.active() ? w * loss_value(mo.huber_delta, rho) : 0.5 * rho * rho);
  };
  for (LocalId v = 0; v < gr.num_owned(); ++v) {
    const double* xv = x + std::size_t(v) * P;
    const GlobalId gv = gr.global_id(v);
    for (auto e = off[v]; e < off[v + 1]; ++e) {
      if (gr.global_id(adj[e]) < gv) continue;  // counted by the smaller end
      const double* xu = x + std::size_t(adj[e]) * P;
      double z[P];
      for (int c = 0; c < P; ++c) z[c] = xv[c] - xu[c];
      term(z, ev[e], mo.edge_weight(e));
    }
    for (auto e = aoff[v]; e < aoff[v + 1]; ++e) {
      const double* a = anc + std::size_t(aid[e]) * P;
      double z[P];
      for (int c = 0; c < P; ++c) z[c] = xv[c] - a[c];
      term(z, ar[e], mo.anchor_weight(e));
    }
  }
  // Reduce only the sums formed (one collective, fewer words).
  detail::ExactSum formed[4];
  int n = 0;
  for (int j = 0; j < 4; ++j)
    if (M & (1u << j)) formed[n++] = t[j];
  detail::allreduce_exact(formed, n, prob.comm());
  double out[4] = {0, 0, 0, 0};
  n = 0;
  for (int j = 0; j < 4; ++j)
    if (M & (1u << j)) out[j] = formed[n++].value();
  return {out[0], out[1], out[2], out[3]};
}

template <unsigned M>
CostTerms costs_of(const LocalizationProblem& prob, const double* x) {
  return detail::with_dim(prob.dim(), [&](auto P) { return costs_impl<decltype(P)::value, M>(prob, x); });
}

}  // namespace

CostTerms evaluate_costs(const LocalizationProblem& prob, const double* x) { return costs_of<kAllCosts>(prob, x); }

double evaluate_ml_cost(const LocalizationProblem& prob, const double* x) { return costs_of<kMl>(prob, x).ml; }

double evaluate_relaxed_cost(const LocalizationProblem& prob, const double* x) {
  return costs_of<kRelaxed>(prob, x).relaxed;
}

void relaxed_gradient(const LocalizationProblem& prob, const double* x, double* g, LocalId begin, LocalId end) {
  detail::with_dim(prob.dim(), [&](auto P) { gradient_impl<decltype(P)::value, true>(prob, x, g, begin, end); });
}

void ml_gradient(const LocalizationProblem& prob, const double* x, double* g, LocalId begin, LocalId end) {
  detail::with_dim(prob.dim(), [&](auto P) { gradient_impl<decltype(P)::value, false>(prob, x, g, begin, end); });
}

double ml_cost_and_gradient(const LocalizationProblem& prob, const double* x, double* g, bool relaxed) {
  const LocalId n = prob.num_owned();
  if (prob.model().active()) {  // the weighted / Huber terms: two passes
    const double f = evaluate_ml_cost(prob, x);
    relaxed ? relaxed_gradient(prob, x, g, 0, n) : ml_gradient(prob, x, g, 0, n);
    return f;
  }
  detail::ExactSum f;
  detail::with_dim(prob.dim(), [&](auto P) {
    constexpr int p = decltype(P)::value;
    relaxed ? gradient_impl<p, true>(prob, x, g, 0, n, &f) : gradient_impl<p, false>(prob, x, g, 0, n, &f);
  });
  detail::allreduce_exact(&f, 1, prob.comm());
  return f.value();
}

double relaxation_lipschitz(const LocalizationProblem& prob) {
  // Weighted (weights.hpp): Gershgorin on the weighted Laplacian plus the
  // anchor diagonal, 2 max_i sum_j w_ij + max_i sum_k w_ik; Huber leaves it
  // (rho(dist_B) has a 1-Lipschitz gradient, docs/quality.md).
  if (prob.model().weighted) return 2.0 * prob.model().max_weight_sum + prob.model().max_anchor_weight_sum;
  return 2.0 * prob.max_degree() + prob.max_anchor_degree();
}

double owned_norm_sq(const LocalizationProblem& prob, const double* v) {
  double s = 0;
  const std::size_t m = std::size_t(prob.num_owned()) * prob.dim();
  for (std::size_t t = 0; t < m; ++t) s += v[t] * v[t];
  return s;
}

ErrorMetrics evaluate_errors(const LocalizationProblem& prob, const double* x) {
  ErrorMetrics m;
  int has = prob.has_truth() ? 1 : 0, all = 0;
  MPI_Allreduce(&has, &all, 1, MPI_INT, MPI_MIN, prob.comm());
  if (!all) return m;
  const int p = prob.dim();
  const auto& tr = prob.truth();
  const auto& fl = prob.flags();
  // Exact sums of the per-node terms: the same metrics for any partition.
  detail::ExactSum sums[5];  // sq, abs, sq_loc, abs_loc, count_loc
  for (LocalId v = 0; v < prob.num_owned(); ++v) {
    double s = 0;
    for (int c = 0; c < p; ++c) {
      const double d = x[std::size_t(v) * p + c] - tr[std::size_t(v) * p + c];
      s += d * d;
    }
    sums[0].add(s);
    sums[1].add(std::sqrt(s));
    if (!fl[v]) {
      sums[2].add(s);
      sums[3].add(std::sqrt(s));
      sums[4].add(1);
    }
  }
  detail::allreduce_exact(sums, 5, prob.comm());
  double glob[5];
  for (int j = 0; j < 5; ++j) glob[j] = sums[j].value();
  const double n = static_cast<double>(prob.num_sensors());
  m.valid = true;
  m.rmse = std::sqrt(glob[0] / n);
  m.mpe = glob[1] / n;
  m.localizable = static_cast<GlobalId>(glob[4]);
  if (glob[4] > 0) {
    m.rmse_localizable = std::sqrt(glob[2] / glob[4]);
    m.mpe_localizable = glob[3] / glob[4];
  }
  return m;
}

}  // namespace snl
