#include "kernels.hpp"

#include <cmath>
#include <cstdlib>
#include <cstring>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define SNL_HAVE_AVX2_PATH 1
#include <immintrin.h>
#endif

namespace snl::detail {

namespace {

bool detect_simd() {
  const char* env = std::getenv("SNL_SIMD");
  if (env && std::strcmp(env, "0") == 0) return false;
#ifdef SNL_HAVE_AVX2_PATH
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2");
#else
  return false;
#endif
}

bool g_simd = detect_simd();

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
  double s = 0;
  for (int c = 0; c < P; ++c) s += yn[c] * yn[c];
  const double nv = std::sqrt(s);
  if (nv > 0) {
    const double f = rho / nv;
    for (int c = 0; c < P; ++c) y[c] = yn[c] * f;
  } else {  // P_sphere(0) = rho e_1
    y[0] = rho;
    for (int c = 1; c < P; ++c) y[c] = 0;
  }
}

template <int P>
void disk_terms_scalar(const LocalId* src, const LocalId* adj, const double* rho, const double* x, std::int64_t n,
                       double* t) {
  for (std::int64_t k = 0; k < n; ++k)
    disk_term<P>(x + std::size_t(src[k]) * P, x + std::size_t(adj[k]) * P, rho[k], t + P * k);
}

template <int P>
void mm_terms_scalar(const LocalId* src, const LocalId* adj, const std::uint8_t* fwd, const double* rho,
                     const double* x, double keep, double invL, std::int64_t n, double* y, double* t) {
  for (std::int64_t k = 0; k < n; ++k)
    mm_term<P>(x + std::size_t(src[k]) * P, x + std::size_t(adj[k]) * P, fwd[k] != 0, rho[k], keep, invL, y + P * k,
               t + P * k);
}

#ifdef SNL_HAVE_AVX2_PATH
// ---- AVX2: 4 slots at a time. Rows are loaded as (x, y) pairs; after the
// unpack the lanes hold slots in the order (0, 2, 1, 3), so per-slot scalars
// (rho, fwd) are permuted the same way and the terms are re-interleaved on
// the way out. Only IEEE add/sub/mul/div/sqrt: no FMA (not enabled for these
// functions), so every lane equals the scalar result bit for bit. They take
// whole groups of 4 slots and return; the dispatcher runs the scalar twin on
// the rest. (A tail call from here into the scalar code got no vzeroupper from
// GCC, and the dirty upper ymm state slowed the caller's SSE node phase by
// ~40%: docs/performance.md.)
#define SNL_AVX2 __attribute__((target("avx2")))

SNL_AVX2 inline void load_rows(const double* x, const LocalId* idx, __m256d* X, __m256d* Y) {
  const __m256d a = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(x + std::size_t(idx[0]) * 2)),
                                         _mm_loadu_pd(x + std::size_t(idx[1]) * 2), 1);
  const __m256d b = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(x + std::size_t(idx[2]) * 2)),
                                         _mm_loadu_pd(x + std::size_t(idx[3]) * 2), 1);
  *X = _mm256_unpacklo_pd(a, b);  // (x0, x2, x1, x3)
  *Y = _mm256_unpackhi_pd(a, b);
}

SNL_AVX2 inline __m256d load_scalars_0213(const double* r) {
  return _mm256_permute4x64_pd(_mm256_loadu_pd(r), _MM_SHUFFLE(3, 1, 2, 0));
}

SNL_AVX2 inline void store_pairs(double* t, __m256d X, __m256d Y) {
  _mm256_storeu_pd(t, _mm256_unpacklo_pd(X, Y));      // (x0, y0, x1, y1)
  _mm256_storeu_pd(t + 4, _mm256_unpackhi_pd(X, Y));  // (x2, y2, x3, y3)
}

SNL_AVX2 void disk_terms_avx2(const LocalId* src, const LocalId* adj, const double* rho, const double* x,
                              std::int64_t n, double* t) {
  const __m256d one = _mm256_set1_pd(1.0);
  std::int64_t k = 0;
  for (; k + 4 <= n; k += 4) {
    __m256d VX, VY, UX, UY;
    load_rows(x, src + k, &VX, &VY);
    load_rows(x, adj + k, &UX, &UY);
    const __m256d r = load_scalars_0213(rho + k);
    const __m256d z0 = _mm256_sub_pd(VX, UX), z1 = _mm256_sub_pd(VY, UY);
    const __m256d s = _mm256_add_pd(_mm256_mul_pd(z0, z0), _mm256_mul_pd(z1, z1));
    const __m256d nz = _mm256_sqrt_pd(s);
    const __m256d mask = _mm256_cmp_pd(nz, r, _CMP_GT_OQ);
    const __m256d c = _mm256_sub_pd(one, _mm256_div_pd(r, nz));
    store_pairs(t + 2 * k, _mm256_and_pd(_mm256_mul_pd(c, z0), mask), _mm256_and_pd(_mm256_mul_pd(c, z1), mask));
  }
}

