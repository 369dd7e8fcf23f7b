#pragma once
// Internal to the graph layer (not installed): the id blocks, the partition
// graph's rows (partition_rows.cpp; root_csr is tested against the serial
// twin) and the partitioners behind partition_nodes, one file each.
#include <mpi.h>

#include <algorithm>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "snl/core/common.hpp"
#include "snl/graph/partition.hpp"
#include "snl/io/network.hpp"

namespace snl {
struct BlockRows;
}  // namespace snl

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

// Records the seconds since the previous mark under a phase name.
struct PhaseMarks {
  std::vector<std::pair<std::string, double>> phases;
  double mark = MPI_Wtime();
  void operator()(const char* name) {
    const double now = MPI_Wtime();
    phases.emplace_back(name, now - mark);
    mark = now;
  }
};

// A half-edge on its way to the block holder of its node: the node's offset
// in that block and the neighbour.
template <class Index>
struct HalfRow {
  std::int32_t v;
  Index u;
};

// The partition graph's steps (partition_rows.cpp): each pair's two
// half-edges to the block holders of their nodes (keep: this rank's block;
// got: received); the rows of a block of nb nodes from them, each ascending;
// all rows as CSR on rank 0. Collective but fill_block_rows; "" or why not.
template <class Index>
std::string route_half_rows(MPI_Comm comm, const Blocks& blocks, const std::vector<GlobalId>& edges,
                            std::vector<HalfRow<Index>>& keep, std::vector<HalfRow<Index>>& got, std::int64_t& bytes);
template <class Offset, class Index>
bool fill_block_rows(std::int64_t nb, std::vector<HalfRow<Index>>&& keep, std::vector<HalfRow<Index>>&& got,
                     std::vector<Offset>& lx, std::vector<Index>& ladj, std::int64_t& bytes);
template <class Offset, class Index>
std::string root_csr_impl(MPI_Comm comm, GlobalId n, const std::vector<GlobalId>& edges, std::vector<Offset>& xadj,
                          std::vector<Index>& adjncy, std::int64_t& peak);

// The partitioners on rank 0: owners of all n nodes there (metis_partition.cpp,
// bfs_partition.cpp), and partition_on_root, which runs one and scatters each
// rank its block's owners (partition.cpp). Collective; "" or why not.
std::string metis_on_root(MPI_Comm comm, GlobalId n, const std::vector<GlobalId>& edges, std::vector<int>& owner,
                          PhaseMarks& phase, std::int64_t& peak);
std::string bfs_on_root(MPI_Comm comm, GlobalId n, const std::vector<GlobalId>& edges, std::vector<int>& owner,
                        PhaseMarks& phase, std::int64_t& peak);
std::string partition_on_root(MPI_Comm comm, GlobalId n, const std::vector<GlobalId>& edges, PartitionMethod method,
                              std::vector<int>& block, PhaseMarks& phase, std::int64_t& peak);

// The distributed partitioners: owners of this rank's block of nodes
// (bfs_partition.cpp; parmetis_partition.cpp where built with ParMETIS).
std::string bfs_partition_blocks(MPI_Comm comm, GlobalId n, const std::vector<GlobalId>& edges,
                                 const BlockRows* rows, std::vector<int>& block, std::vector<std::int32_t>& keys,
                                 PhaseMarks& phase, std::int64_t& peak, std::string& note);
#ifdef SNL_HAVE_PARMETIS
std::string parmetis_partition(MPI_Comm comm, GlobalId n, const std::vector<GlobalId>& edges,
                               std::vector<int>& block, PhaseMarks& phase, std::int64_t& peak);
#endif

}  // namespace snl::detail
