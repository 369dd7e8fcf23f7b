#pragma once
// The communication structures of the consensus solvers (seed 001), built on the
// problem-agnostic DistGraph: the distributed BFS spanning tree (001 Sec. 5: root,
// levels, parent = the smallest id among the previous level's neighbours), the
// tree as a graph of its own with level-by-level sweeps (convergecast and
// broadcast), and ordered gathers for global sums whose result must not depend
// on the number of ranks.
#include <mpi.h>

#include <cstdint>
#include <vector>

#include "snl/core/common.hpp"
#include "snl/graph/dist_graph.hpp"

namespace snl::consensus {

/// Parent (global id, -1 at the root) and BFS level of every owned node of
/// `graph`, in its local order. Collective: one halo exchange of the levels per
/// BFS level. parent = the smallest global id among the neighbours on the
/// previous level, so the tree does not depend on the partition. Throws
/// snl::Error when some node is not reached (disconnected graph).
struct BfsTree {
  std::vector<GlobalId> parent;
  std::vector<std::int32_t> level;
  std::int32_t depth = 0;  ///< largest level (global)
};
BfsTree distributed_bfs(DistGraph& graph, GlobalId root);

/// A spanning tree held as a DistGraph of its n-1 links, owned like the
/// network. Sweeps run one level at a time with one halo exchange per level
/// (skipped for levels whose links all stay on one rank, known globally).
class Tree {
 public:
  /// Collective. `nodes[i]` (owned global ids, any order) has parent
  /// `parents[i]` (-1 for the root) and level `levels[i]`. `halo_width`: most
  /// doubles per node a sweep or exchange carries.
  Tree(MPI_Comm comm, GlobalId n, const std::vector<int>& owner, const std::vector<GlobalId>& nodes,
       const std::vector<GlobalId>& parents, const std::vector<std::int32_t>& levels, int halo_width);
  Tree(const Tree&) = delete;
  Tree& operator=(const Tree&) = delete;

  DistGraph& graph() { return graph_; }
  const DistGraph& graph() const { return graph_; }
  MPI_Comm comm() const { return graph_.comm(); }
  GlobalId num_nodes() const { return graph_.num_global(); }
  LocalId num_owned() const { return graph_.num_owned(); }
  LocalId num_local() const { return graph_.num_local(); }
  /// Local id of v's parent (owned or ghost), -1 for the root.
  LocalId parent(LocalId v) const { return parent_[v]; }
  /// Adjacency entry of v that points to its parent (-1 for the root).
  std::int64_t parent_entry(LocalId v) const { return parent_entry_[v]; }
  std::int32_t level(LocalId v) const { return level_[v]; }
  std::int32_t depth() const { return depth_; }
  LocalId tree_degree(LocalId v) const { return graph_.degree(v); }
  /// Owned nodes of level L: level_nodes()[level_offsets()[L] .. level_offsets()[L+1]).
  const std::vector<LocalId>& level_nodes() const { return level_nodes_; }
  const std::vector<std::int64_t>& level_offsets() const { return level_offsets_; }

  /// Convergecast: on entry the owned rows of `field` ([num_local * width])
  /// hold each node's own value; on return each holds the sum over its subtree
  /// (own value, then the children in global-id order), the root's the total.
  /// Costs n-1 messages of `width` reals.
  void up_sum(double* field, int width);
  /// Broadcast: every owned row receives the root's row. Costs n-1 messages of
  /// `width` reals. Collective; on return every rank's `out` holds the root's row.
  void broadcast_root(double* field, int width);
  /// Local id of the root if this rank owns it, else -1.
  LocalId root_local() const { return root_local_; }
  /// Rank owning the root.
  int root_rank() const { return root_rank_; }

 private:
  DistGraph graph_;
  std::vector<LocalId> parent_;
  std::vector<std::int64_t> parent_entry_;
  std::vector<std::int32_t> level_;
  std::int32_t depth_ = 0;
  std::vector<LocalId> level_nodes_;
  std::vector<std::int64_t> level_offsets_;
  std::vector<char> cross_;  ///< [depth+1]: some link from level L to L-1 joins two ranks
  LocalId root_local_ = -1;
  int root_rank_ = 0;
};

/// Global sums and gathers in node order: every node's rows go to rank 0,
/// which adds them in global-id order, so the result is the same bits on any
/// number of ranks (the fixed order the project's determinism rule asks for).
class NodeGather {
 public:
  NodeGather() = default;
  /// Collective. owned_ids: this rank's nodes in its local order.
  NodeGather(MPI_Comm comm, GlobalId n, std::vector<GlobalId> owned_ids);
  /// Rows of every node in node order ([n * width]) on rank 0; empty elsewhere.
  std::vector<double> to_root(const double* owned_rows, int width) const;
  /// The same on every rank.
  std::vector<double> to_all(const double* owned_rows, int width) const;
  /// Sum of the rows over all nodes in node order, on every rank (out[width]).
  void sum(const double* owned_rows, int width, double* out) const;
  /// Owned rows (local order) picked from rows of every node in node order.
  void pick(const std::vector<double>& all_rows, int width, double* owned_rows) const;
  const std::vector<GlobalId>& owned_ids() const { return ids_; }

 private:
  MPI_Comm comm_ = MPI_COMM_NULL;
  GlobalId n_ = 0;
  std::vector<GlobalId> ids_;
  std::vector<GlobalId> all_ids_;  ///< rank 0: every rank's ids, in rank order
  std::vector<int> counts_;        ///< rank 0: owned nodes per rank
};

}  // namespace snl::consensus
