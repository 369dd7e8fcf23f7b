#include "kernels/simd_common.hpp"
#include "kernels/terms.hpp"

#ifdef SNL_HAVE_AVX2_PATH

namespace snl::detail {

namespace {

// ---- AVX2: the node-lane steps with 4 nodes per register, for p = 2 and 3.
// Rows are loaded as (x, y) pairs (and z alone for p = 3); after the unpack
// the lanes hold nodes (0, 2, 1, 3) of the chunk (NodeLanes::lane_node), and
// per-slot scalars (rho, the lane bits) are stored in that order. Only IEEE
// add/sub/mul/div/sqrt and no FMA, so every lane equals the scalar twin bit
// for bit. The kernels return normally, so that GCC emits vzeroupper: a tail
// call from AVX2 code into scalar code gets none, and the dirty upper ymm
// state slows the caller's SSE code.
#define SNL_AVX2 __attribute__((target("avx2")))


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
  const bool rs = s.restart && s.inv_d;
  __m256d RS = rs ? _mm256_loadu_pd(s.restart) : _mm256_setzero_pd();
  __m256d RA = rs ? _mm256_loadu_pd(s.restart + 4) : _mm256_setzero_pd();
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
      const __m256d mask = _mm256_cmp_pd(nz, s.ml ? _mm256_setzero_pd() : r, _CMP_GT_OQ);
      const __m256d cf = _mm256_sub_pd(one, _mm256_div_pd(r, nz));
      for (int k = 0; k < P; ++k) A[k] = _mm256_add_pd(A[k], _mm256_and_pd(_mm256_mul_pd(cf, z[k]), mask));
    }
    if (nl.anchor_off[c] != nl.anchor_off[c + 1]) {  // through memory, the nodes with anchors alone
      alignas(32) double tmp[4 * P];
      store_own<P>(tmp, A, false);
      add_chunk_anchor_disk_terms<P>(prob, nl, c, s.w + i0, tmp, s.ml);
      load_own<P>(tmp, A);
    }
    __m256d X[P], N[P], D[P], WN[P];
    load_own<P>(s.x + i0, X);
    const __m256d Dinv = s.inv_d ? load_scalars_0213(s.inv_d + v0) : _mm256_setzero_pd();
    for (int k = 0; k < P; ++k) {
      N[k] = _mm256_sub_pd(W[k], s.inv_d ? _mm256_mul_pd(A[k], Dinv) : _mm256_div_pd(A[k], vL));
      D[k] = _mm256_sub_pd(N[k], X[k]);
      WN[k] = _mm256_add_pd(N[k], _mm256_mul_pd(vb, D[k]));
    }
    store_own<P>(s.xn + i0, N, s.stream);
    store_own<P>(s.wn + i0, WN, s.stream);
    if (s.g) store_own<P>(s.g + i0, A, false);
    for (int k = 0; k < P; ++k) DD = _mm256_add_pd(DD, _mm256_mul_pd(D[k], D[k]));
    for (int k = 0; k < P; ++k) SS = _mm256_add_pd(SS, _mm256_mul_pd(N[k], N[k]));
    for (int k = 0; k < P; ++k) GS = _mm256_add_pd(GS, _mm256_mul_pd(A[k], A[k]));
    if (rs) {  // the scalar twin's q_v per lane: sum over c from +0.0, then / inv_d (0 where inv_d <= 0)
      __m256d T = _mm256_setzero_pd();
      for (int k = 0; k < P; ++k) T = _mm256_add_pd(T, _mm256_mul_pd(_mm256_sub_pd(W[k], N[k]), D[k]));
      const __m256d Q = _mm256_and_pd(_mm256_div_pd(T, Dinv), _mm256_cmp_pd(Dinv, _mm256_setzero_pd(), _CMP_GT_OQ));
      RS = _mm256_add_pd(RS, Q);
      RA = _mm256_add_pd(RA, _mm256_andnot_pd(_mm256_set1_pd(-0.0), Q));
    }
  }
  // (0, 2, 1, 3) is its own inverse.
  _mm256_storeu_pd(s.norms, _mm256_permute4x64_pd(DD, _MM_SHUFFLE(3, 1, 2, 0)));
  _mm256_storeu_pd(s.norms + 4, _mm256_permute4x64_pd(SS, _MM_SHUFFLE(3, 1, 2, 0)));
  _mm256_storeu_pd(s.norms + 8, _mm256_permute4x64_pd(GS, _MM_SHUFFLE(3, 1, 2, 0)));
  if (rs) {
    _mm256_storeu_pd(s.restart, RS);
    _mm256_storeu_pd(s.restart + 4, RA);
  }
  _mm_sfence();  // order the non-temporal stores before what follows
}

