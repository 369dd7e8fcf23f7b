// Distributed BFS tree, tree sweeps and ordered gathers of the consensus
// solvers (include/snl/consensus/tree.hpp).
#include "snl/consensus/tree.hpp"

#include <algorithm>
#include <climits>
#include <string>

#include "snl/core/mpi_util.hpp"

namespace snl::consensus {

// ---------------------------------------------------------------------------
BfsTree distributed_bfs(DistGraph& graph, GlobalId root) {
  MPI_Comm comm = graph.comm();
  const LocalId n_owned = graph.num_owned();
  BfsTree t;
  t.parent.assign(n_owned, -1);
  t.level.assign(n_owned, -1);
  // Levels as doubles (exact for any level) so the halo plan carries them.
  std::vector<double> lev(graph.num_local(), -1.0);
  const LocalId r = graph.owned_local(root);
  if (r >= 0) lev[r] = 0.0;
  const auto& off = graph.offsets();
  const auto& adj = graph.adjacency();
  for (std::int32_t cur = 0;; ++cur) {
    graph.halo().exchange(lev.data(), 1);
    long long reached = 0;
    for (LocalId v = 0; v < n_owned; ++v) {
      if (lev[v] >= 0) continue;
      // Neighbours are sorted by global id: the first on level `cur` is the smallest.
      for (auto e = off[v]; e < off[v + 1]; ++e)
        if (lev[adj[e]] == static_cast<double>(cur)) {
          t.parent[v] = graph.global_id(adj[e]);
          lev[v] = cur + 1.0;
          ++reached;
          break;
        }
    }
    long long any = 0;
    MPI_Allreduce(&reached, &any, 1, MPI_LONG_LONG, MPI_SUM, comm);
    if (any == 0) {
      t.depth = cur;
      break;
    }
  }
  GlobalId first_missing = -1;
  for (LocalId v = 0; v < n_owned; ++v) {
    t.level[v] = static_cast<std::int32_t>(lev[v]);
    if (lev[v] < 0 && (first_missing < 0 || graph.global_id(v) < first_missing)) first_missing = graph.global_id(v);
  }
  agree_first(comm, first_missing < 0 ? LLONG_MAX : first_missing,
              first_missing < 0 ? std::string()
                                : "the graph is not connected: node " + std::to_string(first_missing) +
                                      " cannot be reached from node " + std::to_string(root));
  return t;
}

// ---------------------------------------------------------------------------
namespace {
std::vector<GlobalId> tree_links(const std::vector<GlobalId>& nodes, const std::vector<GlobalId>& parents) {
  std::vector<GlobalId> edges;
  edges.reserve(nodes.size() * 2);
  for (std::size_t i = 0; i < nodes.size(); ++i)
    if (parents[i] >= 0) {
      edges.push_back(nodes[i]);
      edges.push_back(parents[i]);
    }
  return edges;
}
}  // namespace

Tree::Tree(MPI_Comm comm, GlobalId n, const std::vector<int>& owner, const std::vector<GlobalId>& nodes,
           const std::vector<GlobalId>& parents, const std::vector<std::int32_t>& levels, int halo_width)
    : graph_(comm, n, owner, tree_links(nodes, parents), {}, 0, halo_width) {
  const LocalId n_owned = graph_.num_owned();
  parent_.assign(n_owned, -1);
  parent_entry_.assign(n_owned, -1);
  level_.assign(n_owned, 0);
  std::string err;
  if (static_cast<LocalId>(nodes.size()) != n_owned) err = "internal error: tree nodes differ from the owned nodes";
  std::int32_t my_depth = 0;
  for (std::size_t i = 0; i < nodes.size() && err.empty(); ++i) {
    const LocalId v = graph_.owned_local(nodes[i]);
    if (v < 0) {
      err = "internal error: tree node " + std::to_string(nodes[i]) + " is not owned here";
      break;
    }
    level_[v] = levels[i];
    my_depth = std::max(my_depth, levels[i]);
    if (parents[i] < 0) {
      root_local_ = v;
      continue;
    }
    for (auto e = graph_.offsets()[v]; e < graph_.offsets()[v + 1]; ++e)
      if (graph_.global_id(graph_.adjacency()[e]) == parents[i]) {
        parent_[v] = graph_.adjacency()[e];
        parent_entry_[v] = e;
      }
  }
  agree(comm, err);
  MPI_Allreduce(&my_depth, &depth_, 1, MPI_INT32_T, MPI_MAX, comm);
  int mine = root_local_ >= 0 ? comm_rank(comm) : -1;
  MPI_Allreduce(&mine, &root_rank_, 1, MPI_INT, MPI_MAX, comm);
  // Owned nodes grouped by level (counting sort, local order inside a level).
  level_offsets_.assign(depth_ + 2, 0);
  for (LocalId v = 0; v < n_owned; ++v) ++level_offsets_[level_[v] + 1];
  for (std::int32_t l = 0; l <= depth_; ++l) level_offsets_[l + 1] += level_offsets_[l];
  level_nodes_.resize(n_owned);
  std::vector<std::int64_t> fill(level_offsets_.begin(), level_offsets_.end() - 1);
  for (LocalId v = 0; v < n_owned; ++v) level_nodes_[fill[level_[v]]++] = v;
  // Levels whose links to their parents cross ranks (agreed, so sweeps stay collective).
  std::vector<int> cross(depth_ + 1, 0), any(depth_ + 1, 0);
  for (LocalId v = 0; v < n_owned; ++v)
    if (parent_[v] >= n_owned) cross[level_[v]] = 1;
  MPI_Allreduce(cross.data(), any.data(), depth_ + 1, MPI_INT, MPI_MAX, comm);
  cross_.assign(any.begin(), any.end());
}

void Tree::up_sum(double* field, int width) {
  const auto& off = graph_.offsets();
  const auto& adj = graph_.adjacency();
  for (std::int32_t l = depth_; l >= 0; --l) {
    for (auto k = level_offsets_[l]; k < level_offsets_[l + 1]; ++k) {
      const LocalId v = level_nodes_[k];
      double* row = field + std::int64_t(v) * width;
      // Children in global-id order (the adjacency's order), the parent skipped.
      for (auto e = off[v]; e < off[v + 1]; ++e) {
        if (e == parent_entry_[v]) continue;
        const double* c = field + std::int64_t(adj[e]) * width;
        for (int j = 0; j < width; ++j) row[j] += c[j];
      }
    }
    if (l >= 1 && cross_[l]) graph_.halo().exchange(field, width);
  }
}

void Tree::broadcast_root(double* field, int width) {
  for (std::int32_t l = 1; l <= depth_; ++l) {
    if (cross_[l]) graph_.halo().exchange(field, width);
    for (auto k = level_offsets_[l]; k < level_offsets_[l + 1]; ++k) {
      const LocalId v = level_nodes_[k];
      const double* p = field + std::int64_t(parent_[v]) * width;
      std::copy(p, p + width, field + std::int64_t(v) * width);
    }
  }
}

// ---------------------------------------------------------------------------
NodeGather::NodeGather(MPI_Comm comm, GlobalId n, std::vector<GlobalId> owned_ids)
    : comm_(comm), n_(n), ids_(std::move(owned_ids)) {
  const int size = comm_size(comm), rank = comm_rank(comm);
  int mine = static_cast<int>(ids_.size());
  if (rank == 0) counts_.assign(size, 0);
  MPI_Gather(&mine, 1, MPI_INT, counts_.data(), 1, MPI_INT, 0, comm);
  std::vector<int> displs;
  if (rank == 0) {
    displs.assign(size, 0);
    for (int r = 1; r < size; ++r) displs[r] = displs[r - 1] + counts_[r - 1];
    all_ids_.resize(static_cast<std::size_t>(n));
  }
  static_assert(sizeof(GlobalId) == sizeof(long long), "GlobalId is 64-bit");
  MPI_Gatherv(ids_.data(), mine, MPI_LONG_LONG, all_ids_.data(), counts_.data(), displs.data(), MPI_LONG_LONG, 0,
              comm);
}

std::vector<double> NodeGather::to_root(const double* owned_rows, int width) const {
  const int size = comm_size(comm_), rank = comm_rank(comm_);
  if (static_cast<double>(n_) * width > INT_MAX) throw Error("consensus: n * width exceeds 2^31 values in a gather");
  std::vector<int> counts, displs;
  std::vector<double> buf, out;
  if (rank == 0) {
    counts.resize(size);
    displs.assign(size, 0);
    for (int r = 0; r < size; ++r) counts[r] = counts_[r] * width;
    for (int r = 1; r < size; ++r) displs[r] = displs[r - 1] + counts[r - 1];
    buf.resize(static_cast<std::size_t>(n_) * width);
  }
  MPI_Gatherv(owned_rows, static_cast<int>(ids_.size()) * width, MPI_DOUBLE, buf.data(), counts.data(),
              displs.data(), MPI_DOUBLE, 0, comm_);
  if (rank == 0) {
    out.resize(buf.size());
    for (std::size_t i = 0; i < all_ids_.size(); ++i)
      std::copy(buf.begin() + i * width, buf.begin() + (i + 1) * width, out.begin() + all_ids_[i] * width);
  }
  return out;
}

std::vector<double> NodeGather::to_all(const double* owned_rows, int width) const {
  std::vector<double> all = to_root(owned_rows, width);
  all.resize(static_cast<std::size_t>(n_) * width);
  bcast_bytes(comm_, all.data(), all.size() * sizeof(double));
  return all;
}

void NodeGather::sum(const double* owned_rows, int width, double* out) const {
  const std::vector<double> all = to_root(owned_rows, width);
  std::fill(out, out + width, 0.0);
  if (comm_rank(comm_) == 0)
    for (GlobalId i = 0; i < n_; ++i)
      for (int j = 0; j < width; ++j) out[j] += all[i * width + j];
  MPI_Bcast(out, width, MPI_DOUBLE, 0, comm_);
}

void NodeGather::pick(const std::vector<double>& all_rows, int width, double* owned_rows) const {
  for (std::size_t i = 0; i < ids_.size(); ++i)
    std::copy(all_rows.begin() + ids_[i] * width, all_rows.begin() + (ids_[i] + 1) * width, owned_rows + i * width);
}

}  // namespace snl::consensus
