#include "kernels/simd_common.hpp"
#include "kernels/terms.hpp"

#ifdef SNL_HAVE_AVX2_PATH

namespace snl::detail {

namespace {

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

// Eight doubles with non-temporal stores, 16 bytes at a time (std::vector
// storage is 16-byte aligned, as _mm_stream_pd needs).
SNL_AVX512 inline void stream8(double* t, __m512d v) {
  _mm_stream_pd(t, _mm512_castpd512_pd128(v));
  _mm_stream_pd(t + 2, _mm512_extractf64x2_pd(v, 1));
  _mm_stream_pd(t + 4, _mm512_extractf64x2_pd(v, 2));
  _mm_stream_pd(t + 6, _mm512_extractf64x2_pd(v, 3));
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

// Anchor pairs whose disk terms the relaxation step forms ahead, 8 at a time.
constexpr int kAheadPairs = 64;

// The disk terms (terms.hpp, disk_term) of anchor pairs [tb, te), te - tb <=
// kAheadPairs, the first of them in chunk c, into T (P per pair, pair order):
// the scalar terms' arithmetic lane by lane, so the same bits.
template <int P>
SNL_AVX512 void anchor_disk_terms8(const LocalizationProblem& prob, const NodeLanes& nl, std::int64_t c,
                                   std::int64_t tb, std::int64_t te, const double* w, bool ml, double* T) {
  alignas(64) LocalId idx[kAheadPairs + 8], aidx[kAheadPairs + 8];
  alignas(64) double rr[kAheadPairs + 8];
  const int n = int(te - tb);
  for (int i = 0; i < n; ++i) {
    const std::int64_t e = tb + i;
    while (nl.anchor_off[c + 1] <= e) ++c;
    idx[i] = nl.first[c] + nl.anchor_q[e];
    aidx[i] = LocalId(prob.anchor_ids()[e]);
    rr[i] = prob.anchor_ranges()[e];
  }
  for (int i = n; i < ((n + 7) & ~7); ++i) {  // a partial group repeats the last pair
    idx[i] = idx[n - 1];
    aidx[i] = aidx[n - 1];
    rr[i] = rr[n - 1];
  }
  const __m512d one = _mm512_set1_pd(1.0);
  for (int b = 0; b < n; b += 8) {
    __m512d z[P], a[P];
    load_rows8<P>(w, idx + b, z);
    load_rows8<P>(prob.anchors().data(), aidx + b, a);
    const __m512d r = load_lanes8(rr + b);
    for (int k = 0; k < P; ++k) z[k] = _mm512_sub_pd(z[k], a[k]);
    const __m512d nz = _mm512_sqrt_pd(square_sum8(z, P));
    const __mmask8 out = _mm512_cmp_pd_mask(nz, ml ? _mm512_setzero_pd() : r, _CMP_GT_OQ);
    const __m512d cf = _mm512_sub_pd(one, _mm512_div_pd(r, nz));
    __m512d t[P];
    for (int k = 0; k < P; ++k) t[k] = _mm512_maskz_mul_pd(out, cf, z[k]);
    if (b + 8 <= n) {
      store_own8<P>(T + std::size_t(b) * P, t, false);
    } else {
      alignas(64) double tail[8 * P];
      store_own8<P>(tail, t, false);
      for (int i = 0; i < (n - b) * P; ++i) T[std::size_t(b) * P + i] = tail[i];
    }
  }
}

template <int P>
SNL_AVX512 void relax_chunks_avx512(const LocalizationProblem& prob, const NodeLanes& nl, std::int64_t c0,
                                    std::int64_t c1, const RelaxStep& s) {
  alignas(64) double T[kAheadPairs * P];  // anchor terms of pairs [tb, te)
  std::int64_t tb = 0, te = 0;
  const __m512d one = _mm512_set1_pd(1.0), vL = _mm512_set1_pd(s.L), vb = _mm512_set1_pd(s.beta);
  __m512d DD = load_lanes8(s.norms), SS = load_lanes8(s.norms + 8), GS = load_lanes8(s.norms + 16);
  const bool rs = s.restart && s.inv_d;
  __m512d RS = rs ? _mm512_loadu_pd(s.restart) : _mm512_setzero_pd();
  __m512d RA = rs ? _mm512_loadu_pd(s.restart + 8) : _mm512_setzero_pd();
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
      const __mmask8 out = _mm512_cmp_pd_mask(nz, s.ml ? _mm512_setzero_pd() : r, _CMP_GT_OQ);
      const __m512d cf = _mm512_sub_pd(one, _mm512_div_pd(r, nz));
      for (int k = 0; k < P; ++k) A[k] = _mm512_mask_add_pd(A[k], out, A[k], _mm512_mul_pd(cf, z[k]));
    }
    if (const std::int64_t e0 = nl.anchor_off[c], e1 = nl.anchor_off[c + 1]; e0 != e1) {
      alignas(64) double tmp[8 * P];
      store_own8<P>(tmp, A, false);
      if (e1 - e0 > kAheadPairs) {
        add_chunk_anchor_disk_terms<P>(prob, nl, c, s.w + i0, tmp, s.ml);
      } else {
        if (e1 > te) {  // the terms of the next pairs, this chunk's first
          tb = e0;
          te = std::min(nl.anchor_off[c1], e0 + kAheadPairs);
          anchor_disk_terms8<P>(prob, nl, c, tb, te, s.w, s.ml, T);
        }
        for (std::int64_t e = e0; e < e1; ++e)  // per node in CSR order, as add_anchor_disk_terms
          for (int k = 0; k < P; ++k) tmp[P * nl.anchor_q[e] + k] += T[std::size_t(e - tb) * P + k];
      }
      load_own8<P>(tmp, A);
    }
    __m512d X[P], N[P], D[P], WN[P];
    load_own8<P>(s.x + i0, X);
    const __m512d Dinv = s.inv_d ? load_lanes8(s.inv_d + v0) : _mm512_setzero_pd();
    for (int k = 0; k < P; ++k) {
      N[k] = _mm512_sub_pd(W[k], s.inv_d ? _mm512_mul_pd(A[k], Dinv) : _mm512_div_pd(A[k], vL));
      D[k] = _mm512_sub_pd(N[k], X[k]);
      WN[k] = _mm512_add_pd(N[k], _mm512_mul_pd(vb, D[k]));
    }
    store_own8<P>(s.xn + i0, N, s.stream);
    store_own8<P>(s.wn + i0, WN, s.stream);
    if (s.g) store_own8<P>(s.g + i0, A, false);
    for (int k = 0; k < P; ++k) DD = _mm512_add_pd(DD, _mm512_mul_pd(D[k], D[k]));
    for (int k = 0; k < P; ++k) SS = _mm512_add_pd(SS, _mm512_mul_pd(N[k], N[k]));
    for (int k = 0; k < P; ++k) GS = _mm512_add_pd(GS, _mm512_mul_pd(A[k], A[k]));
    if (rs) {  // the scalar twin's q_v per lane: sum over c from +0.0, then / inv_d
      __m512d T = _mm512_setzero_pd();
      for (int k = 0; k < P; ++k) T = _mm512_add_pd(T, _mm512_mul_pd(_mm512_sub_pd(W[k], N[k]), D[k]));
      const __m512d Q = _mm512_maskz_div_pd(_mm512_cmp_pd_mask(Dinv, _mm512_setzero_pd(), _CMP_GT_OQ), T, Dinv);
      RS = _mm512_add_pd(RS, Q);
      RA = _mm512_add_pd(RA, _mm512_abs_pd(Q));
    }
  }
  store_lanes8(s.norms, DD);
  store_lanes8(s.norms + 8, SS);
  store_lanes8(s.norms + 16, GS);
  if (rs) {
    _mm512_storeu_pd(s.restart, RS);
    _mm512_storeu_pd(s.restart + 8, RA);
  }
  _mm_sfence();  // order the non-temporal stores before what follows
}

// One group's acceptance-cost terms (mm_cost_chunk): with Z = x_v - x_u per
// coordinate and Y the edge variables (kY), |Z - Y|^2 into SF and (|Z| -
// rho)^2 into Sf, on the lanes in M (forward real slots); the others add
// +0.0, which changes no sum. The MM step's fused form and
// mm_cost_chunk_avx512_p share it: the same bits.
template <int P, bool kY>
SNL_AVX512 inline void add_edge_costs8(const __m512d* Z, const __m512d* Y, __m512d r, __mmask8 M, __m512d& SF,
                                       __m512d& Sf) {
  __m512d S = _mm512_setzero_pd(), Z2 = _mm512_setzero_pd();
  for (int k = 0; k < P; ++k) {
    if (kY) {
      const __m512d R = _mm512_sub_pd(Z[k], Y[k]);
      S = _mm512_add_pd(S, _mm512_mul_pd(R, R));
    }
    Z2 = _mm512_add_pd(Z2, _mm512_mul_pd(Z[k], Z[k]));
  }
  const __m512d Mf = _mm512_sub_pd(_mm512_sqrt_pd(Z2), r);
  SF = _mm512_add_pd(SF, _mm512_maskz_mov_pd(M, S));
  Sf = _mm512_add_pd(Sf, _mm512_maskz_mov_pd(M, _mm512_mul_pd(Mf, Mf)));
}

// Extrap: mm-accel's extrapolated edge variables ya + beta (ya - yb), formed
// on the fly, the result stored to y (as mm_chunks_avx2). Cost (with
// Extrap): each chunk's acceptance costs of (x, ya) as well
// (MMStep::cost_F), add_edge_costs8 on the rows and edge variables the step
// has loaded anyway.
template <int P, bool Extrap = false, bool Cost = false>
SNL_AVX512 void mm_chunks_avx512_impl(const LocalizationProblem& prob, const NodeLanes& nl, std::int64_t c0,
                                      std::int64_t c1, const MMStep& s) {
  const __m512d minus_one = _mm512_set1_pd(-1.0), zero = _mm512_setzero_pd();
  const __m512d vkeep = _mm512_set1_pd(s.keep), vinvL = _mm512_set1_pd(s.invL), vbeta = _mm512_set1_pd(s.beta);
  __m512d DD = load_lanes8(s.norms), SS = load_lanes8(s.norms + 8);
  const std::int64_t last = nl.groups() - 1;
  for (std::int64_t c = c0; c < c1; ++c) {
    const LocalId v0 = nl.first[c];
    const std::size_t i0 = std::size_t(v0) * P;
    __m512d V[P], A[P], XV[P];
    load_own8<P>(s.x + i0, V);
    if constexpr (Cost)
      for (int k = 0; k < P; ++k) XV[k] = V[k];  // the candidate's own rows
    if (Extrap && s.xb) {  // x + beta (x - xb), as the blend pass
      __m512d B[P];
      load_own8<P>(s.xb + i0, B);
      for (int k = 0; k < P; ++k) V[k] = _mm512_add_pd(V[k], _mm512_mul_pd(vbeta, _mm512_sub_pd(V[k], B[k])));
    }
    for (int k = 0; k < P; ++k) A[k] = _mm512_setzero_pd();
    __m512d SF = zero, Sf = zero;  // Cost: the chunk's sums
    unsigned any = 0;
    for (std::int64_t g = nl.group_off[c]; g < nl.group_off[c + 1]; ++g) {
      if constexpr (Extrap) {
        prefetch_group<8, P>(nl, g, last, s.ya);
        prefetch_group<8, P>(nl, g, last, s.yb);
        if (s.xb) prefetch_rows<8, P>(nl, g, last, s.xb);
      } else {
        prefetch_group<8, P>(nl, g, last, s.y);
      }
      prefetch_rows<8, P>(nl, g, last, s.x);
      __m512d U[P], dz[P], yn[P], Z[P];
      load_rows8<P>(s.x, nl.adj.data() + 8 * g, U);
      if constexpr (Cost)
        for (int k = 0; k < P; ++k) Z[k] = _mm512_sub_pd(XV[k], U[k]);
      if (Extrap && s.xb) {
        __m512d B[P];
        load_rows8<P>(s.xb, nl.adj.data() + 8 * g, B);
        for (int k = 0; k < P; ++k) U[k] = _mm512_add_pd(U[k], _mm512_mul_pd(vbeta, _mm512_sub_pd(U[k], B[k])));
      }
      const __m512d r = _mm512_loadu_pd(nl.rho.data() + 8 * g);
      const __mmask8 re = nl.real[g], fw = nl.fwd[g], bw = static_cast<__mmask8>(~fw);
      double* yg = s.y + 8 * P * g;
      __m512d YA[P];  // Cost: the candidate's edge variables
      for (int k = 0; k < P; ++k) {
        dz[k] = _mm512_mask_sub_pd(_mm512_sub_pd(U[k], V[k]), fw, V[k], U[k]);
        __m512d Y;
        if constexpr (Extrap) {  // a + beta (a - b), as the blend pass
          const __m512d Ya = YA[k] = _mm512_loadu_pd(s.ya + 8 * P * g + 8 * k);
          Y = _mm512_add_pd(Ya, _mm512_mul_pd(vbeta, _mm512_sub_pd(Ya, _mm512_loadu_pd(s.yb + 8 * P * g + 8 * k))));
        } else {
          Y = _mm512_loadu_pd(yg + 8 * k);
        }
        __m512d t = _mm512_sub_pd(dz[k], Y);
        t = _mm512_mask_mul_pd(t, bw, t, minus_one);  // sgn (dz - y): 1.0 * t is t
        A[k] = _mm512_mask_add_pd(A[k], re, A[k], t);
        yn[k] = _mm512_add_pd(_mm512_mul_pd(vkeep, Y), _mm512_mul_pd(vinvL, dz[k]));
      }
      if constexpr (Cost) {
        const __mmask8 M = static_cast<__mmask8>(re & fw);
        any |= M;
        add_edge_costs8<P, true>(Z, YA, r, M, SF, Sf);
      }
      const __m512d nv = _mm512_sqrt_pd(square_sum8(yn, P));
      const __mmask8 pos = _mm512_cmp_pd_mask(nv, zero, _CMP_GT_OQ);
      const __m512d f = _mm512_div_pd(r, nv);
      for (int k = 0; k < P; ++k) {  // P_sphere(0) = rho e_1
        const __m512d Yn = _mm512_mask_mul_pd(k == 0 ? r : zero, pos, yn[k], f);
        if (Extrap && s.stream_y)
          stream8(yg + 8 * k, Yn);
        else
          _mm512_storeu_pd(yg + 8 * k, Yn);
      }
    }
    if (nl.anchor_off[c] != nl.anchor_off[c + 1]) {
      alignas(64) double tmp[8 * P], own[8 * P];
      store_own8<P>(tmp, A, false);
      const double* xo = s.x + i0;
      if (Extrap && s.xb) {  // the extrapolated own rows
        store_own8<P>(own, V, false);
        xo = own;
      }
      add_chunk_anchor_mm_terms<P>(prob, nl, c, xo, s.keep, s.invL, s.aw, tmp);
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
    if constexpr (Cost) {
      const std::size_t q = std::size_t(c - s.cost_base);
      _mm512_storeu_pd(s.cost_F + 8 * q, SF);
      _mm512_storeu_pd(s.cost_f + 8 * q, Sf);
      s.cost_any[q] = any;
    }
  }
  store_lanes8(s.norms, DD);
  store_lanes8(s.norms + 8, SS);
  _mm_sfence();
}

template <int P, bool Extrap = false>
SNL_AVX512 void mm_chunks_avx512(const LocalizationProblem& prob, const NodeLanes& nl, std::int64_t c0,
                                 std::int64_t c1, const MMStep& s) {
  if (Extrap && s.cost_F)
    mm_chunks_avx512_impl<P, Extrap, true>(prob, nl, c0, c1, s);
  else
    mm_chunks_avx512_impl<P, Extrap, false>(prob, nl, c0, c1, s);
}

// mm_cost_chunk_avx2_p with 8 lanes: the MM kernel's row loads (lane order
// (0, 4, 1, 5, ...), the layout's), the scalar twin's arithmetic per lane,
// and the lanes whose slot is not forward adding +0.0 (zero-masked).
template <int P, bool kY>
SNL_AVX512 unsigned mm_cost_chunk_avx512_p(const NodeLanes& nl, std::int64_t c, const double* x, const double* y,
                                           double* F, double* f) {
  unsigned any = 0;
  __m512d XV[P];
  load_own8<P>(x + std::size_t(nl.first[c]) * P, XV);
  __m512d SF = _mm512_setzero_pd(), Sf = _mm512_setzero_pd();
  const std::int64_t last = nl.groups() - 1;
  for (std::int64_t g = nl.group_off[c]; g < nl.group_off[c + 1]; ++g) {
    if (kY) prefetch_group<8, P>(nl, g, last, y);  // as the MM kernel (the chunks are visited in order)
    prefetch_rows<8, P>(nl, g, last, x);
    const __mmask8 M = static_cast<__mmask8>(nl.real[g] & nl.fwd[g]);
    if (!M) continue;
    any |= M;
    __m512d U[P], Z[P], Y[P];
    load_rows8<P>(x, &nl.adj[g * 8], U);
    for (int k = 0; k < P; ++k) {
      Z[k] = _mm512_sub_pd(XV[k], U[k]);
      if (kY) Y[k] = _mm512_loadu_pd(y + std::size_t(g * P + k) * 8);
    }
    add_edge_costs8<P, kY>(Z, Y, _mm512_loadu_pd(&nl.rho[g * 8]), M, SF, Sf);
  }
  _mm512_storeu_pd(F, _mm512_add_pd(_mm512_loadu_pd(F), SF));
  _mm512_storeu_pd(f, _mm512_add_pd(_mm512_loadu_pd(f), Sf));
  return any;
}

}  // namespace

unsigned mm_cost_chunk_avx512(const NodeLanes& nl, int p, std::int64_t c, const double* x, const double* y,
                              double* F, double* f) {
  if (!y) return p == 2 ? mm_cost_chunk_avx512_p<2, false>(nl, c, x, y, F, f) : mm_cost_chunk_avx512_p<3, false>(nl, c, x, y, F, f);
  return p == 2 ? mm_cost_chunk_avx512_p<2, true>(nl, c, x, y, F, f) : mm_cost_chunk_avx512_p<3, true>(nl, c, x, y, F, f);
}

const KernelTable kAvx512Kernels = {{relax_chunks_avx512<2>, relax_chunks_avx512<3>},
                                    {mm_chunks_avx512<2>, mm_chunks_avx512<3>},
                                    {mm_chunks_avx512<2, true>, mm_chunks_avx512<3, true>}};
#pragma GCC diagnostic pop

}  // namespace snl::detail

#endif  // SNL_HAVE_AVX2_PATH
