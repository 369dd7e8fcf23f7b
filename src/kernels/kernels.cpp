#include "kernels/kernels.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <type_traits>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define SNL_HAVE_AVX2_PATH 1
#include <immintrin.h>
#endif

namespace snl::detail {

namespace {

// SIMD levels: 0 scalar, 1 AVX2 (4 lanes), 2 AVX-512F/DQ (8 lanes).
int cpu_level() {
#ifdef SNL_HAVE_AVX2_PATH
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq")) return 2;
  if (__builtin_cpu_supports("avx2")) return 1;
#endif
  return 0;
}

// SNL_SIMD=0 (or scalar) selects the scalar kernels, SNL_SIMD=avx2 the AVX2
// ones even where AVX-512 is there (for comparisons); unset: the best.
const char* simd_env() {
  const char* env = std::getenv("SNL_SIMD");
  return env ? env : "";
}
const int g_cpu = cpu_level();
const int g_lanes = (g_cpu == 2 && std::strcmp(simd_env(), "avx2") != 0) ? 8 : 4;
static_assert(kMaxLanes == 8, "per-lane scratch sized for AVX-512");
// The best level the lane width allows (8 lanes: AVX-512, 4 lanes: AVX2).
const int g_top = std::min(g_cpu, g_lanes == 8 ? 2 : 1);
int g_level = (std::strcmp(simd_env(), "0") == 0 || std::strcmp(simd_env(), "scalar") == 0) ? 0 : g_top;

// ---- scalar terms (the portable path and the reference for the SIMD one) ----

// Branch-free disk residual: the mask zeroes the term where |z| <= rho (or z is
// not finite), which leaves the node's sum bit-identical to the branching form
// (the sum starts at +0.0 and adding +0.0 changes nothing but the sign of an
// all-zero sum, which cannot be -0.0 here). See docs/performance.md.
template <int P>
inline void disk_term(const double* xv, const double* xu, double rho, double* t) {
  double z[P];
  for (int c = 0; c < P; ++c) z[c] = xv[c] - xu[c];
  double s = 0;
  for (int c = 0; c < P; ++c) s += z[c] * z[c];
  const double nz = std::sqrt(s);
  const std::uint64_t mask = nz > rho ? ~std::uint64_t(0) : 0;
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
      disk_term<P>(s.w + i0, s.w + std::size_t(nl.adj[g * C + q]) * P, nl.rho[g * C + L], t);
      for (int k = 0; k < P; ++k) acc[k] += t[k];
    }
    if (aoff[v] != aoff[v + 1]) add_anchor_disk_terms(prob, v, s.w + i0, acc);
    for (int k = 0; k < P; ++k) {
      const double now = s.w[i0 + k] - acc[k] / s.L, d = now - s.x[i0 + k];
      s.xn[i0 + k] = now;
      s.wn[i0 + k] = now + s.beta * d;
      s.norms[q] += d * d;
      s.norms[C + q] += now * now;
      s.norms[2 * C + q] += acc[k] * acc[k];
    }
  }
}

