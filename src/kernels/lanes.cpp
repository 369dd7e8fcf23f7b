#include "kernels/kernels.hpp"

#include <algorithm>

namespace snl::detail {

std::int64_t NodeLanes::bytes() const {
  return static_cast<std::int64_t>(first.capacity() * sizeof(LocalId) + count.capacity() +
                                   group_off.capacity() * sizeof(std::int64_t) + adj.capacity() * sizeof(LocalId) +
                                   rho.capacity() * sizeof(double) + real.capacity() + fwd.capacity() +
                                   anchor_off.capacity() * sizeof(std::int64_t) + anchor_q.capacity());
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
  // The anchor pairs, in CSR order: the chunks cover the owned nodes in order.
  anchor_off.assign(std::size_t(chunks) + 1, aoff[n_owned]);
  anchor_q.resize(std::size_t(aoff[n_owned]));
  for (std::int64_t ch = 0; ch < chunks; ++ch) {
    anchor_off[std::size_t(ch)] = aoff[first[ch]];
    for (int q = 0; q < count[ch]; ++q)
      for (auto e = aoff[first[ch] + q]; e < aoff[first[ch] + q + 1]; ++e) anchor_q[std::size_t(e)] = std::uint8_t(q);
  }
}

std::shared_ptr<const NodeLanes> shared_lanes(const LocalizationProblem& prob) {
  std::shared_ptr<void>& slot = prob.derived_cache();
  if (!slot) {
    auto lanes = std::make_shared<NodeLanes>();
    lanes->build(prob);
    slot = lanes;
  }
  return std::static_pointer_cast<const NodeLanes>(slot);
}

}  // namespace snl::detail
