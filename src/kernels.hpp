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
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "snl/problem.hpp"

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
void add_anchor_disk_terms(const LocalizationProblem& prob, LocalId v, const double* xv, double* acc);

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
  std::vector<std::uint8_t> has_anchor;   ///< some node of the chunk has anchor ranges
  std::vector<std::int64_t> group_off;    ///< chunk c: groups [group_off[c], group_off[c + 1])
  std::vector<LocalId> adj;               ///< lanes per group; entry q: neighbour of node first[c] + q
  std::vector<double> rho;                ///< lanes per group, in register lane order (lane_node)
  /// Per group, bit L for register lane L: the slot is real (not padding);
  /// the slot's edge is (owner, neighbour) in global-id order (MM's orientation).
  std::vector<std::uint8_t> real, fwd;
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

/// Whether the steps should write their node rows with non-temporal stores:
/// when `bytes` (the iterate arrays one step streams) exceed what a cache
/// keeps from one iteration to the next (16 MiB). 10M on 2 ranks: relaxation
/// 35-36 instead of 39-40 ms/iteration while the VM's bandwidth was low,
/// equal when it was high; at 100k (in cache) 17% slower, hence the size test
/// (docs/performance.md).
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
};
void mm_chunks(const LocalizationProblem& prob, const NodeLanes& nl, std::int64_t c0, std::int64_t c1,
               const MMStep& s);

}  // namespace snl::detail
