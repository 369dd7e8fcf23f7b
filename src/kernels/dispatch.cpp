// CPU dispatch of the node kernels: which instruction set runs (the CPU and
// SNL_SIMD), the lane width fixed at start-up, and relax_chunks / mm_chunks,
// which send full chunks to the SIMD table and the rest to the scalar twins.
#include <cstdlib>
#include <cstring>
#include <type_traits>

#include "kernels/simd_common.hpp"

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

// The SIMD table for a layout of `lanes` lanes, if the CPU and the setting
// allow it; null: the scalar twins only.
const KernelTable* simd_table(int lanes) {
#ifdef SNL_HAVE_AVX2_PATH
  if (g_level == 2 && lanes == 8) return &kAvx512Kernels;
  if (g_level >= 1 && lanes == 4) return &kAvx2Kernels;
#endif
  (void)lanes;
  return nullptr;
}

// Chunks [c0, c1): the full ones through the SIMD kernel of the layout's lane
// width where the CPU allows it, the rest (each part's partial last chunk;
// everything without SIMD) through the scalar twin. Fn is KernelTable::relax
// or KernelTable::mm. A range over both parts is run part by part: the
// interior's last chunk may be partial, and a SIMD pass over it would step
// the next nodes too (their anchor variables a second time, as the extra
// lanes read the rows that follow).
template <auto Fn, class Step>
void run_chunks(const LocalizationProblem& prob, const NodeLanes& nl, std::int64_t c0, std::int64_t c1,
                const Step& s) {
  if (c0 >= c1) return;
  if (c0 < nl.split && nl.split < c1) {
    run_chunks<Fn>(prob, nl, c0, nl.split, s);
    run_chunks<Fn>(prob, nl, nl.split, c1, s);
    return;
  }
  if (prob.dim() == 1) {  // p = 1: the scalar twin only (simd_common.hpp)
    if constexpr (std::is_same_v<Step, RelaxStep>)
      kScalarRelax1(prob, nl, c0, c1, s);
    else
      kScalarMM1(prob, nl, c0, c1, s);
    return;
  }
  const std::int64_t full = nl.count[c1 - 1] == nl.lanes ? c1 : c1 - 1;
  const int d = prob.dim() == 2 ? 0 : 1;  // p = 2, else p = 3
  if (const KernelTable* simd = simd_table(nl.lanes)) {
    (simd->*Fn)[d](prob, nl, c0, full, s);
    c0 = full;
  }
  (kScalarKernels.*Fn)[d](prob, nl, c0, c1, s);
}

}  // namespace

bool simd_enabled() { return g_level > 0; }

bool set_simd_enabled(bool on) {
  const bool old = g_level > 0;
  g_level = on ? g_top : 0;
  return old;
}

int node_lanes() { return g_lanes; }

const char* simd_name() { return g_level == 2 ? "avx512" : g_level == 1 ? "avx2" : "scalar"; }

void relax_chunks(const LocalizationProblem& prob, const NodeLanes& nl, std::int64_t c0, std::int64_t c1,
                  const RelaxStep& s) {
  run_chunks<&KernelTable::relax>(prob, nl, c0, c1, s);
}

void mm_chunks(const LocalizationProblem& prob, const NodeLanes& nl, std::int64_t c0, std::int64_t c1,
               const MMStep& s) {
  if (s.ya) {
    if (s.cost_F) {  // the chunks whose costs the step does not sum itself (the AVX-512 kernel's full ones)
#ifdef SNL_HAVE_AVX2_PATH
      const bool fused = simd_table(nl.lanes) == &kAvx512Kernels && prob.dim() >= 2;
#else
      const bool fused = false;
#endif
      const int C = nl.lanes;
      for (std::int64_t c = c0; c < c1; ++c) {
        if (fused && nl.count[c] == C) continue;
        const std::size_t q = std::size_t(c - s.cost_base);
        std::fill(s.cost_F + C * q, s.cost_F + C * (q + 1), 0.0);
        std::fill(s.cost_f + C * q, s.cost_f + C * (q + 1), 0.0);
        s.cost_any[q] = mm_cost_chunk(nl, prob.dim(), c, s.x, s.ya, s.cost_F + C * q, s.cost_f + C * q);
      }
    }
    run_chunks<&KernelTable::mm_extrapolated>(prob, nl, c0, c1, s);
  } else
    run_chunks<&KernelTable::mm>(prob, nl, c0, c1, s);
}

unsigned mm_cost_chunk(const NodeLanes& nl, int p, std::int64_t c, const double* x, const double* y, double* F,
                       double* f) {
#ifdef SNL_HAVE_AVX2_PATH
  // The SIMD form of the layout's table (simd_table's rule), on full chunks.
  if (const KernelTable* simd = simd_table(nl.lanes); simd && p >= 2 && nl.count[c] == nl.lanes)
    return (simd == &kAvx512Kernels ? mm_cost_chunk_avx512 : mm_cost_chunk_avx2)(nl, p, c, x, y, F, f);
#endif
  return mm_cost_chunk_scalar(nl, p, c, x, y, F, f);
}

}  // namespace snl::detail
