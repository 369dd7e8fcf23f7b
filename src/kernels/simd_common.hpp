#pragma once
// What the kernel files share (internal to src/kernels/): the function tables
// through which dispatch.cpp reaches each instruction set's chunk loops, and
// the x86 helpers of the AVX2 and AVX-512 kernels (prefetch, row stores).
//
// Files: dispatch.cpp (CPU detection, SNL_SIMD, relax_chunks / mm_chunks),
// scalar.cpp (the scalar twins), avx2.cpp and avx512.cpp (the SIMD kernels),
// terms.hpp (the per-edge terms they share), lanes.cpp (NodeLanes),
// level_plan.cpp (LevelPlan; run_levels is in kernels.hpp).
#include <algorithm>
#include <cstdint>

#include "kernels/kernels.hpp"

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define SNL_HAVE_AVX2_PATH 1
#include <immintrin.h>
#endif

namespace snl::detail {

/// The chunk loops of one instruction set, indexed by p - 2: each runs its
/// step on chunks [c0, c1). The SIMD tables take full chunks only.
using RelaxChunksFn = void (*)(const LocalizationProblem&, const NodeLanes&, std::int64_t, std::int64_t,
                               const RelaxStep&);
using MMChunksFn = void (*)(const LocalizationProblem&, const NodeLanes&, std::int64_t, std::int64_t, const MMStep&);
struct KernelTable {
  RelaxChunksFn relax[2];
  MMChunksFn mm[2];
  MMChunksFn mm_extrapolated[2];  ///< MMStep::ya set
};

extern const KernelTable kScalarKernels;  // scalar.cpp
/// p = 1 (the 003 Fig. 2 networks): scalar only, no SIMD table (a 1-D run is
/// small; the lane layout is the same, so ranks still agree bit for bit).
extern const RelaxChunksFn kScalarRelax1;  // scalar.cpp
extern const MMChunksFn kScalarMM1;        // scalar.cpp
/// mm_cost_chunk's twins: scalar (any p, any chunk; scalar.cpp), AVX2 (p =
/// 2, 3, full chunks of 4 lanes; avx2.cpp) and AVX-512 (p = 2, 3, full chunks
/// of 8 lanes; avx512.cpp).
unsigned mm_cost_chunk_scalar(const NodeLanes& nl, int p, std::int64_t c, const double* x, const double* y,
                              double* F, double* f);
unsigned mm_cost_chunk_avx2(const NodeLanes& nl, int p, std::int64_t c, const double* x, const double* y,
                            double* F, double* f);
unsigned mm_cost_chunk_avx512(const NodeLanes& nl, int p, std::int64_t c, const double* x, const double* y,
                              double* F, double* f);

#ifdef SNL_HAVE_AVX2_PATH
extern const KernelTable kAvx2Kernels;    // avx2.cpp, 4 lanes
extern const KernelTable kAvx512Kernels;  // avx512.cpp, 8 lanes

// Software prefetch of the lane arrays a fixed distance ahead (groups at
// kPrefetchBytes of ranges): the arrays are read in order, but the hardware
// prefetcher alone leaves these sqrt/div-heavy loops waiting on memory. The index is clamped to the last
// group so that no address past the arrays is formed. EdgeP > 0: also MM's
// edge rows y (EdgeP doubles per lane and group). Always inlined: GCC
// takes a function that only prefetches for one without side effects and
// drops calls to it that it did not inline (it did so in the MM kernels).
inline constexpr std::int64_t kPrefetchBytes = 2048;
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
// keeps 2D neighbours close (the gathers hit L1/L2, where these prefetches
// only cost), but a 3D BFS level of 1M sensors spans ~10^4 rows, so the
// gathers wait on L3.
inline constexpr std::int64_t kRowPrefetchGroups = 16;
template <int C, int P>
__attribute__((always_inline)) inline void prefetch_rows(const NodeLanes& nl, std::int64_t g, std::int64_t last,
                                                         const double* x) {
  if constexpr (P == 3) {
    const LocalId* idx = nl.adj.data() + C * std::min(g + kRowPrefetchGroups, last);
    for (int q = 0; q < C; ++q) _mm_prefetch(reinterpret_cast<const char*>(x + std::size_t(idx[q]) * P), _MM_HINT_T0);
  }
}

// Coordinate registers, stored lane by lane, back to the P-rows of the
// chunk's nodes 0..C-1 at t (the p = 3 row store of both widths).
template <int P, int C>
inline void rows_from_lanes(double* t, const double (&lanes)[P][C]) {
  for (int q = 0; q < C; ++q)
    for (int k = 0; k < P; ++k) t[P * q + k] = lanes[k][NodeLanes::lane_of_node(q, C)];
}

// Row offsets 0..7, for loading a chunk's own p = 3 rows with the neighbour loads.
inline constexpr LocalId kIota[8] = {0, 1, 2, 3, 4, 5, 6, 7};

#endif  // SNL_HAVE_AVX2_PATH

}  // namespace snl::detail
