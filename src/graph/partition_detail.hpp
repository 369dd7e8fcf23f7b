#pragma once
// Internal to the graph layer (not installed): the partition's graph on rank
// 0, exposed for its test against the serial twin; the id blocks.
#include <mpi.h>

#include <algorithm>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "snl/core/common.hpp"
#include "snl/io/network.hpp"

namespace snl::detail {

// The blocks of node ids (block_range): block r holds [first[r], first[r + 1]).
struct Blocks {
  std::vector<GlobalId> first;
  double per_node = 0;  // blocks per node: the guess of of()
  Blocks(GlobalId n, int size) : first(static_cast<std::size_t>(size) + 1) {
    for (int r = 0; r < size; ++r) {
      GlobalId rb, re;
      block_range(n, size, r, rb, re);
      first[r] = rb;
      first[r + 1] = re;
    }
    per_node = n > 0 ? static_cast<double>(size) / static_cast<double>(n) : 0.0;
  }
  int size() const { return static_cast<int>(first.size()) - 1; }
  // The block of node v from a floating-point guess, without integer divisions.
  int of(GlobalId v) const {
    int r = std::min(size() - 1, static_cast<int>(static_cast<double>(v) * per_node));
    while (v < first[r]) --r;
    while (v >= first[r + 1]) ++r;
    return r;
  }
};

/// The undirected graph of every rank's edge pairs as CSR on rank 0 (xadj of
/// n + 1 offsets, each row ascending, a pair's two half-edges in the rows of
/// both ends), built in parallel by the block holders of the rows. Collective;
/// returns "" on success, else why not (the same on every rank). Other ranks'
/// xadj and adjncy are left empty. peak: this rank's bytes at their largest.
std::string root_csr(MPI_Comm comm, GlobalId n, const std::vector<GlobalId>& edges, std::vector<std::int64_t>& xadj,
                     std::vector<std::int32_t>& adjncy, std::int64_t& peak);

/// Owners of this rank's block of nodes under the bfs partition into nparts
/// parts (src/graph/level_bisection.cpp) of the graph of every rank's edge
/// pairs, computed by all ranks on their blocks of rows. Collective; returns
/// "" on success, kPastMaxLevels when a breadth-first pass ran past
/// max_levels levels (one collective round each), else why not; the same on
/// every rank. mark(name) is called after the rows are built and at the end.
/// keys: each node's key in the split that decided its part (level_bisection).
inline const std::string kPastMaxLevels = "past the level limit";
std::string bfs_blocks(MPI_Comm comm, GlobalId n, const std::vector<GlobalId>& edges, int nparts,
                       std::int64_t max_levels, std::vector<int>& block, std::int64_t& peak,
                       const std::function<void(const char*)>& mark = {}, std::vector<std::int32_t>* keys = nullptr);

/// The breadth-first passes allowed: 2^14 levels, or 4 sqrt(n) (a planar
/// geometric graph's diameter in hops grows as sqrt(n)).
std::int64_t default_max_levels(GlobalId n);

/// The bfs partition over this rank's rows of blocks (lx: nb + 1 offsets,
/// ladj: neighbour ids); false when a pass ran past max_levels. With keys:
/// each node's breadth-first distance from the root of the pass that decided
/// its part (nodes of one part share that root: an order of the part in
/// bands, OwnerDirectory's keyed index).
template <class Index>
bool level_bisection(MPI_Comm comm, const Blocks& blocks, const std::vector<std::int64_t>& lx,
                     const std::vector<Index>& ladj, int nparts, std::int64_t max_levels, std::vector<int>& owner,
                     std::int64_t& bytes, std::vector<std::int32_t>* keys = nullptr);

}  // namespace snl::detail
