// The scalar twins of the node-lane steps, one node at a time: the portable
// path (no AVX2, SNL_SIMD=0), the path for partial chunks, and the reference
// the SIMD kernels are tested against bit for bit.
#include <cmath>

#include "kernels/simd_common.hpp"
#include "kernels/terms.hpp"

namespace snl::detail {

namespace {

// The node-lane relaxation step, one node at a time: the reference for the
// SIMD versions (and the path for p = 3, for partial chunks and CPUs without
// AVX2). Padding slots are skipped: the SIMD lanes add +0.0 there, which
// changes no sum (a sum that starts at +0.0 is never -0.0).
template <int P>
void relax_chunk_scalar(const LocalizationProblem& prob, const NodeLanes& nl, std::int64_t c, const RelaxStep& s) {
  const int C = nl.lanes;
  const std::int64_t g0 = nl.group_off[c], g1 = nl.group_off[c + 1];
  const std::int64_t* aoff = prob.anchor_offsets().data();
  for (int q = 0; q < nl.count[c]; ++q) {
    const LocalId v = nl.first[c] + q;
    const std::size_t i0 = std::size_t(v) * P;
    const int L = NodeLanes::lane_of_node(q, C);
    double acc[P] = {}, t[P];
    for (std::int64_t g = g0; g < g1; ++g) {
      if (!((nl.real[g] >> L) & 1)) continue;
      disk_term<P>(s.w + i0, s.w + std::size_t(nl.adj[g * C + q]) * P, nl.rho[g * C + L], t, s.ml);
      for (int k = 0; k < P; ++k) acc[k] += t[k];
    }
    if (aoff[v] != aoff[v + 1]) add_anchor_disk_terms(prob, v, s.w + i0, acc, s.ml);
    double rt = 0;  // ml-agd's restart term (RelaxStep::restart)
    for (int k = 0; k < P; ++k) {
      const double now = s.w[i0 + k] - (s.inv_d ? acc[k] * s.inv_d[v] : acc[k] / s.L), d = now - s.x[i0 + k];
      rt += (s.w[i0 + k] - now) * d;
      s.xn[i0 + k] = now;
      s.wn[i0 + k] = now + s.beta * d;
      if (s.g) s.g[i0 + k] = acc[k];
      s.norms[q] += d * d;
      s.norms[C + q] += now * now;
      s.norms[2 * C + q] += acc[k] * acc[k];
    }
    if (s.restart && s.inv_d && s.inv_d[v] > 0) {
      const double r = rt / s.inv_d[v];
      s.restart[L] += r;
      s.restart[C + L] += std::fabs(r);
    }
  }
}

// The node-lane MM step, one node at a time (reference twin of the SIMD
// versions; the path for p = 3 and partial chunks). Padding slots are
// skipped, which is what the SIMD lanes' masked adds amount to.
template <int P>
void mm_chunk_scalar(const LocalizationProblem& prob, const NodeLanes& nl, std::int64_t c, const MMStep& s) {
  const int C = nl.lanes;
  const std::int64_t g0 = nl.group_off[c], g1 = nl.group_off[c + 1];
  const std::int64_t* aoff = prob.anchor_offsets().data();
  for (int q = 0; q < nl.count[c]; ++q) {
    const LocalId v = nl.first[c] + q;
    // The step's input rows: x, or mm-accel's extrapolation x + beta (x - xb).
    auto row = [&](LocalId u, double* buf) -> const double* {
      const double* r = s.x + std::size_t(u) * P;
      if (!s.xb) return r;
      for (int k = 0; k < P; ++k) buf[k] = r[k] + s.beta * (r[k] - s.xb[std::size_t(u) * P + k]);
      return buf;
    };
    double xe[P], ue[P];
    const double* xv = row(v, xe);
    const int L = NodeLanes::lane_of_node(q, C);
    double acc[P] = {}, t[P], y[P];
    for (std::int64_t g = g0; g < g1; ++g) {
      if (!((nl.real[g] >> L) & 1)) continue;
      const std::size_t yi = std::size_t(g * P) * C + L;
      double* yg = s.y + yi;
      if (s.ya)  // mm-accel's extrapolated point, as its blend pass would form it
        for (int k = 0; k < P; ++k) y[k] = s.ya[yi + k * C] + s.beta * (s.ya[yi + k * C] - s.yb[yi + k * C]);
      else
        for (int k = 0; k < P; ++k) y[k] = yg[k * C];
      mm_term<P>(xv, row(nl.adj[g * C + q], ue), (nl.fwd[g] >> L) & 1, nl.rho[g * C + L], s.keep,
                 s.invL, y, t);
      for (int k = 0; k < P; ++k) {
        yg[k * C] = y[k];
        acc[k] += t[k];
      }
    }
    if (aoff[v] != aoff[v + 1]) add_anchor_mm_terms<P>(prob, v, xv, s.keep, s.invL, s.aw, acc);
    double* xo = s.xn + std::size_t(v) * P;
    for (int k = 0; k < P; ++k) {
      xo[k] = xv[k] - s.invL * acc[k];
      const double d = xo[k] - xv[k];
      s.norms[q] += d * d;
      s.norms[C + q] += xo[k] * xo[k];
    }
  }
}

// The chunk loops of the function table: the loop and the per-chunk step in
// one translation unit, so that the step is inlined as before the split.
template <int P>
void relax_chunks_scalar(const LocalizationProblem& prob, const NodeLanes& nl, std::int64_t c0, std::int64_t c1,
                         const RelaxStep& s) {
  for (std::int64_t c = c0; c < c1; ++c) relax_chunk_scalar<P>(prob, nl, c, s);
}

template <int P>
void mm_chunks_scalar(const LocalizationProblem& prob, const NodeLanes& nl, std::int64_t c0, std::int64_t c1,
                      const MMStep& s) {
  for (std::int64_t c = c0; c < c1; ++c) mm_chunk_scalar<P>(prob, nl, c, s);
}

}  // namespace

const KernelTable kScalarKernels = {{relax_chunks_scalar<2>, relax_chunks_scalar<3>},
                                    {mm_chunks_scalar<2>, mm_chunks_scalar<3>},
                                    {mm_chunks_scalar<2>, mm_chunks_scalar<3>}};
const RelaxChunksFn kScalarRelax1 = relax_chunks_scalar<1>;
const MMChunksFn kScalarMM1 = mm_chunks_scalar<1>;

void add_anchor_disk_terms(const LocalizationProblem& prob, LocalId v, const double* xv, double* acc, bool ml) {
  const int p = prob.dim();
  const auto& aoff = prob.anchor_offsets();
  const auto& aid = prob.anchor_ids();
  const auto& ar = prob.anchor_ranges();
  const double* anc = prob.anchors().data();
  double t[3];
  for (auto e = aoff[v]; e < aoff[v + 1]; ++e) {
    const double* a = anc + std::size_t(aid[e]) * p;
    if (p == 2)
      disk_term<2>(xv, a, ar[e], t, ml);
    else if (p == 3)
      disk_term<3>(xv, a, ar[e], t, ml);
    else
      disk_term<1>(xv, a, ar[e], t, ml);
    for (int c = 0; c < p; ++c) acc[c] += t[c];
  }
}

namespace {

template <int P>
unsigned mm_cost_chunk_p(const NodeLanes& nl, std::int64_t c, const double* x, const double* y, double* F,
                         double* f) {
  const int C = nl.lanes;
  unsigned any = 0;
  for (std::int64_t g = nl.group_off[c]; g < nl.group_off[c + 1]; ++g) {
    const unsigned mask = nl.real[g] & nl.fwd[g];
    for (int L = 0; L < C; ++L) {
      if (!((mask >> L) & 1)) continue;
      const int q = NodeLanes::lane_node(L, C);
      const double* xv = x + std::size_t(nl.first[c] + q) * P;
      const double* xu = x + std::size_t(nl.adj[g * C + q]) * P;
      double s = 0, z2 = 0;
      for (int k = 0; k < P; ++k) {
        const double z = xv[k] - xu[k];
        if (y) {
          const double r = z - y[std::size_t(g * P + k) * C + L];
          s += r * r;
        }
        z2 += z * z;
      }
      const double m = std::sqrt(z2) - nl.rho[g * C + L];
      F[L] += s;
      f[L] += m * m;
    }
    any |= mask;
  }
  return any;
}

}  // namespace

unsigned mm_cost_chunk_scalar(const NodeLanes& nl, int p, std::int64_t c, const double* x, const double* y,
                              double* F, double* f) {
  switch (p) {
    case 1: return mm_cost_chunk_p<1>(nl, c, x, y, F, f);
    case 2: return mm_cost_chunk_p<2>(nl, c, x, y, F, f);
    default: return mm_cost_chunk_p<3>(nl, c, x, y, F, f);
  }
}

}  // namespace snl::detail
