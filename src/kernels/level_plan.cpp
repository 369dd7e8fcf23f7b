#include "kernels/kernels.hpp"

#include <algorithm>
#include <cstdlib>

namespace snl::detail {

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

}  // namespace snl::detail