// MM anchor terms of owned node v (000, eqs. 11 and 13): acc += dz - w_k,
// w_k <- P_sphere(keep w_k + invL dz) with dz = x_v - a_k, in anchor-id order.
template <int P>
void add_anchor_mm_terms(const LocalizationProblem& prob, LocalId v, const double* xv, double keep, double invL,
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
    const double* xv = s.x + std::size_t(v) * P;
    const int L = NodeLanes::lane_of_node(q, C);
    double acc[P] = {}, t[P], y[P];
    for (std::int64_t g = g0; g < g1; ++g) {
      if (!((nl.real[g] >> L) & 1)) continue;
      double* yg = s.y + std::size_t(g * P) * C + L;
      for (int k = 0; k < P; ++k) y[k] = yg[k * C];
      mm_term<P>(xv, s.x + std::size_t(nl.adj[g * C + q]) * P, (nl.fwd[g] >> L) & 1, nl.rho[g * C + L], s.keep,
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

#ifdef SNL_HAVE_AVX2_PATH
// Software prefetch of the lane arrays a fixed distance ahead (groups at
// kPrefetchBytes of ranges): the arrays are read in order, but the hardware
// prefetcher alone left these sqrt/div-heavy loops waiting on memory. At 1M
// sensors on one core (AVX-512): relaxation 5.9-6.1 -> 5.3-5.8 ms, MM 9.1-9.8
// -> 8.0-8.3 ms per iteration; 10M on 2 ranks 7-13% faster; no gain for the
// AVX2 kernels (docs/performance.md). The index is clamped to the last
// group so that no address past the arrays is formed. EdgeP > 0: also MM's
// edge rows y (EdgeP doubles per lane and group). Always inlined: GCC
// takes a function that only prefetches for one without side effects and
// drops calls to it that it did not inline (it did so in the MM kernels).
constexpr std::int64_t kPrefetchBytes = 2048;
template <int C, int EdgeP>
__attribute__((always_inline)) inline void prefetch_group(const NodeLanes& nl, std::int64_t g, std::int64_t last,
                                                          const double* y) {
  const std::int64_t ahead = std::min(g + kPrefetchBytes / (8 * C), last);
  _mm_prefetch(reinterpret_cast<const char*>(nl.rho.data() + C * ahead), _MM_HINT_T0);
  _mm_prefetch(reinterpret_cast<const char*>(nl.adj.data() + C * ahead), _MM_HINT_T0);
  for (int j = 0; j < EdgeP * C; j += 8)  // one 64-byte line at a time
    _mm_prefetch(reinterpret_cast<const char*>(y + EdgeP * C * ahead + j), _MM_HINT_T0);
}

// 3D only: the neighbour rows of the group kRowPrefetchGroups ahead. RCM
// keeps 2D neighbours close (the gathers hit L1/L2, and these prefetches made
// the 2D relaxation 15% slower), but a 3D BFS level of 1M sensors spans ~10^4
// rows, so the gathers wait on L3: 1M sensors, one core, relaxation 13.4-13.9
// -> 9.7-10.3 ms per iteration (16-64 groups ahead alike).
constexpr std::int64_t kRowPrefetchGroups = 16;
template <int C, int P>
__attribute__((always_inline)) inline void prefetch_rows(const NodeLanes& nl, std::int64_t g, std::int64_t last,
                                                         const double* x) {
  if constexpr (P == 3) {
    const LocalId* idx = nl.adj.data() + C * std::min(g + kRowPrefetchGroups, last);
    for (int q = 0; q < C; ++q) _mm_prefetch(reinterpret_cast<const char*>(x + std::size_t(idx[q]) * P), _MM_HINT_T0);
  }
}

// ---- AVX2: the node-lane steps with 4 nodes per register, for p = 2 and 3.
// Rows are loaded as (x, y) pairs (and z alone for p = 3); after the unpack
// the lanes hold nodes (0, 2, 1, 3) of the chunk (NodeLanes::lane_node), and
// per-slot scalars (rho, the lane bits) are stored in that order. Only IEEE
// add/sub/mul/div/sqrt and no FMA, so every lane equals the scalar twin bit
// for bit. The kernels return normally (GCC emits vzeroupper there): an
// earlier tail call from AVX2 code into scalar code got none, and the dirty
// upper ymm state slowed the caller's SSE code by ~40% (docs/performance.md).
#define SNL_AVX2 __attribute__((target("avx2")))

// Coordinate registers, stored lane by lane, back to the P-rows of the
// chunk's nodes 0..C-1 at t (the p = 3 row store of both widths).
template <int P, int C>
inline void rows_from_lanes(double* t, const double (&lanes)[P][C]) {
  for (int q = 0; q < C; ++q)
    for (int k = 0; k < P; ++k) t[P * q + k] = lanes[k][NodeLanes::lane_of_node(q, C)];
}

// Row offsets 0..7, for loading a chunk's own p = 3 rows with the neighbour loads.
constexpr LocalId kIota[8] = {0, 1, 2, 3, 4, 5, 6, 7};

// Rows idx[0..3] of x (p = P) as P registers in lane order (0, 2, 1, 3).
template <int P>
SNL_AVX2 inline void load_rows(const double* x, const LocalId* idx, __m256d* U) {
  auto row = [&](int q) { return _mm_loadu_pd(x + std::size_t(idx[q]) * P); };
  const __m256d a = _mm256_insertf128_pd(_mm256_castpd128_pd256(row(0)), row(1), 1);
  const __m256d b = _mm256_insertf128_pd(_mm256_castpd128_pd256(row(2)), row(3), 1);
  U[0] = _mm256_unpacklo_pd(a, b);  // (x0, x2, x1, x3)
  U[1] = _mm256_unpackhi_pd(a, b);
  if constexpr (P == 3) {
    auto z = [&](int q) { return _mm_load_sd(x + std::size_t(idx[q]) * 3 + 2); };
    const __m256d c = _mm256_insertf128_pd(_mm256_castpd128_pd256(z(0)), z(1), 1);
    const __m256d d = _mm256_insertf128_pd(_mm256_castpd128_pd256(z(2)), z(3), 1);
    U[2] = _mm256_unpacklo_pd(c, d);
  }
}

SNL_AVX2 inline __m256d load_scalars_0213(const double* r) {
  return _mm256_permute4x64_pd(_mm256_loadu_pd(r), _MM_SHUFFLE(3, 1, 2, 0));
}

// The rows of nodes v .. v+3 (contiguous, from r) in the lane order of load_rows.
template <int P>
SNL_AVX2 inline void load_own(const double* r, __m256d* U) {
  if constexpr (P == 2) {
    const __m256d a = _mm256_loadu_pd(r), b = _mm256_loadu_pd(r + 4);
    U[0] = _mm256_unpacklo_pd(a, b);
    U[1] = _mm256_unpackhi_pd(a, b);
  } else {
    load_rows<P>(r, kIota, U);
  }
}

// The inverse of load_own. p = 2 rows may go out with non-temporal stores
// (stream_rows: the lines are not read for ownership first; 16-byte rows in
// std::vector storage are 16-byte aligned, as _mm_stream_pd needs); p = 3
// rows (24 bytes, not always 16-byte aligned) are always stored plainly.
template <int P>
SNL_AVX2 inline void store_own(double* t, const __m256d* U, bool stream) {
  if constexpr (P == 2) {
    const __m256d lo = _mm256_unpacklo_pd(U[0], U[1]), hi = _mm256_unpackhi_pd(U[0], U[1]);
    if (stream) {
      _mm_stream_pd(t, _mm256_castpd256_pd128(lo));
      _mm_stream_pd(t + 2, _mm256_extractf128_pd(lo, 1));
      _mm_stream_pd(t + 4, _mm256_castpd256_pd128(hi));
      _mm_stream_pd(t + 6, _mm256_extractf128_pd(hi, 1));
    } else {
      _mm256_storeu_pd(t, lo);      // (x0, y0, x1, y1)
      _mm256_storeu_pd(t + 4, hi);  // (x2, y2, x3, y3)
    }
  } else {
    alignas(32) double lanes[P][4];
    for (int k = 0; k < P; ++k) _mm256_store_pd(lanes[k], U[k]);
    rows_from_lanes(t, lanes);
  }
}

// sum_k U[k]^2 in coordinate order (the scalar twins' order).
SNL_AVX2 inline __m256d square_sum(const __m256d* U, int P) {
  __m256d s = _mm256_mul_pd(U[0], U[0]);
  for (int k = 1; k < P; ++k) s = _mm256_add_pd(s, _mm256_mul_pd(U[k], U[k]));
  return s;
}

// Node-lane relaxation step, 4 nodes per register (full chunks only).
template <int P>
SNL_AVX2 void relax_chunks_avx2(const LocalizationProblem& prob, const NodeLanes& nl, std::int64_t c0,
                                std::int64_t c1, const RelaxStep& s) {
  const __m256d one = _mm256_set1_pd(1.0), vL = _mm256_set1_pd(s.L), vb = _mm256_set1_pd(s.beta);
  __m256d DD = load_scalars_0213(s.norms), SS = load_scalars_0213(s.norms + 4), GS = load_scalars_0213(s.norms + 8);
  const std::int64_t last = nl.groups() - 1;
  for (std::int64_t c = c0; c < c1; ++c) {
    const LocalId v0 = nl.first[c];
    const std::size_t i0 = std::size_t(v0) * P;
    __m256d W[P], A[P];
    load_own<P>(s.w + i0, W);
    for (int k = 0; k < P; ++k) A[k] = _mm256_setzero_pd();
    for (std::int64_t g = nl.group_off[c]; g < nl.group_off[c + 1]; ++g) {
      prefetch_group<4, 0>(nl, g, last, nullptr);
      prefetch_rows<4, P>(nl, g, last, s.w);
      __m256d z[P];
      load_rows<P>(s.w, nl.adj.data() + 4 * g, z);
      const __m256d r = _mm256_loadu_pd(nl.rho.data() + 4 * g);
      for (int k = 0; k < P; ++k) z[k] = _mm256_sub_pd(W[k], z[k]);
      const __m256d nz = _mm256_sqrt_pd(square_sum(z, P));
      const __m256d mask = _mm256_cmp_pd(nz, r, _CMP_GT_OQ);
      const __m256d cf = _mm256_sub_pd(one, _mm256_div_pd(r, nz));
      for (int k = 0; k < P; ++k) A[k] = _mm256_add_pd(A[k], _mm256_and_pd(_mm256_mul_pd(cf, z[k]), mask));
    }
    if (nl.has_anchor[c]) {  // rare at scale: through memory, one node at a time
      alignas(32) double tmp[4 * P];
      store_own<P>(tmp, A, false);
      for (int q = 0; q < 4; ++q) add_anchor_disk_terms(prob, v0 + q, s.w + i0 + P * q, tmp + P * q);
      load_own<P>(tmp, A);
    }
    __m256d X[P], N[P], D[P], WN[P];
    load_own<P>(s.x + i0, X);
    for (int k = 0; k < P; ++k) {
      N[k] = _mm256_sub_pd(W[k], _mm256_div_pd(A[k], vL));
      D[k] = _mm256_sub_pd(N[k], X[k]);
      WN[k] = _mm256_add_pd(N[k], _mm256_mul_pd(vb, D[k]));
    }
    store_own<P>(s.xn + i0, N, s.stream);
    store_own<P>(s.wn + i0, WN, s.stream);
    for (int k = 0; k < P; ++k) DD = _mm256_add_pd(DD, _mm256_mul_pd(D[k], D[k]));
    for (int k = 0; k < P; ++k) SS = _mm256_add_pd(SS, _mm256_mul_pd(N[k], N[k]));
    for (int k = 0; k < P; ++k) GS = _mm256_add_pd(GS, _mm256_mul_pd(A[k], A[k]));
  }
  // (0, 2, 1, 3) is its own inverse.
  _mm256_storeu_pd(s.norms, _mm256_permute4x64_pd(DD, _MM_SHUFFLE(3, 1, 2, 0)));
  _mm256_storeu_pd(s.norms + 4, _mm256_permute4x64_pd(SS, _MM_SHUFFLE(3, 1, 2, 0)));
  _mm256_storeu_pd(s.norms + 8, _mm256_permute4x64_pd(GS, _MM_SHUFFLE(3, 1, 2, 0)));
  _mm_sfence();  // order the non-temporal stores before what follows
}

// Lane bits (register order) -> 64-bit lane masks.
SNL_AVX2 inline __m256d lane_mask4(unsigned bits) {
  const __m256i bit = _mm256_setr_epi64x(1, 2, 4, 8);
  return _mm256_castsi256_pd(_mm256_cmpeq_epi64(_mm256_and_si256(_mm256_set1_epi64x(bits), bit), bit));
}

// Node-lane MM step, 4 nodes per register (full chunks only).
template <int P>
SNL_AVX2 void mm_chunks_avx2(const LocalizationProblem& prob, const NodeLanes& nl, std::int64_t c0, std::int64_t c1,
                             const MMStep& s) {
  const __m256d one = _mm256_set1_pd(1.0), minus_one = _mm256_set1_pd(-1.0), zero = _mm256_setzero_pd();
  const __m256d vkeep = _mm256_set1_pd(s.keep), vinvL = _mm256_set1_pd(s.invL);
  __m256d DD = load_scalars_0213(s.norms), SS = load_scalars_0213(s.norms + 4);
  const std::int64_t last = nl.groups() - 1;
  for (std::int64_t c = c0; c < c1; ++c) {
    const LocalId v0 = nl.first[c];
    const std::size_t i0 = std::size_t(v0) * P;
    __m256d V[P], A[P];
    load_own<P>(s.x + i0, V);
    for (int k = 0; k < P; ++k) A[k] = _mm256_setzero_pd();
    for (std::int64_t g = nl.group_off[c]; g < nl.group_off[c + 1]; ++g) {
      prefetch_group<4, P>(nl, g, last, s.y);
      prefetch_rows<4, P>(nl, g, last, s.x);
      __m256d U[P], dz[P], yn[P];
      load_rows<P>(s.x, nl.adj.data() + 4 * g, U);
      const __m256d r = _mm256_loadu_pd(nl.rho.data() + 4 * g);
      const __m256d re = lane_mask4(nl.real[g]), fw = lane_mask4(nl.fwd[g]);
      const __m256d sgn = _mm256_blendv_pd(minus_one, one, fw);
      double* yg = s.y + 4 * P * g;
      for (int k = 0; k < P; ++k) {
        // dz = x_i - x_j in the edge's orientation (both differences,
        // selected, so that signed zeros match the scalar form).
        dz[k] = _mm256_blendv_pd(_mm256_sub_pd(U[k], V[k]), _mm256_sub_pd(V[k], U[k]), fw);
        const __m256d Y = _mm256_loadu_pd(yg + 4 * k);
        A[k] = _mm256_add_pd(A[k], _mm256_and_pd(_mm256_mul_pd(sgn, _mm256_sub_pd(dz[k], Y)), re));
        yn[k] = _mm256_add_pd(_mm256_mul_pd(vkeep, Y), _mm256_mul_pd(vinvL, dz[k]));
      }
      const __m256d nv = _mm256_sqrt_pd(square_sum(yn, P));
      const __m256d pos = _mm256_cmp_pd(nv, zero, _CMP_GT_OQ);
      const __m256d f = _mm256_div_pd(r, nv);
      for (int k = 0; k < P; ++k)  // P_sphere(0) = rho e_1
        _mm256_storeu_pd(yg + 4 * k, _mm256_blendv_pd(k == 0 ? r : zero, _mm256_mul_pd(yn[k], f), pos));
    }
    if (nl.has_anchor[c]) {
      alignas(32) double tmp[4 * P];
      store_own<P>(tmp, A, false);
      for (int q = 0; q < 4; ++q)
        add_anchor_mm_terms<P>(prob, v0 + q, s.x + i0 + P * q, s.keep, s.invL, s.aw, tmp + P * q);
      load_own<P>(tmp, A);
    }
    __m256d X[P], D[P];
    for (int k = 0; k < P; ++k) {
      X[k] = _mm256_sub_pd(V[k], _mm256_mul_pd(vinvL, A[k]));
      D[k] = _mm256_sub_pd(X[k], V[k]);
    }
    store_own<P>(s.xn + i0, X, s.stream);
    for (int k = 0; k < P; ++k) DD = _mm256_add_pd(DD, _mm256_mul_pd(D[k], D[k]));
    for (int k = 0; k < P; ++k) SS = _mm256_add_pd(SS, _mm256_mul_pd(X[k], X[k]));
  }
  _mm256_storeu_pd(s.norms, _mm256_permute4x64_pd(DD, _MM_SHUFFLE(3, 1, 2, 0)));
  _mm256_storeu_pd(s.norms + 4, _mm256_permute4x64_pd(SS, _MM_SHUFFLE(3, 1, 2, 0)));
  _mm_sfence();
}

// ---- AVX-512: the same node-lane steps with 8 nodes per register. Lanes
// hold nodes (0, 4, 1, 5, 2, 6, 3, 7) of the chunk (NodeLanes::lane_node).
// A lane whose slot is inside its disk is left as it is by a masked add,
// which is the scalar form's "+ (+0.0)" (the sum is never -0.0).
#define SNL_AVX512 __attribute__((target("avx512f,avx512dq")))
// GCC 12 warns about the intrinsics headers' own deliberately undefined
// registers (_mm512_undefined_pd) once they are inlined here.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

// Rows idx[0..7] of x (p = P) as P registers in lane order (0, 4, 1, 5, ...).
template <int P>
SNL_AVX512 inline void load_rows8(const double* x, const LocalId* idx, __m512d* U) {
  auto row = [&](int q) { return _mm_loadu_pd(x + std::size_t(idx[q]) * P); };
  __m512d a = _mm512_castpd128_pd512(row(0)), b = _mm512_castpd128_pd512(row(4));
  a = _mm512_insertf64x2(a, row(1), 1);
  b = _mm512_insertf64x2(b, row(5), 1);
  a = _mm512_insertf64x2(a, row(2), 2);
  b = _mm512_insertf64x2(b, row(6), 2);
  a = _mm512_insertf64x2(a, row(3), 3);
  b = _mm512_insertf64x2(b, row(7), 3);
  U[0] = _mm512_unpacklo_pd(a, b);
  U[1] = _mm512_unpackhi_pd(a, b);
  if constexpr (P == 3) {
    auto z = [&](int q) { return _mm_load_sd(x + std::size_t(idx[q]) * 3 + 2); };
    __m512d c = _mm512_castpd128_pd512(z(0)), d = _mm512_castpd128_pd512(z(4));
    c = _mm512_insertf64x2(c, z(1), 1);
    d = _mm512_insertf64x2(d, z(5), 1);
    c = _mm512_insertf64x2(c, z(2), 2);
    d = _mm512_insertf64x2(d, z(6), 2);
    c = _mm512_insertf64x2(c, z(3), 3);
    d = _mm512_insertf64x2(d, z(7), 3);
    U[2] = _mm512_unpacklo_pd(c, d);
  }
}

// load_own with 8 lanes.
template <int P>
SNL_AVX512 inline void load_own8(const double* r, __m512d* U) {
  if constexpr (P == 2) {
    const __m512d a = _mm512_loadu_pd(r), b = _mm512_loadu_pd(r + 8);
    U[0] = _mm512_unpacklo_pd(a, b);
    U[1] = _mm512_unpackhi_pd(a, b);
  } else {
    load_rows8<P>(r, kIota, U);
  }
}

// The inverse of load_own8; non-temporal stores for p = 2 only (see store_own).
template <int P>
SNL_AVX512 inline void store_own8(double* t, const __m512d* U, bool stream) {
  if constexpr (P == 2) {
    const __m512d lo = _mm512_unpacklo_pd(U[0], U[1]), hi = _mm512_unpackhi_pd(U[0], U[1]);
    if (stream) {
      _mm_stream_pd(t, _mm512_castpd512_pd128(lo));
      _mm_stream_pd(t + 2, _mm512_extractf64x2_pd(lo, 1));
      _mm_stream_pd(t + 4, _mm512_extractf64x2_pd(lo, 2));
      _mm_stream_pd(t + 6, _mm512_extractf64x2_pd(lo, 3));
      _mm_stream_pd(t + 8, _mm512_castpd512_pd128(hi));
      _mm_stream_pd(t + 10, _mm512_extractf64x2_pd(hi, 1));
      _mm_stream_pd(t + 12, _mm512_extractf64x2_pd(hi, 2));
      _mm_stream_pd(t + 14, _mm512_extractf64x2_pd(hi, 3));
    } else {
      _mm512_storeu_pd(t, lo);      // nodes 0..3
      _mm512_storeu_pd(t + 8, hi);  // nodes 4..7
    }
  } else {
    alignas(64) double lanes[P][8];
    for (int k = 0; k < P; ++k) _mm512_store_pd(lanes[k], U[k]);
    rows_from_lanes(t, lanes);
  }
}

// Lane sums <-> per-node-offset arrays.
SNL_AVX512 inline __m512d load_lanes8(const double* q) {
  return _mm512_permutexvar_pd(_mm512_setr_epi64(0, 4, 1, 5, 2, 6, 3, 7), _mm512_loadu_pd(q));
}
SNL_AVX512 inline void store_lanes8(double* q, __m512d v) {
  _mm512_storeu_pd(q, _mm512_permutexvar_pd(_mm512_setr_epi64(0, 2, 4, 6, 1, 3, 5, 7), v));
}

// square_sum with 8 lanes.
SNL_AVX512 inline __m512d square_sum8(const __m512d* U, int P) {
  __m512d s = _mm512_mul_pd(U[0], U[0]);
  for (int k = 1; k < P; ++k) s = _mm512_add_pd(s, _mm512_mul_pd(U[k], U[k]));
  return s;
}

template <int P>
SNL_AVX512 void relax_chunks_avx512(const LocalizationProblem& prob, const NodeLanes& nl, std::int64_t c0,
                                    std::int64_t c1, const RelaxStep& s) {
  const __m512d one = _mm512_set1_pd(1.0), vL = _mm512_set1_pd(s.L), vb = _mm512_set1_pd(s.beta);
  __m512d DD = load_lanes8(s.norms), SS = load_lanes8(s.norms + 8), GS = load_lanes8(s.norms + 16);
  const std::int64_t last = nl.groups() - 1;
  for (std::int64_t c = c0; c < c1; ++c) {
    const LocalId v0 = nl.first[c];
    const std::size_t i0 = std::size_t(v0) * P;
    __m512d W[P], A[P];
    load_own8<P>(s.w + i0, W);
    for (int k = 0; k < P; ++k) A[k] = _mm512_setzero_pd();
    for (std::int64_t g = nl.group_off[c]; g < nl.group_off[c + 1]; ++g) {
      prefetch_group<8, 0>(nl, g, last, nullptr);
      prefetch_rows<8, P>(nl, g, last, s.w);
      __m512d z[P];
      load_rows8<P>(s.w, nl.adj.data() + 8 * g, z);
      const __m512d r = _mm512_loadu_pd(nl.rho.data() + 8 * g);
      for (int k = 0; k < P; ++k) z[k] = _mm512_sub_pd(W[k], z[k]);
      const __m512d nz = _mm512_sqrt_pd(square_sum8(z, P));
      const __mmask8 out = _mm512_cmp_pd_mask(nz, r, _CMP_GT_OQ);
      const __m512d cf = _mm512_sub_pd(one, _mm512_div_pd(r, nz));
      for (int k = 0; k < P; ++k) A[k] = _mm512_mask_add_pd(A[k], out, A[k], _mm512_mul_pd(cf, z[k]));
    }
    if (nl.has_anchor[c]) {
      alignas(64) double tmp[8 * P];
      store_own8<P>(tmp, A, false);
      for (int q = 0; q < 8; ++q) add_anchor_disk_terms(prob, v0 + q, s.w + i0 + P * q, tmp + P * q);
      load_own8<P>(tmp, A);
    }
    __m512d X[P], N[P], D[P], WN[P];
    load_own8<P>(s.x + i0, X);
    for (int k = 0; k < P; ++k) {
      N[k] = _mm512_sub_pd(W[k], _mm512_div_pd(A[k], vL));
      D[k] = _mm512_sub_pd(N[k], X[k]);
      WN[k] = _mm512_add_pd(N[k], _mm512_mul_pd(vb, D[k]));
    }
    store_own8<P>(s.xn + i0, N, s.stream);
    store_own8<P>(s.wn + i0, WN, s.stream);
    for (int k = 0; k < P; ++k) DD = _mm512_add_pd(DD, _mm512_mul_pd(D[k], D[k]));
    for (int k = 0; k < P; ++k) SS = _mm512_add_pd(SS, _mm512_mul_pd(N[k], N[k]));
    for (int k = 0; k < P; ++k) GS = _mm512_add_pd(GS, _mm512_mul_pd(A[k], A[k]));
  }
  store_lanes8(s.norms, DD);
  store_lanes8(s.norms + 8, SS);
  store_lanes8(s.norms + 16, GS);
  _mm_sfence();  // order the non-temporal stores before what follows
}

template <int P>
SNL_AVX512 void mm_chunks_avx512(const LocalizationProblem& prob, const NodeLanes& nl, std::int64_t c0,
                                 std::int64_t c1, const MMStep& s) {
  const __m512d minus_one = _mm512_set1_pd(-1.0), zero = _mm512_setzero_pd();
  const __m512d vkeep = _mm512_set1_pd(s.keep), vinvL = _mm512_set1_pd(s.invL);
  __m512d DD = load_lanes8(s.norms), SS = load_lanes8(s.norms + 8);
  const std::int64_t last = nl.groups() - 1;
  for (std::int64_t c = c0; c < c1; ++c) {
    const LocalId v0 = nl.first[c];
    const std::size_t i0 = std::size_t(v0) * P;
    __m512d V[P], A[P];
    load_own8<P>(s.x + i0, V);
    for (int k = 0; k < P; ++k) A[k] = _mm512_setzero_pd();
    for (std::int64_t g = nl.group_off[c]; g < nl.group_off[c + 1]; ++g) {
      prefetch_group<8, P>(nl, g, last, s.y);
      prefetch_rows<8, P>(nl, g, last, s.x);
      __m512d U[P], dz[P], yn[P];
      load_rows8<P>(s.x, nl.adj.data() + 8 * g, U);
      const __m512d r = _mm512_loadu_pd(nl.rho.data() + 8 * g);
      const __mmask8 re = nl.real[g], fw = nl.fwd[g], bw = static_cast<__mmask8>(~fw);
      double* yg = s.y + 8 * P * g;
      for (int k = 0; k < P; ++k) {
        dz[k] = _mm512_mask_sub_pd(_mm512_sub_pd(U[k], V[k]), fw, V[k], U[k]);
        const __m512d Y = _mm512_loadu_pd(yg + 8 * k);
        __m512d t = _mm512_sub_pd(dz[k], Y);
        t = _mm512_mask_mul_pd(t, bw, t, minus_one);  // sgn (dz - y): 1.0 * t is t
        A[k] = _mm512_mask_add_pd(A[k], re, A[k], t);
        yn[k] = _mm512_add_pd(_mm512_mul_pd(vkeep, Y), _mm512_mul_pd(vinvL, dz[k]));
      }
      const __m512d nv = _mm512_sqrt_pd(square_sum8(yn, P));
      const __mmask8 pos = _mm512_cmp_pd_mask(nv, zero, _CMP_GT_OQ);
      const __m512d f = _mm512_div_pd(r, nv);
      for (int k = 0; k < P; ++k)  // P_sphere(0) = rho e_1
        _mm512_storeu_pd(yg + 8 * k, _mm512_mask_mul_pd(k == 0 ? r : zero, pos, yn[k], f));
    }
    if (nl.has_anchor[c]) {
      alignas(64) double tmp[8 * P];
      store_own8<P>(tmp, A, false);
      for (int q = 0; q < 8; ++q)
        add_anchor_mm_terms<P>(prob, v0 + q, s.x + i0 + P * q, s.keep, s.invL, s.aw, tmp + P * q);
      load_own8<P>(tmp, A);
    }
    __m512d X[P], D[P];
    for (int k = 0; k < P; ++k) {
      X[k] = _mm512_sub_pd(V[k], _mm512_mul_pd(vinvL, A[k]));
      D[k] = _mm512_sub_pd(X[k], V[k]);
    }
    store_own8<P>(s.xn + i0, X, s.stream);
    for (int k = 0; k < P; ++k) DD = _mm512_add_pd(DD, _mm512_mul_pd(D[k], D[k]));
    for (int k = 0; k < P; ++k) SS = _mm512_add_pd(SS, _mm512_mul_pd(X[k], X[k]));
  }
  store_lanes8(s.norms, DD);
  store_lanes8(s.norms + 8, SS);
  _mm_sfence();
}
#pragma GCC diagnostic pop
#endif

}  // namespace

bool simd_enabled() { return g_level > 0; }

bool set_simd_enabled(bool on) {
  const bool old = g_level > 0;
  g_level = on ? g_top : 0;
  return old;
}

int node_lanes() { return g_lanes; }

const char* simd_name() { return g_level == 2 ? "avx512" : g_level == 1 ? "avx2" : "scalar"; }

void add_anchor_disk_terms(const LocalizationProblem& prob, LocalId v, const double* xv, double* acc) {
  const int p = prob.dim();
  const auto& aoff = prob.anchor_offsets();
  const auto& aid = prob.anchor_ids();
  const auto& ar = prob.anchor_ranges();
  const double* anc = prob.anchors().data();
  double t[3];
  for (auto e = aoff[v]; e < aoff[v + 1]; ++e) {
    const double* a = anc + std::size_t(aid[e]) * p;
    if (p == 2)
      disk_term<2>(xv, a, ar[e], t);
    else
      disk_term<3>(xv, a, ar[e], t);
    for (int c = 0; c < p; ++c) acc[c] += t[c];
  }
}

std::int64_t NodeLanes::bytes() const {
  return static_cast<std::int64_t>(first.capacity() * sizeof(LocalId) + count.capacity() + has_anchor.capacity() +
                                   group_off.capacity() * sizeof(std::int64_t) + adj.capacity() * sizeof(LocalId) +
                                   rho.capacity() * sizeof(double) + real.capacity() + fwd.capacity());
}

void NodeLanes::build(const LocalizationProblem& prob) {
  const DistGraph& gr = prob.graph();
  const auto& off = gr.offsets();
  const auto& aoff = prob.anchor_offsets();
  const LocalId n_int = gr.num_interior(), n_owned = gr.num_owned();
  const int C = lanes = node_lanes();
  auto deg = [&](LocalId v) { return off[v + 1] - off[v]; };
  // Two passes (widths, then fill) so that every array is allocated once, at
  // its size. f(v0, count, width) per chunk, interior chunks first.
  auto each_chunk = [&](auto&& f) {
    for (auto [b, e] : {std::pair<LocalId, LocalId>{0, n_int}, {n_int, n_owned}})
      for (LocalId v0 = b; v0 < e; v0 += C) {
        const int cnt = static_cast<int>(std::min<LocalId>(C, e - v0));
        std::int64_t width = 0;
        for (int q = 0; q < cnt; ++q) width = std::max(width, deg(v0 + q));
        f(v0, cnt, width);
      }
  };
  std::int64_t chunks = 0, groups = 0;
  split = 0;
  each_chunk([&](LocalId v0, int, std::int64_t width) {
    if (v0 < n_int) ++split;
    ++chunks;
    groups += width;
  });
  first.assign(std::size_t(chunks), 0);
  count.assign(std::size_t(chunks), 0);
  has_anchor.assign(std::size_t(chunks), 0);
  group_off.assign(std::size_t(chunks) + 1, 0);
  adj.assign(std::size_t(groups) * C, 0);
  rho.assign(std::size_t(groups) * C, 1.0);
  real.assign(std::size_t(groups), 0);
  fwd.assign(std::size_t(groups), 0);
  n_interior = n_int;
  std::int64_t c = 0;
  each_chunk([&](LocalId v0, int cnt, std::int64_t width) {
    first[c] = v0;
    count[c] = static_cast<std::uint8_t>(cnt);
    const std::int64_t g0 = group_off[c];
    group_off[c + 1] = g0 + width;
    for (int q = 0; q < cnt; ++q) {
      const LocalId v = v0 + q;
      has_anchor[c] |= aoff[v] != aoff[v + 1];
      for (std::int64_t g = 0; g < width; ++g) {
        const std::size_t at = std::size_t(g0 + g) * C;
        const int L = NodeLanes::lane_of_node(q, C);
        if (g >= deg(v)) {  // padding: the node itself, range 1
          adj[at + q] = v;
          continue;
        }
        const LocalId u = gr.adjacency()[off[v] + g];
        adj[at + q] = u;
        rho[at + L] = gr.edge_values()[off[v] + g];
        real[g0 + g] |= std::uint8_t(1u << L);
        if (gr.global_id(v) < gr.global_id(u)) fwd[g0 + g] |= std::uint8_t(1u << L);
      }
    }
    ++c;
  });
}

std::int64_t LevelPlan::bytes() const {
  std::int64_t b = static_cast<std::int64_t>(depth.capacity());
  for (const auto& d : deferred) b += static_cast<std::int64_t>(d.capacity() * sizeof(d[0]));
  return b;
}

void LevelPlan::build(const LocalizationProblem& prob, const NodeLanes& nl, int n_levels) {
  const DistGraph& gr = prob.graph();
  const auto& off = gr.offsets();
  const auto& adj = gr.adjacency();
  const std::int64_t chunks = nl.size(), split = nl.split;
  const int cap = std::max(n_levels, 2);
  skew = 0;
  depth.assign(std::size_t(chunks), std::uint8_t(cap));
  std::fill(depth.begin() + split, depth.end(), std::uint8_t(0));
  deferred.assign(std::size_t(n_levels), {});
  if (n_levels == 1) return;  // a plain iteration needs only "boundary or not"
  auto chunk_of = [&](LocalId u) -> std::int64_t {
    return u < nl.n_interior ? u / nl.lanes : split + (u - nl.n_interior) / nl.lanes;
  };
  // Breadth-first distances in the chunk graph from the boundary chunks.
  for (int r = 1; r < cap; ++r)
    for (std::int64_t c = 0; c < chunks; ++c) {
      if (depth[c] != r - 1) continue;
      for (LocalId v = nl.first[c]; v < nl.first[c] + nl.count[c]; ++v)
        for (auto e = off[v]; e < off[v + 1]; ++e)
          if (adj[e] < gr.num_owned()) {
            auto& d = depth[chunk_of(adj[e])];
            if (d > r) d = std::uint8_t(r);
          }
    }
  // Chunks of depth >= 2 have only interior neighbours: their widest edge sets the skew.
  for (std::int64_t c = 0; c < split; ++c) {
    if (depth[c] < 2) continue;
    for (LocalId v = nl.first[c]; v < nl.first[c] + nl.count[c]; ++v)
      for (auto e = off[v]; e < off[v + 1]; ++e) skew = std::max(skew, std::abs(chunk_of(adj[e]) - c));
  }
  block = std::max<std::int64_t>(skew, 16);
  for (int j = 1; j < n_levels; ++j)
    for (std::int64_t c = 0; c < split; ++c) {
      if (depth[c] > j) continue;
      auto& runs = deferred[j];
      if (!runs.empty() && runs.back().second == c)
        runs.back().second = c + 1;
      else
        runs.emplace_back(c, c + 1);
    }
}

namespace {

// Chunks [c0, c1) of one part: the full ones through the SIMD kernel of the
// layout's lane width where the CPU allows it, the rest (the part's partial
// last chunk; everything without SIMD) through the scalar twin. Kernel is a
// tag with the three functions as static members.
template <class Kernel, class Step>
void run_chunks(const LocalizationProblem& prob, const NodeLanes& nl, std::int64_t c0, std::int64_t c1,
                const Step& s) {
  if (c0 >= c1) return;
  const std::int64_t full = nl.count[c1 - 1] == nl.lanes ? c1 : c1 - 1;
  auto run = [&](auto dim) {
    constexpr int P = decltype(dim)::value;
#ifdef SNL_HAVE_AVX2_PATH
    if (g_level == 2 && nl.lanes == 8) {
      Kernel::template avx512<P>(prob, nl, c0, full, s);
      c0 = full;
    } else if (g_level >= 1 && nl.lanes == 4) {
      Kernel::template avx2<P>(prob, nl, c0, full, s);
      c0 = full;
    }
#endif
    for (std::int64_t c = c0; c < c1; ++c) Kernel::template scalar<P>(prob, nl, c, s);
  };
  if (prob.dim() == 2)
    run(std::integral_constant<int, 2>{});
  else
    run(std::integral_constant<int, 3>{});
}

// Tags naming the three paths of each step for run_chunks.
struct RelaxKernels {
#ifdef SNL_HAVE_AVX2_PATH
  template <int P>
  static void avx512(const LocalizationProblem& prob, const NodeLanes& nl, std::int64_t c0, std::int64_t c1,
                     const RelaxStep& s) {
    relax_chunks_avx512<P>(prob, nl, c0, c1, s);
  }
  template <int P>
  static void avx2(const LocalizationProblem& prob, const NodeLanes& nl, std::int64_t c0, std::int64_t c1,
                   const RelaxStep& s) {
    relax_chunks_avx2<P>(prob, nl, c0, c1, s);
  }
#endif
  template <int P>
  static void scalar(const LocalizationProblem& prob, const NodeLanes& nl, std::int64_t c, const RelaxStep& s) {
    relax_chunk_scalar<P>(prob, nl, c, s);
  }
};

struct MMKernels {
#ifdef SNL_HAVE_AVX2_PATH
  template <int P>
  static void avx512(const LocalizationProblem& prob, const NodeLanes& nl, std::int64_t c0, std::int64_t c1,
                     const MMStep& s) {
    mm_chunks_avx512<P>(prob, nl, c0, c1, s);
  }
  template <int P>
  static void avx2(const LocalizationProblem& prob, const NodeLanes& nl, std::int64_t c0, std::int64_t c1,
                   const MMStep& s) {
    mm_chunks_avx2<P>(prob, nl, c0, c1, s);
  }
#endif
  template <int P>
  static void scalar(const LocalizationProblem& prob, const NodeLanes& nl, std::int64_t c, const MMStep& s) {
    mm_chunk_scalar<P>(prob, nl, c, s);
  }
};

}  // namespace

void relax_chunks(const LocalizationProblem& prob, const NodeLanes& nl, std::int64_t c0, std::int64_t c1,
                  const RelaxStep& s) {
  run_chunks<RelaxKernels>(prob, nl, c0, c1, s);
}

void mm_chunks(const LocalizationProblem& prob, const NodeLanes& nl, std::int64_t c0, std::int64_t c1,
               const MMStep& s) {
  run_chunks<MMKernels>(prob, nl, c0, c1, s);
}

}  // namespace snl::detail