// Lane bits (register order) -> 64-bit lane masks.
SNL_AVX2 inline __m256d lane_mask4(unsigned bits) {
  const __m256i bit = _mm256_setr_epi64x(1, 2, 4, 8);
  return _mm256_castsi256_pd(_mm256_cmpeq_epi64(_mm256_and_si256(_mm256_set1_epi64x(bits), bit), bit));
}

// Node-lane MM step, 4 nodes per register (full chunks only). Extrap: the edge
// variables are mm-accel's extrapolated point ya + beta (ya - yb), formed
// on the fly (MMStep::ya), the result stored to y.
template <int P, bool Extrap = false>
SNL_AVX2 void mm_chunks_avx2(const LocalizationProblem& prob, const NodeLanes& nl, std::int64_t c0, std::int64_t c1,
                             const MMStep& s) {
  const __m256d one = _mm256_set1_pd(1.0), minus_one = _mm256_set1_pd(-1.0), zero = _mm256_setzero_pd();
  const __m256d vkeep = _mm256_set1_pd(s.keep), vinvL = _mm256_set1_pd(s.invL), vbeta = _mm256_set1_pd(s.beta);
  __m256d DD = load_scalars_0213(s.norms), SS = load_scalars_0213(s.norms + 4);
  const std::int64_t last = nl.groups() - 1;
  for (std::int64_t c = c0; c < c1; ++c) {
    const LocalId v0 = nl.first[c];
    const std::size_t i0 = std::size_t(v0) * P;
    __m256d V[P], A[P];
    load_own<P>(s.x + i0, V);
    if (Extrap && s.xb) {  // x + beta (x - xb), as the blend pass
      __m256d B[P];
      load_own<P>(s.xb + i0, B);
      for (int k = 0; k < P; ++k) V[k] = _mm256_add_pd(V[k], _mm256_mul_pd(vbeta, _mm256_sub_pd(V[k], B[k])));
    }
    for (int k = 0; k < P; ++k) A[k] = _mm256_setzero_pd();
    for (std::int64_t g = nl.group_off[c]; g < nl.group_off[c + 1]; ++g) {
      if constexpr (Extrap) {
        prefetch_group<4, P>(nl, g, last, s.ya);
        prefetch_group<4, P>(nl, g, last, s.yb);
        if (s.xb) prefetch_rows<4, P>(nl, g, last, s.xb);
      } else {
        prefetch_group<4, P>(nl, g, last, s.y);
      }
      prefetch_rows<4, P>(nl, g, last, s.x);
      __m256d U[P], dz[P], yn[P];
      load_rows<P>(s.x, nl.adj.data() + 4 * g, U);
      if (Extrap && s.xb) {
        __m256d B[P];
        load_rows<P>(s.xb, nl.adj.data() + 4 * g, B);
        for (int k = 0; k < P; ++k) U[k] = _mm256_add_pd(U[k], _mm256_mul_pd(vbeta, _mm256_sub_pd(U[k], B[k])));
      }
      const __m256d r = _mm256_loadu_pd(nl.rho.data() + 4 * g);
      const __m256d re = lane_mask4(nl.real[g]), fw = lane_mask4(nl.fwd[g]);
      const __m256d sgn = _mm256_blendv_pd(minus_one, one, fw);
      double* yg = s.y + 4 * P * g;
      for (int k = 0; k < P; ++k) {
        // dz = x_i - x_j in the edge's orientation (both differences,
        // selected, so that signed zeros match the scalar form).
        dz[k] = _mm256_blendv_pd(_mm256_sub_pd(U[k], V[k]), _mm256_sub_pd(V[k], U[k]), fw);
        __m256d Y;
        if constexpr (Extrap) {  // a + beta (a - b), as the blend pass
          const __m256d Ya = _mm256_loadu_pd(s.ya + 4 * P * g + 4 * k);
          Y = _mm256_add_pd(Ya, _mm256_mul_pd(vbeta, _mm256_sub_pd(Ya, _mm256_loadu_pd(s.yb + 4 * P * g + 4 * k))));
        } else {
          Y = _mm256_loadu_pd(yg + 4 * k);
        }
        A[k] = _mm256_add_pd(A[k], _mm256_and_pd(_mm256_mul_pd(sgn, _mm256_sub_pd(dz[k], Y)), re));
        yn[k] = _mm256_add_pd(_mm256_mul_pd(vkeep, Y), _mm256_mul_pd(vinvL, dz[k]));
      }
      const __m256d nv = _mm256_sqrt_pd(square_sum(yn, P));
      const __m256d pos = _mm256_cmp_pd(nv, zero, _CMP_GT_OQ);
      const __m256d f = _mm256_div_pd(r, nv);
      for (int k = 0; k < P; ++k) {  // P_sphere(0) = rho e_1
        const __m256d Yn = _mm256_blendv_pd(k == 0 ? r : zero, _mm256_mul_pd(yn[k], f), pos);
        if (Extrap && s.stream_y) {  // non-temporal, 16 bytes at a time (16-byte aligned storage)
          _mm_stream_pd(yg + 4 * k, _mm256_castpd256_pd128(Yn));
          _mm_stream_pd(yg + 4 * k + 2, _mm256_extractf128_pd(Yn, 1));
        } else {
          _mm256_storeu_pd(yg + 4 * k, Yn);
        }
      }
    }
    if (nl.anchor_off[c] != nl.anchor_off[c + 1]) {
      alignas(32) double tmp[4 * P], own[4 * P];
      store_own<P>(tmp, A, false);
      const double* xo = s.x + i0;
      if (Extrap && s.xb) {  // the extrapolated own rows
        store_own<P>(own, V, false);
        xo = own;
      }
      add_chunk_anchor_mm_terms<P>(prob, nl, c, xo, s.keep, s.invL, s.aw, tmp);
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

// mm_cost_chunk on a full chunk of 4 lanes: the scalar twin's arithmetic per
// lane (s and z2 from +0.0, then sqrt, sub, mul, add), with the lanes whose
// slot is not forward adding +0.0 (and-masked), which changes no sum that
// starts at +0.0. The MM kernel's row loads: the same lane order (0, 2, 1, 3).
template <int P, bool kY>
SNL_AVX2 unsigned mm_cost_chunk_avx2_p(const NodeLanes& nl, std::int64_t c, const double* x, const double* y,
                                       double* F, double* f) {
  const __m256i bits = _mm256_set_epi64x(8, 4, 2, 1);
  unsigned any = 0;
  __m256d XV[P];
  load_own<P>(x + std::size_t(nl.first[c]) * P, XV);
  __m256d SF = _mm256_setzero_pd(), Sf = _mm256_setzero_pd();
  const std::int64_t last = nl.groups() - 1;
  for (std::int64_t g = nl.group_off[c]; g < nl.group_off[c + 1]; ++g) {
    if (kY) prefetch_group<4, P>(nl, g, last, y);  // as the MM kernel (the chunks are visited in order)
    prefetch_rows<4, P>(nl, g, last, x);
    const unsigned mask = (nl.real[g] & nl.fwd[g]) & 15u;
    if (!mask) continue;
    any |= mask;
    const __m256d M =
        _mm256_castsi256_pd(_mm256_cmpeq_epi64(_mm256_and_si256(_mm256_set1_epi64x(mask), bits), bits));
    __m256d S = _mm256_setzero_pd(), Z2 = _mm256_setzero_pd(), U[P];
    load_rows<P>(x, &nl.adj[g * 4], U);
    for (int k = 0; k < P; ++k) {
      const __m256d Z = _mm256_sub_pd(XV[k], U[k]);
      if (kY) {
        const __m256d R = _mm256_sub_pd(Z, _mm256_loadu_pd(y + std::size_t(g * P + k) * 4));
        S = _mm256_add_pd(S, _mm256_mul_pd(R, R));
      }
      Z2 = _mm256_add_pd(Z2, _mm256_mul_pd(Z, Z));
    }
    const __m256d Mf = _mm256_sub_pd(_mm256_sqrt_pd(Z2), _mm256_loadu_pd(&nl.rho[g * 4]));
    SF = _mm256_add_pd(SF, _mm256_and_pd(S, M));
    Sf = _mm256_add_pd(Sf, _mm256_and_pd(_mm256_mul_pd(Mf, Mf), M));
  }
  _mm256_storeu_pd(F, _mm256_add_pd(_mm256_loadu_pd(F), SF));
  _mm256_storeu_pd(f, _mm256_add_pd(_mm256_loadu_pd(f), Sf));
  return any;
}

}  // namespace

unsigned mm_cost_chunk_avx2(const NodeLanes& nl, int p, std::int64_t c, const double* x, const double* y,
                            double* F, double* f) {
  if (!y) return p == 2 ? mm_cost_chunk_avx2_p<2, false>(nl, c, x, y, F, f) : mm_cost_chunk_avx2_p<3, false>(nl, c, x, y, F, f);
  return p == 2 ? mm_cost_chunk_avx2_p<2, true>(nl, c, x, y, F, f) : mm_cost_chunk_avx2_p<3, true>(nl, c, x, y, F, f);
}

const KernelTable kAvx2Kernels = {{relax_chunks_avx2<2>, relax_chunks_avx2<3>},
                                  {mm_chunks_avx2<2>, mm_chunks_avx2<3>},
                                  {mm_chunks_avx2<2, true>, mm_chunks_avx2<3, true>}};

}  // namespace snl::detail

#endif  // SNL_HAVE_AVX2_PATH