SNL_AVX2 void mm_terms_avx2(const LocalId* src, const LocalId* adj, const std::uint8_t* fwd, const double* rho,
                            const double* x, double keep, double invL, std::int64_t n, double* y, double* t) {
  const __m256d one = _mm256_set1_pd(1.0), minus_one = _mm256_set1_pd(-1.0), zero = _mm256_setzero_pd();
  const __m256d vkeep = _mm256_set1_pd(keep), vinvL = _mm256_set1_pd(invL);
  std::int64_t k = 0;
  for (; k + 4 <= n; k += 4) {
    __m256d VX, VY, UX, UY;
    load_rows(x, src + k, &VX, &VY);
    load_rows(x, adj + k, &UX, &UY);
    const __m256d r = load_scalars_0213(rho + k);
    // fwd bytes -> 64-bit lane masks in the (0, 2, 1, 3) order.
    std::int32_t f4;
    std::memcpy(&f4, fwd + k, 4);
    const __m256i fw = _mm256_permute4x64_epi64(_mm256_cvtepu8_epi64(_mm_cvtsi32_si128(f4)), _MM_SHUFFLE(3, 1, 2, 0));
    const __m256d fmask = _mm256_castsi256_pd(_mm256_cmpgt_epi64(fw, _mm256_setzero_si256()));
    const __m256d sgn = _mm256_blendv_pd(minus_one, one, fmask);
    // dz = x_i - x_j in the edge's orientation (computed both ways and
    // selected, so signed zeros match the scalar form too).
    const __m256d dz0 = _mm256_blendv_pd(_mm256_sub_pd(UX, VX), _mm256_sub_pd(VX, UX), fmask);
    const __m256d dz1 = _mm256_blendv_pd(_mm256_sub_pd(UY, VY), _mm256_sub_pd(VY, UY), fmask);
    __m256d YX, YY;
    {
      const __m256d a = _mm256_loadu_pd(y + 2 * k), b = _mm256_loadu_pd(y + 2 * k + 4);
      YX = _mm256_unpacklo_pd(a, b);
      YY = _mm256_unpackhi_pd(a, b);
    }
    store_pairs(t + 2 * k, _mm256_mul_pd(sgn, _mm256_sub_pd(dz0, YX)), _mm256_mul_pd(sgn, _mm256_sub_pd(dz1, YY)));
    __m256d y0 = _mm256_add_pd(_mm256_mul_pd(vkeep, YX), _mm256_mul_pd(vinvL, dz0));
    __m256d y1 = _mm256_add_pd(_mm256_mul_pd(vkeep, YY), _mm256_mul_pd(vinvL, dz1));
    const __m256d s = _mm256_add_pd(_mm256_mul_pd(y0, y0), _mm256_mul_pd(y1, y1));
    const __m256d nv = _mm256_sqrt_pd(s);
    const __m256d pos = _mm256_cmp_pd(nv, zero, _CMP_GT_OQ);
    const __m256d f = _mm256_div_pd(r, nv);
    y0 = _mm256_blendv_pd(r, _mm256_mul_pd(y0, f), pos);
    y1 = _mm256_blendv_pd(zero, _mm256_mul_pd(y1, f), pos);
    store_pairs(y + 2 * k, y0, y1);
  }
}
#endif

}  // namespace

bool simd_enabled() { return g_simd; }

bool set_simd_enabled(bool on) {
  const bool old = g_simd;
#ifdef SNL_HAVE_AVX2_PATH
  g_simd = on && __builtin_cpu_supports("avx2");
#else
  (void)on;
  g_simd = false;
#endif
  return old;
}

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

void disk_terms(int p, const LocalId* src, const LocalId* adj, const double* rho, const double* x, std::int64_t n,
                double* t) {
  if (p == 3) return disk_terms_scalar<3>(src, adj, rho, x, n, t);
#ifdef SNL_HAVE_AVX2_PATH
  if (g_simd) {
    const std::int64_t k = n & ~std::int64_t(3);
    disk_terms_avx2(src, adj, rho, x, k, t);
    return disk_terms_scalar<2>(src + k, adj + k, rho + k, x, n - k, t + 2 * k);
  }
#endif
  disk_terms_scalar<2>(src, adj, rho, x, n, t);
}

void mm_terms(int p, const LocalId* src, const LocalId* adj, const std::uint8_t* fwd, const double* rho,
              const double* x, double keep, double invL, std::int64_t n, double* y, double* t) {
  if (p == 3) return mm_terms_scalar<3>(src, adj, fwd, rho, x, keep, invL, n, y, t);
#ifdef SNL_HAVE_AVX2_PATH
  if (g_simd) {
    const std::int64_t k = n & ~std::int64_t(3);
    mm_terms_avx2(src, adj, fwd, rho, x, keep, invL, k, y, t);
    return mm_terms_scalar<2>(src + k, adj + k, fwd + k, rho + k, x, keep, invL, n - k, y + 2 * k, t + 2 * k);
  }
#endif
  mm_terms_scalar<2>(src, adj, fwd, rho, x, keep, invL, n, y, t);
}

}  // namespace snl::detail
