#pragma once
// Node kernels of the synchronous methods (internal header).
//
// A node's update sums one term per incident edge in global-id order (so
// results do not depend on the number of ranks). The owned nodes are taken C
// at a time, one per SIMD lane (C = 8 with AVX-512, 4 with AVX2; NodeLanes),
// and each lane adds its own node's terms in that order: IEEE
// add/sub/mul/div/sqrt and no FMA, so every lane equals the scalar twin bit
// for bit. The SIMD kernels serve p = 2 and p = 3; the scalar twins are the
// portable path and what the tests compare the SIMD paths against.
// docs/performance.md has the measurements behind this layout.
//
// This header is the interface the solvers use. The implementation is split
// by concern: lanes.cpp (NodeLanes), level_plan.cpp (LevelPlan; run_levels
// is below), dispatch.cpp (CPU detection, SNL_SIMD, relax_chunks/mm_chunks),
// scalar.cpp, avx2.cpp, avx512.cpp (the kernels of each instruction set),
// with terms.hpp and simd_common.hpp as their private headers.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "snl/graph/halo.hpp"
#include "snl/problem/problem.hpp"

namespace snl::detail {

/// v <- P_sphere(rho)(v) = rho v / |v|, and rho e_1 for v = 0 (spec convention).
template <int P>
inline void project_sphere(double rho, double* v) {
  double s = 0;
  for (int c = 0; c < P; ++c) s += v[c] * v[c];
  const double nv = std::sqrt(s);
  if (nv > 0) {
    const double f = rho / nv;
    for (int c = 0; c < P; ++c) v[c] *= f;
  } else {
    v[0] = rho;
    for (int c = 1; c < P; ++c) v[c] = 0;
  }
}

/// True when the SIMD kernels are used: the CPU has AVX2 (or AVX-512) and the
/// environment does not say SNL_SIMD=0 (read once).
bool simd_enabled();
/// Forces the path (tests compare the two); returns the previous setting.
bool set_simd_enabled(bool on);

/// Anchor terms e(x_v - a_k, r_vk) of owned node v added to acc in anchor-id
/// order (scalar: a node has few).
/// With `ml`, the ML cost's anchor gradient terms instead (disk_term).
void add_anchor_disk_terms(const LocalizationProblem& prob, LocalId v, const double* xv, double* acc,
                           bool ml = false);

/// SIMD lanes of the node-lane kernels: 8 where the CPU has AVX-512F/DQ, else
/// 4. Fixed at start-up from the CPU and SNL_SIMD (0, avx2, avx512), not by
/// set_simd_enabled: the layout, and with it every rounding of the lane sums,
/// is then the same on the SIMD and on the scalar path.
int node_lanes();
/// The largest value node_lanes() returns (size of per-lane scratch).
inline constexpr int kMaxLanes = 8;
/// The instruction set the kernels use now: "avx512", "avx2" or "scalar".
const char* simd_name();

/// Owned nodes in chunks of C = lanes consecutive nodes with their slots
/// interleaved (ELL per chunk, i.e. SELL-C-1 of Kreutzer et al. 2014): group
/// g of a chunk holds the g-th neighbour of each of its C nodes, so that the
/// C nodes' sums run side by side, one node per SIMD lane, each still adding
/// its own terms in its own slot (global-id) order: the same bits as a loop
/// over the node's slots. A chunk is padded to its largest degree with the
/// node itself at range 1 (z = 0 is inside the disk: the term is +0.0, which
/// changes no sum). The interior [0, num_interior) and the boundary nodes are
/// chunked separately (the halo overlap needs the split); only the last chunk
/// of each part can be partial.
struct NodeLanes {
  int lanes = 4;
  std::int64_t split = 0;                 ///< chunks [0, split) interior, [split, size) boundary
  std::vector<LocalId> first;             ///< chunk c: nodes [first[c], first[c] + count[c])
  std::vector<std::uint8_t> count;
  std::vector<std::int64_t> group_off;    ///< chunk c: groups [group_off[c], group_off[c + 1])
  std::vector<LocalId> adj;               ///< lanes per group; entry q: neighbour of node first[c] + q
  std::vector<double> rho;                ///< lanes per group, in register lane order (lane_node)
  /// Per group, bit L for register lane L: the slot is real (not padding);
  /// the slot's edge is (owner, neighbour) in global-id order (MM's orientation).
  std::vector<std::uint8_t> real, fwd;
  /// Chunk c's anchor pairs are [anchor_off[c], anchor_off[c + 1]) of the
  /// problem's anchor CSR (the chunks hold consecutive nodes); anchor_q: per
  /// pair, its node's offset in the chunk. The kernels read them in sequence
  /// instead of the anchor offsets of every node.
  std::vector<std::int64_t> anchor_off;
  std::vector<std::uint8_t> anchor_q;
  LocalId n_interior = 0;
  /// Node offset held by register lane L after the pairwise unpack of row
  /// loads: (0, C/2, 1, C/2 + 1, ...); lane_of_node is its inverse.
  static int lane_node(int L, int C) { return (L & 1) ? C / 2 + L / 2 : L / 2; }
  static int lane_of_node(int q, int C) { return q < C / 2 ? 2 * q : 2 * (q - C / 2) + 1; }
  std::int64_t size() const { return static_cast<std::int64_t>(first.size()); }
  std::int64_t groups() const { return group_off.empty() ? 0 : group_off.back(); }
  /// Index of coordinate c of slot k of owned node v in a per-slot array of
  /// P-rows in lane layout: [(group P + c) lanes + register lane].
  std::size_t at(LocalId v, std::int64_t k, int P, int c) const {
    const std::int64_t ch = v < n_interior ? v / lanes : split + (v - n_interior) / lanes;
    const int L = lane_of_node(static_cast<int>(v - first[ch]), lanes);
    return std::size_t((group_off[ch] + k) * P + c) * lanes + L;
  }
  std::int64_t bytes() const;
  void build(const LocalizationProblem& prob);
};

/// Temporal blocking of a Jacobi step over the chunks of a NodeLanes layout
/// (plan once, run every pass): up to `levels` iterations per pass over
/// memory, so that the edge arrays a chunk streams are reused from cache by
/// the following levels. Level j (iteration j of the pass) reads the rows of
/// buffer j % 2 and writes buffer (j + 1) % 2; each node does exactly the
/// arithmetic of a plain iteration, so the iterates are the same bits.
///
/// Schedule (run_levels): a wavefront over the interior chunks, level j
/// trailing level j - 1 by `skew` chunks, the largest chunk distance of any
/// edge between two chunks that are not next to the boundary. A chunk within
/// chunk-graph distance j of a boundary chunk (depth <= j) is not safe at
/// level j in the wavefront (its neighbours' level j - 1 may wait for the
/// halo); it runs after the wavefront, level by level, each level's halo
/// exchange overlapping its interior part. Writing x(j+1) over x(j-1) is safe
/// by the same conditions: every reader of x(j-1)[c] is a neighbour's level
/// j - 1, already done.
struct LevelPlan {
  std::int64_t skew = 0;             ///< chunks between consecutive levels of the wavefront
  std::int64_t block = 16;           ///< chunks per level and wavefront stage (tests vary it)
  std::vector<std::uint8_t> depth;   ///< per chunk: distance to a boundary chunk, capped at max(levels, 2)
  /// Per level j: runs [b, e) of interior chunks with depth <= j, ascending.
  std::vector<std::vector<std::pair<std::int64_t, std::int64_t>>> deferred;
  void build(const LocalizationProblem& prob, const NodeLanes& nl, int levels);
  std::int64_t bytes() const;
};

/// One pass of n iterations (n <= the levels the plan was built for, the size
/// of `deferred`): step(j, c0, c1) runs level j on chunks [c0, c1).
/// buf[j % 2] is the row array level j reads; its ghost rows are exchanged
/// here (level 0's over the whole wavefront). With n = 1 this is the plain
/// iteration: halo begin -> interior chunks -> halo end -> boundary.
template <class Step>
void run_levels(const LevelPlan& lp, const NodeLanes& nl, int n, HaloPlan& halo, double* const buf[2], int p,
                Step&& step) {
  const std::int64_t split = nl.split;
  // Chunks per level and stage: the window the levels share is (n - 1) skew
  // + block chunks.
  const std::int64_t block = n == 1 ? std::max<std::int64_t>(split, 1) : lp.block;
  halo.begin(buf[0], p);
  for (std::int64_t t = 0; split > 0; ++t) {
    for (int j = 0; j < n; ++j) {
      const std::int64_t lo = std::max<std::int64_t>(0, t * block - j * lp.skew);
      const std::int64_t hi = std::min(split, (t + 1) * block - j * lp.skew);
      for (std::int64_t c = lo; c < hi;) {  // runs of chunks deeper than j
        while (c < hi && lp.depth[c] <= j) ++c;
        std::int64_t e = c;
        while (e < hi && lp.depth[e] > j) ++e;
        if (c < e) step(j, c, e);
        c = e;
      }
    }
    if ((t + 1) * block - (n - 1) * lp.skew >= split) break;
  }
  halo.end(buf[0], p);
  step(0, split, nl.size());
  for (int j = 1; j < n; ++j) {
    halo.begin(buf[j & 1], p);
    for (const auto& [b, e] : lp.deferred[j]) step(j, b, e);
    halo.end(buf[j & 1], p);
    step(j, split, nl.size());
  }
}

/// The problem's lane layout, built once and shared by every phase of a solve
/// (LocalizationProblem::derived_cache): the phases' kernels read the same
/// layout, which at 10^7 sensors is a gigabyte per rank to build and fault in.
std::shared_ptr<const NodeLanes> shared_lanes(const LocalizationProblem& prob);

/// Whether the steps should write their node rows with non-temporal stores:
/// when `bytes` (the iterate arrays one step streams) exceed what a cache
/// keeps from one iteration to the next (16 MiB): below that the rows stay in
/// cache, where non-temporal stores would evict them.
inline bool stream_rows(std::size_t bytes) { return bytes > (std::size_t(16) << 20); }

/// out[j] = sum over the lanes of norms[j C .. j C + C) in lane order, j < n:
/// the steps' per-lane norm sums, combined the same way on every path.
inline void sum_lanes(const double* norms, int C, int n, double* out) {
  for (int j = 0; j < n; ++j) {
    out[j] = 0;
    for (int q = 0; q < C; ++q) out[j] += norms[j * C + q];
  }
}

/// One relaxation step (003, Alg. 1 steps 7-8 and the extrapolation) on the
/// chunks [c0, c1): per node v, g = sum of the disk residuals e(w_v - w_u,
/// rho) over its slots, then over its anchors; x(k) = w - g/L into xn, w(k+1)
/// = x(k) + beta (x(k) - x(k-1)) into wn. norms[0 .. 3C): per lane q (node
/// offset in its chunk) the running sums ||x(k) - x(k-1)||^2, ||x(k)||^2, ||g||^2.
struct RelaxStep {
  const double* w;
  const double* x;
  double* xn;
  double* wn;
  double L, beta;
  double* norms;
  bool stream = false;  ///< non-temporal stores of xn and wn (stream_rows; p = 2 only)
  /// The ML cost's gradient instead of f_hat's: every term (1 - rho/|z|) z
  /// with |z| > 0 (ml-agd, relaxation.cpp).
  bool ml = false;
  /// Per owned node 1/D_v: x(k) = w - g * inv_d[v] instead of w - g/L
  /// (ml-agd's diagonal majorizer).
  const double* inv_d = nullptr;
  /// With inv_d: ml-agd's restart terms q_v = sum_c (w - x(k))_c (x(k) -
  /// x(k-1))_c / inv_d[v] (nodes with inv_d[v] > 0), added per lane into
  /// restart[0 .. C) and their absolute values into restart[C .. 2C), in no
  /// fixed order (relaxation.cpp bounds the rounding).
  double* restart = nullptr;
  /// Where set, the gradient g per owned node is stored here too, after xn
  /// and wn (the same array as both is allowed: g is what it then holds).
  double* g = nullptr;
};
void relax_chunks(const LocalizationProblem& prob, const NodeLanes& nl, std::int64_t c0, std::int64_t c1,
                  const RelaxStep& s);

/// One MM step (000, Alg. 1, eqs. 11-13) on the chunks [c0, c1): per node
/// v, with dz = x_i - x_j in each edge's orientation, the x-step sum of sgn
/// (dz - y_e) over its slots, then over its anchors (with their w updates),
/// x(t+1) = x - invL sum into xn; y_e <- P_sphere(rho)(keep y_e + invL dz)
/// in place (lane layout, NodeLanes::at; P_sphere(0) = rho e_1). norms[0 ..
/// 2C): per lane ||x(t+1) - x(t)||^2, ||x(t+1)||^2.
struct MMStep {
  const double* x;
  double* xn;
  double* y;
  double* aw;
  double keep, invL;
  double* norms;
  bool stream = false;  ///< non-temporal stores of xn (stream_rows; p = 2 only)
  /// mm-accel's extrapolated edge variables, read on the fly: where ya is
  /// set, each real slot's y_e is taken as ya + beta (ya - yb) (the same
  /// arithmetic as a separate blend pass, so the same bits) and the step's
  /// result is written to y. Every kernel table (scalar, AVX2, AVX-512) has it.
  const double* ya = nullptr;
  const double* yb = nullptr;
  double beta = 0;
  /// With ya: where xb is set, every row the step reads (the node's own and
  /// its neighbours') is x + beta (x - xb), formed on the fly the same way
  /// (mm-accel's extrapolated point without a buffer or a pass of its own).
  const double* xb = nullptr;
  /// Non-temporal stores of y where ya is set (the step writes a buffer it
  /// does not read: without them every line of y is read for ownership
  /// first, a third more traffic on y; stream_rows of y's bytes).
  bool stream_y = false;
  /// With ya: where cost_F is set, each chunk c's mm_cost_chunk(nl, p, c, x,
  /// ya) as well (the candidate's acceptance costs, of x and ya themselves,
  /// not of their extrapolation): its F and f lane sums into cost_F and
  /// cost_f at [(c - cost_base) C, + C) and its lanes mask into
  /// cost_any[c - cost_base]. The AVX-512 kernel sums them from the rows and
  /// edge variables its step loads anyway (one pass instead of two); the
  /// other paths call mm_cost_chunk. The same bits either way.
  double* cost_F = nullptr;
  double* cost_f = nullptr;
  unsigned* cost_any = nullptr;
  std::int64_t cost_base = 0;
};
void mm_chunks(const LocalizationProblem& prob, const NodeLanes& nl, std::int64_t c0, std::int64_t c1,
               const MMStep& s);

/// mm-accel's acceptance costs (src/solvers/mm_accel.cpp) on chunk c: per
/// register lane L, the sums over its node's forward slots (MM's
/// orientation, so that each edge counts once over all ranks), in slot
/// order, of |x_v - x_u - y_e|^2 into F[L] and of (|x_v - x_u| - rho_e)^2
/// into f[L]: the edge terms of 000's surrogate (eq. 2) and of the ML cost,
/// before their factor 1/2. F and f hold C zeros on entry. Returns the lanes
/// with at least one forward slot. A full chunk (p = 2, 3) takes the SIMD
/// path of its layout where simd_enabled() (AVX2 for 4 lanes, AVX-512 for
/// 8); every lane equals the scalar twin bit for bit. y = nullptr: f alone
/// (F gets +0.0; the solver's bounded gradient test).
unsigned mm_cost_chunk(const NodeLanes& nl, int p, std::int64_t c, const double* x, const double* y, double* F,
                       double* f);

}  // namespace snl::detail
