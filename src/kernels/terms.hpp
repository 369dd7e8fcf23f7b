#pragma once
// Scalar per-edge terms of the node kernels (internal to src/kernels/): the
// arithmetic every path shares. The scalar twins (scalar.cpp) are built from
// them, and the SIMD kernels (avx2.cpp, avx512.cpp) use the anchor terms as
// they are (a node has few anchors) and repeat the edge terms lane by lane.
#include <cstdint>
#include <cstring>

#include "kernels/kernels.hpp"

namespace snl::detail {

// Internal linkage: each kernel file gets its own copy, whose register use
// GCC then knows at the SIMD kernels' calls (IPA-RA; a shared, interposable
// copy made the MM kernels spill around the anchor call).
namespace {

// Branch-free disk residual: the mask zeroes the term where |z| <= rho (or z is
// not finite), which leaves the node's sum bit-identical to the branching form
// (the sum starts at +0.0 and adding +0.0 changes nothing but the sign of an
// all-zero sum, which cannot be -0.0 here). See docs/performance.md. With
// `ml` the mask is |z| > 0 instead: (1 - rho/|z|) z is then the ML cost's
// edge gradient (z = 0: the zero subgradient).
template <int P>
inline void disk_term(const double* xv, const double* xu, double rho, double* t, bool ml = false) {
  double z[P];
  for (int c = 0; c < P; ++c) z[c] = xv[c] - xu[c];
  double s = 0;
  for (int c = 0; c < P; ++c) s += z[c] * z[c];
  const double nz = std::sqrt(s);
  const std::uint64_t mask = nz > (ml ? 0.0 : rho) ? ~std::uint64_t(0) : 0;
  const double cf = 1.0 - rho / nz;
  for (int c = 0; c < P; ++c) {
    const double a = cf * z[c];
    std::uint64_t bits;
    std::memcpy(&bits, &a, 8);
    bits &= mask;
    std::memcpy(&t[c], &bits, 8);
  }
}

template <int P>
inline void mm_term(const double* xv, const double* xu, bool fwd, double rho, double keep, double invL, double* y,
                    double* t) {
  const double* xi = fwd ? xv : xu;
  const double* xj = fwd ? xu : xv;
  const double sgn = fwd ? 1.0 : -1.0;
  double dz[P], yn[P];
  for (int c = 0; c < P; ++c) dz[c] = xi[c] - xj[c];
  for (int c = 0; c < P; ++c) t[c] = sgn * (dz[c] - y[c]);
  for (int c = 0; c < P; ++c) yn[c] = keep * y[c] + invL * dz[c];
  project_sphere<P>(rho, yn);
  for (int c = 0; c < P; ++c) y[c] = yn[c];
}

// MM anchor terms of owned node v (000, eqs. 11 and 13): acc += dz - w_k,
// w_k <- P_sphere(keep w_k + invL dz) with dz = x_v - a_k, in anchor-id order.
// Out of line, as when one file held every kernel (it had three callers
// there): the anchor path is rare, and inlined it would grow the MM kernels.
template <int P>
__attribute__((noinline)) void add_anchor_mm_terms(const LocalizationProblem& prob, LocalId v, const double* xv, double keep, double invL,
                         double* aw, double* acc) {
  const auto& aoff = prob.anchor_offsets();
  const auto& aid = prob.anchor_ids();
  const auto& ar = prob.anchor_ranges();
  const double* anc = prob.anchors().data();
  for (auto e = aoff[v]; e < aoff[v + 1]; ++e) {
    const double* a = anc + std::size_t(aid[e]) * P;
    double* w = aw + std::size_t(e) * P;
    double dz[P];
    for (int c = 0; c < P; ++c) dz[c] = xv[c] - a[c];
    for (int c = 0; c < P; ++c) acc[c] += dz[c] - w[c];
    for (int c = 0; c < P; ++c) w[c] = keep * w[c] + invL * dz[c];
    project_sphere<P>(ar[e], w);
  }
}

// add_anchor_disk_terms for every node of chunk c with anchor ranges, its
// pairs read in sequence (NodeLanes::anchor_off): acc and x hold the chunk's
// rows (P per node offset); per node its anchors in CSR order, the same
// arithmetic, so the same bits.
template <int P>
__attribute__((noinline)) void add_chunk_anchor_disk_terms(const LocalizationProblem& prob, const NodeLanes& nl,
                                                           std::int64_t c, const double* x, double* acc, bool ml) {
  const auto* aid = prob.anchor_ids().data();
  const double* ar = prob.anchor_ranges().data();
  const double* anc = prob.anchors().data();
  double t[P];
  for (auto e = nl.anchor_off[c]; e < nl.anchor_off[c + 1]; ++e) {
    const int q = nl.anchor_q[e];
    disk_term<P>(x + P * q, anc + std::size_t(aid[e]) * P, ar[e], t, ml);
    for (int k = 0; k < P; ++k) acc[P * q + k] += t[k];
  }
}

// add_anchor_mm_terms for every node of chunk c with anchor ranges, likewise.
template <int P>
__attribute__((noinline)) void add_chunk_anchor_mm_terms(const LocalizationProblem& prob, const NodeLanes& nl,
                                                         std::int64_t c, const double* x, double keep, double invL,
                                                         double* aw, double* acc) {
  const auto* aid = prob.anchor_ids().data();
  const double* ar = prob.anchor_ranges().data();
  const double* anc = prob.anchors().data();
  for (auto e = nl.anchor_off[c]; e < nl.anchor_off[c + 1]; ++e) {
    const int q = nl.anchor_q[e];
    const double* a = anc + std::size_t(aid[e]) * P;
    double* w = aw + std::size_t(e) * P;
    double dz[P];
    for (int k = 0; k < P; ++k) dz[k] = x[P * q + k] - a[k];
    for (int k = 0; k < P; ++k) acc[P * q + k] += dz[k] - w[k];
    for (int k = 0; k < P; ++k) w[k] = keep * w[k] + invL * dz[k];
    project_sphere<P>(ar[e], w);
  }
}

}  // namespace

}  // namespace snl::detail
