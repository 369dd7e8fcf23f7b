#pragma once
// Edge kernels of the synchronous methods (internal header).
//
// A node's update sums one term per incident edge in global-id order (so
// results do not depend on the number of ranks). The expensive part of a term
// is a sqrt and a division, which do not depend on the order; only the sum
// does. So the owned nodes are processed in blocks: first every slot (directed
// edge) of the block gets its term, in SIMD where the CPU has AVX2 (4 slots at a
// time, IEEE sqrt/div/mul/add and no FMA, so each term is bit-identical to the
// scalar one); then each node adds its terms in slot order, exactly as the
// plain loop did. The scalar term functions are kept as the portable path and
// as the twin the tests compare the SIMD path against.
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <vector>
#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include "snl/problem.hpp"

namespace snl::detail {

/// True when the AVX2 term functions are used: the CPU has AVX2 and the
/// environment does not say SNL_SIMD=0 (read once).
bool simd_enabled();
/// Forces the path (tests compare the two); returns the previous setting.
bool set_simd_enabled(bool on);

/// Disk residual e(x_v - x_u, rho) = max(0, 1 - rho/|z|) z (003, eq. 9/Alg. 1
/// step 7) for n slots: owner src[k], neighbour adj[k], range rho[k]; rows of
/// p = 2 or 3 coordinates in x; terms written to t[p k .. p k + p). SIMD for p = 2.
void disk_terms(int p, const LocalId* src, const LocalId* adj, const double* rho, const double* x, std::int64_t n,
                double* t);

/// MM slot update (000, eqs. 11-12) for n slots: with dz = x_i - x_j in the
/// edge's global orientation (fwd[k] != 0: i = owner, j = neighbour), the
/// x-step term sgn (dz - y) goes to t, and y <- P_sphere(rho)(keep y + invL dz)
/// in place (P_sphere(0) = rho e_1).
void mm_terms(int p, const LocalId* src, const LocalId* adj, const std::uint8_t* fwd, const double* rho,
              const double* x, double keep, double invL, std::int64_t n, double* y, double* t);

/// Anchor terms e(x_v - a_k, r_vk) of owned node v added to acc in anchor-id
/// order (scalar: a node has few).
void add_anchor_disk_terms(const LocalizationProblem& prob, LocalId v, const double* xv, double* acc);

/// Scratch of the block loop: owners and terms of up to `capacity` slots
/// (plus padding read by sum_terms). Sized once: no allocation in the loop.
struct SlotBlock {
  static constexpr int kPad = 16;
  std::int64_t capacity = 0;
  std::vector<LocalId> src;
  std::vector<double> t;
  void reserve(std::int64_t max_degree, int p) {
    capacity = std::max<std::int64_t>(2048, max_degree);
    src.assign(std::size_t(capacity + kPad), 0);
    t.assign(std::size_t(capacity + kPad) * p, 0.0);
  }
};

inline constexpr int kFixedTerms = 10;

/// acc[c] += t[k p + c] for k = 0 .. deg-1, in that order. Degrees vary from
/// node to node, so a loop over deg mispredicts its exit once per node; up to
/// kFixedTerms terms are summed instead with a fixed count, the terms past deg masked
/// to +0.0 (exact: acc starts at +0.0 and a sum that starts there is never
/// -0.0, so adding +0.0 changes no bit).
template <int P>
inline void sum_terms(const double* t, int deg, double* acc) {
  constexpr int kFixed = kFixedTerms;
  static_assert(kFixed <= SlotBlock::kPad, "padding");
  if (deg <= kFixed) {
    for (int k = 0; k < kFixed; ++k) {
      std::uint64_t mask = k < deg ? ~std::uint64_t(0) : 0;
      asm("" : "+r"(mask));  // keep it a mask (not a jump on deg)
      for (int c = 0; c < P; ++c) {
        std::uint64_t bits;
        std::memcpy(&bits, &t[k * P + c], 8);
        bits &= mask;
        double v;
        std::memcpy(&v, &bits, 8);
        acc[c] += v;
      }
    }
  } else {
    for (int k = 0; k < deg; ++k)
      for (int c = 0; c < P; ++c) acc[c] += t[k * P + c];
  }
}

#ifdef __SSE2__
/// Lane masks for sum_terms_2: row d holds d all-ones pairs, then zeros.
struct alignas(16) TermMasks {
  std::uint64_t m[kFixedTerms + 1][kFixedTerms][2] = {};
  constexpr TermMasks() {
    for (int d = 0; d <= kFixedTerms; ++d)
      for (int k = 0; k < kFixedTerms; ++k) m[d][k][0] = m[d][k][1] = k < d ? ~std::uint64_t(0) : 0;
  }
};
inline constexpr TermMasks kTermMasks{};

/// sum_terms for p = 2 with the pair of sums in one register (per-lane IEEE
/// adds: the same bits as the scalar form). The masks come from a table row,
/// so that the loop is a fixed run of load/and/add the optimiser cannot turn
/// back into a jump on deg.
inline __m128d sum_terms_2(const double* t, int deg) {
  __m128d acc = _mm_setzero_pd();
  if (deg <= kFixedTerms) {
    const double* mk = reinterpret_cast<const double*>(kTermMasks.m[deg]);
    for (int k = 0; k < kFixedTerms; ++k)
      acc = _mm_add_pd(acc, _mm_and_pd(_mm_loadu_pd(t + 2 * k), _mm_load_pd(mk + 2 * k)));
  } else {
    for (int k = 0; k < deg; ++k) acc = _mm_add_pd(acc, _mm_loadu_pd(t + 2 * k));
  }
  return acc;
}
#endif

/// Runs owned nodes [b, e) in blocks of at most blk.capacity slots: terms(v0,
/// v1, s0, n) fills blk.t for the slots [s0, s0 + n) of nodes [v0, v1) (blk.src
/// already holds their owners), then node(v, terms_of_v, degree) per node in order.
template <class Terms, class Node>
[[gnu::always_inline]] inline void for_node_blocks(const std::vector<std::int64_t>& off, LocalId b, LocalId e, SlotBlock& blk, Terms&& terms,
                     Node&& node, int p) {
  LocalId v0 = b;
  while (v0 < e) {
    LocalId v1 = v0 + 1;
    while (v1 < e && off[v1 + 1] - off[v0] <= blk.capacity) ++v1;
    const std::int64_t s0 = off[v0], n = off[v1] - s0;
    // Owner of each slot without a per-node loop of varying count (its exit
    // would mispredict once per node): each node writes its id into
    // kFixedTerms slots from its first one, and the next node overwrites what
    // lies past its end.
    LocalId* src = blk.src.data();
    for (LocalId v = v0; v < v1; ++v) {
      LocalId* q = src + (off[v] - s0);
      const std::int64_t d = off[v + 1] - off[v];
      if (d <= kFixedTerms) {
        for (int k = 0; k < kFixedTerms; ++k) q[k] = v;
      } else {
        for (std::int64_t k = 0; k < d; ++k) q[k] = v;
      }
    }
    terms(v0, v1, s0, n);
    for (LocalId v = v0; v < v1; ++v)
      node(v, blk.t.data() + std::size_t(off[v] - s0) * p, static_cast<int>(off[v + 1] - off[v]));
    v0 = v1;
  }
}

}  // namespace snl::detail
