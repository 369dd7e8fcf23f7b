#include "snl/problem/problem.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "core/phase_clock.hpp"
#include "snl/core/memory.hpp"
#include "snl/core/mpi_util.hpp"
#include "snl/core/random.hpp"

namespace snl {

namespace {

struct AnchorEdgeRec {
  GlobalId i, k;
  double r, s;
};

// Union-find with path halving over indices 0..n-1 (T: int32 or int64).
template <class T>
struct DisjointSets {
  std::vector<T> parent;
  explicit DisjointSets(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), T(0)); }
  T find(T x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(T a, T b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

// Which rank holds file row g, given every rank's first row (allgathered).
int slab_holder(const std::vector<GlobalId>& starts, GlobalId g) {
  return static_cast<int>(std::upper_bound(starts.begin(), starts.end(), g) - starts.begin()) - 1;
}

// The measurements after step 1: flat (i, j) / (i, k) pairs with their ranges
// and, where the file has them (on any rank), their sigmas.
struct Measurements {
  std::vector<GlobalId> sedges, aedges;
  std::vector<double> sranges, aranges;
  bool has_ssigmas = false, has_asigmas = false;
  std::vector<double> ssigmas, asigmas;
};

// Step 1: the anchor measurements to the block holders of their sensors,
// duplicates merged (the sensor measurements merge in their rows,
// sensor_rows); rep gets the counts.
Measurements merge_measurements(MPI_Comm comm, const Network& slab, ProblemReport& rep) {
  const int size = comm_size(comm);
  const GlobalId n = slab.num_sensors;
  Measurements m;
  m.has_ssigmas = any_rank(comm, !slab.sensor_sigmas.empty());
  m.has_asigmas = any_rank(comm, !slab.anchor_sigmas.empty());
  std::vector<std::vector<AnchorEdgeRec>> aout(size);
  for (GlobalId e = 0; e < slab.local_anchor_edges(); ++e) {
    const GlobalId i = slab.anchor_edges[2 * e];
    const double sg = slab.anchor_sigmas.empty() ? 0.0 : slab.anchor_sigmas[e];
    aout[block_owner(n, size, i)].push_back({i, slab.anchor_edges[2 * e + 1], slab.anchor_ranges[e], sg});
  }
  auto agot = exchange_records(comm, aout);
  m.aedges.reserve(2 * agot.size());
  m.aranges.reserve(agot.size());
  for (const auto& r : agot) {
    m.aedges.push_back(r.i);
    m.aedges.push_back(r.k);
    m.aranges.push_back(r.r);
    if (m.has_asigmas) m.asigmas.push_back(r.s);
  }
  MeasurementExtras sx, ax;  // sigmas merge by inverse-variance weighting
  if (m.has_asigmas) ax.sigmas = &m.asigmas;
  MergeStats local = merge_duplicates(m.sedges, m.sranges, sx, m.aedges, m.aranges, ax);
  long long in[2] = {local.merged_anchor_pairs, static_cast<long long>(m.aranges.size())}, sum[2];
  MPI_Allreduce(in, sum, 2, MPI_LONG_LONG, MPI_SUM, comm);
  rep.merged.merged_anchor_pairs = sum[0];
  rep.num_anchor_edges = sum[1];
  return m;
}

// Step 2a: the sensor measurements as block rows (BlockRows::from_pairs),
// the range and, where the file has sigmas, the sigma as values, straight
// from the slab: each pair's duplicates (either orientation, any rank) merge
// in the rows of both its ends by merge_duplicates' rule (merge_readings).
// With `consumed`, the slab's sensor measurements are freed once packed.
// rep gets the counts.
BlockRows sensor_rows(MPI_Comm comm, const Network& slab, Network* consumed, bool sigmas, ProblemReport& rep) {
  const BlockRows::Merge merge = [](double* v, std::int64_t count, int width) {
    double sigma = 0.0;
    v[0] = merge_readings(v, width == 2 ? v + 1 : nullptr, static_cast<std::size_t>(count),
                          static_cast<std::size_t>(width), &sigma);
    if (width == 2) v[1] = sigma;
  };
  auto packed = [consumed] {
    test_fail_point("alloc");  // fault-injection tests: one rank runs out of memory between collectives
    if (!consumed) return;
    release(consumed->sensor_edges);
    release(consumed->sensor_ranges);
    release(consumed->sensor_sigmas);
    release(consumed->sensor_nlos);
  };
  BlockRows rows = BlockRows::from_pairs(comm, slab.num_sensors, slab.sensor_edges.data(),
                                         static_cast<std::size_t>(slab.local_sensor_edges()), slab.sensor_ranges.data(),
                                         slab.sensor_sigmas.empty() ? nullptr : slab.sensor_sigmas.data(),
                                         sigmas ? 2 : 1, merge, packed);
  long long in[2] = {rows.merged, rows.offsets.back()}, sum[2];
  MPI_Allreduce(in, sum, 2, MPI_LONG_LONG, MPI_SUM, comm);
  rep.merged.merged_sensor_pairs = sum[0];
  rep.num_sensor_edges = sum[1] / 2;  // each pair is in the rows of both its ends (no self-loops)
  return rows;
}

// Rank 0's part of unanchored_owned. Every rank's message is [number of
// pairs, pairs (a, b) of component labels joined by a cut edge, then (label,
// anchored) for each of its n_mine components with ghosts]. Union-find over
// the labels seen; each rank gets, for its listed components in order,
// whether their joined component has an anchor measurement. O(edge cut + ranks).
std::vector<std::uint8_t> join_components(MPI_Comm comm, const std::vector<GlobalId>& msg, int n_mine) {
  const int size = comm_size(comm);
  const std::vector<GlobalId> all = gather_to_root(comm, msg);
  std::vector<int> counts(size, 0), displs(size, 0);
  MPI_Gather(&n_mine, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, comm);
  std::vector<std::uint8_t> answers;
  if (comm_rank(comm) == 0) {
    std::vector<GlobalId> labels;
    for (std::size_t p = 0, q = 0; q < static_cast<std::size_t>(size); ++q) {
      const auto np = static_cast<std::size_t>(all[p]);
      labels.insert(labels.end(), all.begin() + p + 1, all.begin() + p + 1 + 2 * np);
      for (int t = 0; t < counts[q]; ++t) labels.push_back(all[p + 1 + 2 * np + 2 * t]);
      p += 1 + 2 * np + 2 * static_cast<std::size_t>(counts[q]);
    }
    std::sort(labels.begin(), labels.end());
    labels.erase(std::unique(labels.begin(), labels.end()), labels.end());
    auto idx = [&](GlobalId l) { return std::lower_bound(labels.begin(), labels.end(), l) - labels.begin(); };
    DisjointSets<std::int64_t> ds(labels.size());
    std::vector<std::uint8_t> root_anchored(labels.size(), 0);
    for (int pass = 0; pass < 2; ++pass)  // unite every pair first, then collect the anchored flags
      for (std::size_t p = 0, q = 0; q < static_cast<std::size_t>(size); ++q) {
        const auto np = static_cast<std::size_t>(all[p]);
        for (std::size_t t = 0; t < np && pass == 0; ++t)
          ds.unite(idx(all[p + 1 + 2 * t]), idx(all[p + 2 + 2 * t]));
        for (int t = 0; t < counts[q] && pass == 1; ++t) {
          const std::size_t at = p + 1 + 2 * np + 2 * static_cast<std::size_t>(t);
          if (all[at + 1]) root_anchored[ds.find(idx(all[at]))] = 1;
        }
        p += 1 + 2 * np + 2 * static_cast<std::size_t>(counts[q]);
      }
    for (std::size_t p = 0, q = 0; q < static_cast<std::size_t>(size); ++q) {
      const auto np = static_cast<std::size_t>(all[p]);
      for (int t = 0; t < counts[q]; ++t)
        answers.push_back(root_anchored[ds.find(idx(all[p + 1 + 2 * np + 2 * static_cast<std::size_t>(t)]))]);
      p += 1 + 2 * np + 2 * static_cast<std::size_t>(counts[q]);
    }
    for (int q = 1; q < size; ++q) displs[q] = displs[q - 1] + counts[q - 1];
  }
  std::vector<std::uint8_t> mine(static_cast<std::size_t>(n_mine));
  MPI_Scatterv(answers.data(), counts.data(), displs.data(), MPI_UINT8_T, mine.data(), n_mine, MPI_UINT8_T, 0, comm);
  return mine;
}

// Total and largest ghost count over the ranks, into the partition report.
void count_ghosts(MPI_Comm comm, const DistGraph& graph, PartitionStats& stats) {
  long long g = graph.num_ghosts(), gs = 0, gm = 0;
  MPI_Allreduce(&g, &gs, 1, MPI_LONG_LONG, MPI_SUM, comm);
  MPI_Allreduce(&g, &gm, 1, MPI_LONG_LONG, MPI_MAX, comm);
  stats.total_ghosts = gs;
  stats.max_ghosts = gm;
}

// The smallest 20 global ids of flagged sensors over all ranks (on every rank).
std::vector<GlobalId> flagged_sample(MPI_Comm comm, const DistGraph& graph, const std::vector<std::uint8_t>& flags) {
  std::vector<GlobalId> bad;
  for (LocalId v = 0; v < graph.num_owned() && bad.size() < 20; ++v)
    if (flags[v]) bad.push_back(graph.global_id(v));
  std::sort(bad.begin(), bad.end());
  auto all_bad = gather_to_root(comm, bad);
  std::sort(all_bad.begin(), all_bad.end());
  if (all_bad.size() > 20) all_bad.resize(20);
  long long k = static_cast<long long>(all_bad.size());
  MPI_Bcast(&k, 1, MPI_LONG_LONG, 0, comm);
  all_bad.resize(static_cast<std::size_t>(k));
  MPI_Bcast(all_bad.data(), static_cast<int>(k), MPI_INT64_T, 0, comm);
  return all_bad;
}

}  // namespace

// A block holder's rows (`width` items each, one per node of its directory
// block, ascending) to the owners of their nodes; returns this rank's owned
// rows by local id. Each row goes where its directory slot says, without ids:
// an owner receives from each block holder the rows of its nodes in that
// block in ascending global id, and the blocks come in rank order, so the
// rows arrive in the order of the owned nodes sorted by global id. (Asking
// the holders for the rows, file_rows_to_owned, sends every owned node's id
// there and back: about twice the time at 10M on 2 ranks, docs/performance.md,
// "Owned rows pushed by their block holders".) The rows this rank owns are
// copied into place, not sent to itself. Collective.
template <class T>
std::vector<T> push_block_rows(MPI_Comm comm, const OwnerDirectory& dir, const DistGraph& graph, const T* rows,
                               int width, MPI_Datatype type) {
  const int size = comm_size(comm), rank = comm_rank(comm);
  const auto w = static_cast<std::size_t>(width);
  const GlobalId b = dir.block_begin(), e = dir.block_end();
  std::vector<std::int64_t> cnt(static_cast<std::size_t>(size), 0), rcnt(static_cast<std::size_t>(size));
  for (GlobalId g = b; g < e; ++g) ++cnt[dir.local(g).owner];
  MPI_Alltoall(cnt.data(), 1, MPI_INT64_T, rcnt.data(), 1, MPI_INT64_T, comm);
  std::int64_t stot = 0, rtot = 0;
  for (int r = 0; r < size; ++r) {
    stot += cnt[r];
    rtot += rcnt[r];
  }
  agree(comm, stot * width <= INT32_MAX && rtot * width <= INT32_MAX
                  ? ""
                  : "owned rows: more than 2^31 items on one rank; use more ranks");
  std::vector<int> scount(size), sdisp(size), rcount(size), rdisp(size);
  for (int r = 0, s = 0, t = 0; r < size; ++r) {
    scount[r] = r == rank ? 0 : static_cast<int>(cnt[r] * width);
    rcount[r] = r == rank ? 0 : static_cast<int>(rcnt[r] * width);
    sdisp[r] = s;
    rdisp[r] = t;  // this rank's own segment keeps its place among the others
    s += scount[r];
    t += static_cast<int>(rcnt[r] * width);
  }
  std::vector<T> sbuf(static_cast<std::size_t>(stot - cnt[rank]) * w), seq(static_cast<std::size_t>(rtot) * w);
  {
    std::vector<int> at(sdisp);
    at[rank] = rdisp[rank];
    for (GlobalId g = b; g < e; ++g) {
      const int o = dir.local(g).owner;
      T* dst = (o == rank ? seq.data() : sbuf.data()) + at[o];
      std::copy(rows + static_cast<std::size_t>(g - b) * w, rows + static_cast<std::size_t>(g - b + 1) * w, dst);
      at[o] += width;
    }
  }
  MPI_Alltoallv(sbuf.data(), scount.data(), sdisp.data(), type, seq.data(), rcount.data(), rdisp.data(), type, comm);
  const auto& by_gid = graph.owned_by_global_id();
  if (by_gid.size() * w != seq.size()) throw std::logic_error("owned rows: the directory and the graph disagree");
  std::vector<T> owned(seq.size());
  for (std::size_t t = 0; t < by_gid.size(); ++t) {
    const auto v = static_cast<std::size_t>(by_gid[t].second);
    std::copy(seq.data() + t * w, seq.data() + (t + 1) * w, owned.data() + v * w);
  }
  return owned;
}

// The body runs collectives from start to end: a failure that only some ranks
// see (std::bad_alloc, a bug) cannot be agreed on without a hang, so it aborts
// every rank (abort_on_local_failure); snl::Error is agreed and propagates.
LocalizationProblem::LocalizationProblem(MPI_Comm comm, const Network& slab, PartitionMethod method,
                                         ProblemReport* report)
    : dim_(slab.dim), anchors_(slab.anchors), has_truth_(slab.has_truth), sigma_(slab.sigma) {
  abort_on_local_failure(comm, "problem setup", [&] { build(comm, slab, nullptr, method, report); });
}

LocalizationProblem::LocalizationProblem(MPI_Comm comm, Network&& slab, PartitionMethod method,
                                         ProblemReport* report)
    : dim_(slab.dim), anchors_(slab.anchors), has_truth_(slab.has_truth), sigma_(slab.sigma) {
  abort_on_local_failure(comm, "problem setup", [&] { build(comm, slab, &slab, method, report); });
}

void LocalizationProblem::build(MPI_Comm comm, const Network& slab, Network* consumed, PartitionMethod method,
                                ProblemReport* report) {
  test_fail_point("setup");  // fault-injection tests: one rank fails before the first collective
  // The setup's temporaries (GBs at 10M) reuse freed memory instead of faulting
  // fresh pages; returned to the system at the end (snl/core/memory.hpp).
  const ReuseFreedMemory reuse;
  ProblemReport rep;
  PhaseClock clock(rep.setup_phases);
  Measurements m = merge_measurements(comm, slab, rep);
  if (consumed) {  // the merged lists hold them now; the truth and flags rows are still to come
    release(consumed->anchor_edges);
    release(consumed->anchor_ranges);
    release(consumed->anchor_sigmas);
    release(consumed->anchor_nlos);
  }
  clock.done("merge");
  // 2. The sensor graph by blocks of rows, ranges (and sigmas, as a second
  // column) as values: the partition reads it and the graph build consumes
  // it. The owners stay distributed (OwnerDirectory): nothing of size n.
  BlockRows rows = sensor_rows(comm, slab, consumed, m.has_ssigmas, rep);
  clock.done("rows");
  rep.setup_bytes.emplace_back(
      "measurements", rows.memory_bytes() + static_cast<std::int64_t>(m.aedges.capacity() * sizeof(GlobalId) +
                                                                      m.aranges.capacity() * sizeof(double)));
  rep.setup_bytes.emplace_back("rows", rows.peak_bytes);
  const OwnerDirectory owners = partition_nodes(comm, rows, method, &rep.partition);
  clock.done("partition");
  for (const auto& ph : rep.partition.phases) rep.setup_phases.emplace_back("partition." + ph.first, ph.second);
  rep.setup_bytes.emplace_back("partition", rep.partition.peak_bytes);
  rep.setup_bytes.emplace_back("directory", owners.memory_bytes());
  // The widest exchange: the distance-vector start's anchor lists, (id,
  // distance) x 3p and a flag (solvers/dv_start.cpp).
  graph_ = DistGraph(comm, owners, std::move(rows), std::max(2, 6 * dim_ + 1));
  if (m.has_ssigmas) {
    sensor_sigmas_ = graph_.take_last_edge_column();
    has_sensor_sigmas_ = true;
  }
  clock.done("graph");
  for (const auto& ph : graph_.build_phases()) rep.setup_phases.emplace_back("graph." + ph.first, ph.second);
  rep.setup_bytes.emplace_back("graph_build", graph_.build_peak_bytes());
  rep.partition.edge_cut = graph_.edge_cut();
  count_ghosts(comm, graph_, rep.partition);
  has_anchor_sigmas_ = m.has_asigmas;
  distribute_anchors(comm, owners, m.aedges, m.aranges, m.asigmas);
  read_owned_rows(comm, owners, slab);
  clock.done("anchors");
  const std::vector<std::uint8_t> unanchored = unanchored_owned(comm);
  clock.done("connectivity");
  flag_sensors(comm, unanchored, rep);
  delta_max_ = graph_.max_degree();
  clock.done("flags");
  if (report) *report = rep;
}

// Step 4: anchor measurements to the owners of their sensors, sorted by
// (local sensor, anchor id). They sit on the block holder of their sensor
// (merge_measurements), whose directory slots name the owners.
void LocalizationProblem::distribute_anchors(MPI_Comm comm, const OwnerDirectory& owners,
                                             const std::vector<GlobalId>& aedges, const std::vector<double>& aranges,
                                             const std::vector<double>& asigmas) {
  const LocalId n_owned = graph_.num_owned();
  std::vector<std::vector<AnchorEdgeRec>> out(comm_size(comm));
  for (std::size_t e = 0; 2 * e < aedges.size(); ++e)
    out[owners.local(aedges[2 * e]).owner].push_back(
        {aedges[2 * e], aedges[2 * e + 1], aranges[e], asigmas.empty() ? 0.0 : asigmas[e]});
  auto got = exchange_records(comm, out);
  std::vector<std::pair<LocalId, std::size_t>> keyed(got.size());
  for (std::size_t t = 0; t < got.size(); ++t) keyed[t] = {graph_.owned_local(got[t].i), t};
  std::sort(keyed.begin(), keyed.end(), [&](const auto& x, const auto& y) {
    return x.first != y.first ? x.first < y.first : got[x.second].k < got[y.second].k;
  });
  anchor_offsets_.assign(static_cast<std::size_t>(n_owned) + 1, 0);
  anchor_ids_.resize(got.size());
  anchor_ranges_.resize(got.size());
  if (has_anchor_sigmas_) anchor_sigmas_.resize(got.size());
  for (std::size_t t = 0; t < keyed.size(); ++t) {
    const auto& r = got[keyed[t].second];
    ++anchor_offsets_[keyed[t].first + 1];
    anchor_ids_[t] = static_cast<std::int32_t>(r.k);
    anchor_ranges_[t] = r.r;
    if (has_anchor_sigmas_) anchor_sigmas_[t] = r.s;
  }
  for (LocalId v = 0; v < n_owned; ++v) anchor_offsets_[v + 1] += anchor_offsets_[v];
}

// Step 5: truth and the file's localizability flags to the owners. Where
// every rank's slab holds the rows of its directory block (as read_network
// and network_slab deal them), the rows are pushed by the block holders
// (push_block_rows); other slabs ask the holders of the rows
// (file_rows_to_owned).
void LocalizationProblem::read_owned_rows(MPI_Comm comm, const OwnerDirectory& owners, const Network& slab) {
  const LocalId n_owned = graph_.num_owned();
  const auto nb = static_cast<std::size_t>(owners.block_end() - owners.block_begin());
  const bool any = any_rank(comm, !slab.localizability.empty());  // the file has flags
  const bool block_slab =
      all_ranks(comm, slab.sensor_row_offset == owners.block_begin() &&
                          (!has_truth_ || slab.truth.size() == nb * static_cast<std::size_t>(dim_)) &&
                          (!any || slab.localizability.size() == nb));
  if (block_slab) {
    if (has_truth_) truth_ = push_block_rows(comm, owners, graph_, slab.truth.data(), dim_, MPI_DOUBLE);
    flags_ = any ? push_block_rows(comm, owners, graph_, slab.localizability.data(), 1, MPI_UINT8_T)
                 : std::vector<std::uint8_t>(static_cast<std::size_t>(n_owned), 0);
    return;
  }
  if (has_truth_) truth_ = file_rows_to_owned(slab.truth, slab.sensor_row_offset, dim_);
  flags_.assign(static_cast<std::size_t>(n_owned), 0);
  if (any) {
    std::vector<double> f(slab.localizability.begin(), slab.localizability.end());
    auto owned_f = file_rows_to_owned(f, slab.sensor_row_offset, 1);
    for (LocalId v = 0; v < n_owned; ++v) flags_[v] = static_cast<std::uint8_t>(owned_f[v]);
  }
}

// Step 5b: per owned sensor, 1 if its connected component has no anchor
// measurement. Union-find over the owned subgraph on each rank; components
// that reach other ranks are then joined on rank 0 over the cut edges only
// (O(edge cut + ranks), nothing of size n): the labels of the ghosts come by
// one halo exchange, rank 0 gets (label, label) pairs and the anchored flags
// of the components that have ghosts, and answers per component.
std::vector<std::uint8_t> LocalizationProblem::unanchored_owned(MPI_Comm comm) {
  const LocalId n_owned = graph_.num_owned();
  const auto& off = graph_.offsets();
  const auto& adj = graph_.adjacency();
  DisjointSets<LocalId> ds(static_cast<std::size_t>(n_owned));
  for (LocalId v = 0; v < n_owned; ++v)
    for (auto e = off[v]; e < off[v + 1]; ++e)
      if (adj[e] < n_owned) ds.unite(v, adj[e]);
  std::vector<LocalId> comp(static_cast<std::size_t>(n_owned));
  std::vector<std::int64_t> comp_of_root(static_cast<std::size_t>(n_owned), -1);
  std::int64_t ncomp = 0;
  for (LocalId v = 0; v < n_owned; ++v) {
    const LocalId r = ds.find(v);
    if (comp_of_root[r] < 0) comp_of_root[r] = ncomp++;
    comp[v] = static_cast<LocalId>(comp_of_root[r]);
  }
  release(comp_of_root);
  ds = DisjointSets<LocalId>(0);
  std::vector<std::uint8_t> anchored(static_cast<std::size_t>(ncomp), 0), remote(static_cast<std::size_t>(ncomp), 0);
  for (LocalId v = 0; v < n_owned; ++v)
    if (anchor_offsets_[v + 1] > anchor_offsets_[v]) anchored[comp[v]] = 1;
  long long first = 0;
  MPI_Exscan(&ncomp, &first, 1, MPI_LONG_LONG, MPI_SUM, comm);
  if (comm_rank(comm) == 0) first = 0;
  // Global labels (exact in doubles below 2^53) of owned nodes, then ghosts'.
  std::vector<double> label(static_cast<std::size_t>(graph_.num_local()), 0.0);
  for (LocalId v = 0; v < n_owned; ++v) label[v] = static_cast<double>(first + comp[v]);
  graph_.halo().exchange(label.data(), 1);
  std::vector<GlobalId> msg;  // pairs (own label, ghost label), then (label, anchored) of the components with ghosts
  for (LocalId v = graph_.num_interior(); v < n_owned; ++v)
    for (auto e = off[v]; e < off[v + 1]; ++e)
      if (adj[e] >= n_owned) {
        remote[comp[v]] = 1;
        msg.push_back(first + comp[v]);
        msg.push_back(static_cast<GlobalId>(label[adj[e]]));
      }
  release(label);
  const std::int64_t n_pairs = static_cast<std::int64_t>(msg.size() / 2);
  std::vector<GlobalId> mine_remote;
  for (std::int64_t c = 0; c < ncomp; ++c)
    if (remote[c]) {
      mine_remote.push_back(first + c);
      msg.push_back(first + c);
      msg.push_back(anchored[c]);
    }
  msg.insert(msg.begin(), n_pairs);
  const std::vector<std::uint8_t> answer = join_components(comm, msg, static_cast<int>(mine_remote.size()));
  for (std::size_t t = 0; t < mine_remote.size(); ++t) anchored[mine_remote[t] - first] = answer[t];
  std::vector<std::uint8_t> un(static_cast<std::size_t>(n_owned));
  for (LocalId v = 0; v < n_owned; ++v) un[v] = anchored[comp[v]] ? 0 : 1;
  return un;
}

// Step 6: flags of sensors that cannot be localized (no anchored component,
// fewer than p + 1 measurements), their counts and a sample into rep, and
// the largest anchor degree.
void LocalizationProblem::flag_sensors(MPI_Comm comm, const std::vector<std::uint8_t>& unanchored,
                                       ProblemReport& rep) {
  long long cnt[3] = {0, 0, 0};
  int maxa = 0;
  for (LocalId v = 0; v < graph_.num_owned(); ++v) {
    const auto na = anchor_offsets_[v + 1] - anchor_offsets_[v];
    maxa = std::max(maxa, static_cast<int>(na));
    if (unanchored[v]) {
      flags_[v] |= kUnanchoredComponent;
      ++cnt[0];
    }
    if (graph_.degree(v) + na < dim_ + 1) {
      flags_[v] |= kFewMeasurements;
      ++cnt[1];
    }
    if (flags_[v]) ++cnt[2];
  }
  long long tot[3];
  MPI_Allreduce(cnt, tot, 3, MPI_LONG_LONG, MPI_SUM, comm);
  rep.unanchored = tot[0];
  rep.few_measurements = tot[1];
  rep.unlocalizable = tot[2];
  rep.unlocalizable_sample = flagged_sample(comm, graph_, flags_);
  MPI_Allreduce(&maxa, &max_anchor_deg_, 1, MPI_INT, MPI_MAX, comm);
}

std::int64_t LocalizationProblem::memory_bytes() const {
  return graph_.memory_bytes() +
         static_cast<std::int64_t>(anchors_.capacity() * sizeof(double) +
                                   anchor_offsets_.capacity() * sizeof(std::int64_t) +
                                   anchor_ids_.capacity() * sizeof(std::int32_t) +
                                   anchor_ranges_.capacity() * sizeof(double) + truth_.capacity() * sizeof(double) +
                                   flags_.capacity() + sensor_sigmas_.capacity() * sizeof(double) +
                                   anchor_sigmas_.capacity() * sizeof(double) +
                                   model_.edge_weights.capacity() * sizeof(double) +
                                   model_.anchor_weights.capacity() * sizeof(double));
}

std::vector<double> LocalizationProblem::file_rows_to_owned(const std::vector<double>& rows, GlobalId row_offset,
                                                            int width) const {
  MPI_Comm comm = this->comm();
  const int size = comm_size(comm);
  std::vector<GlobalId> starts(size);
  GlobalId mine = row_offset;
  MPI_Allgather(&mine, 1, MPI_INT64_T, starts.data(), 1, MPI_INT64_T, comm);
  // Ask the holder of each owned row for it (in local order), then answer.
  const LocalId n_owned = graph_.num_owned();
  std::vector<std::vector<GlobalId>> ask(size);
  std::vector<std::vector<LocalId>> ask_local(size);
  for (LocalId v = 0; v < n_owned; ++v) {
    const int h = slab_holder(starts, graph_.global_id(v));
    ask[h].push_back(graph_.global_id(v));
    ask_local[h].push_back(v);
  }
  std::vector<std::int64_t> cnt_out(size), cnt_in(size);
  for (int r = 0; r < size; ++r) cnt_out[r] = static_cast<std::int64_t>(ask[r].size());
  MPI_Alltoall(cnt_out.data(), 1, MPI_INT64_T, cnt_in.data(), 1, MPI_INT64_T, comm);
  std::vector<GlobalId> asked = exchange_records(comm, ask);
  std::vector<std::vector<double>> answer(size);
  std::size_t pos = 0;
  for (int r = 0; r < size; ++r) {
    answer[r].reserve(static_cast<std::size_t>(cnt_in[r]) * width);
    for (std::int64_t t = 0; t < cnt_in[r]; ++t, ++pos) {
      const GlobalId local_row = asked[pos] - row_offset;
      answer[r].insert(answer[r].end(), rows.begin() + local_row * width, rows.begin() + (local_row + 1) * width);
    }
  }
  std::vector<double> got = exchange_records(comm, answer);
  std::vector<double> owned(static_cast<std::size_t>(n_owned) * width);
  pos = 0;
  for (int r = 0; r < size; ++r)
    for (LocalId v : ask_local[r]) {
      std::copy(got.begin() + pos * width, got.begin() + (pos + 1) * width, owned.begin() + std::size_t(v) * width);
      ++pos;
    }
  return owned;
}

std::vector<double> LocalizationProblem::owned_to_file_rows(const double* owned, int width,
                                                            GlobalId* row_offset) const {
  MPI_Comm comm = this->comm();
  const int size = comm_size(comm), rank = comm_rank(comm);
  const GlobalId n = num_sensors();
  GlobalId b, e;
  block_range(n, size, rank, b, e);
  std::vector<std::vector<GlobalId>> ids(size);
  std::vector<std::vector<double>> vals(size);
  for (LocalId v = 0; v < graph_.num_owned(); ++v) {
    const GlobalId g = graph_.global_id(v);
    const int r = block_owner(n, size, g);
    ids[r].push_back(g);
    vals[r].insert(vals[r].end(), owned + std::size_t(v) * width, owned + std::size_t(v + 1) * width);
  }
  auto gid = exchange_records(comm, ids);
  auto gv = exchange_records(comm, vals);
  std::vector<double> rows(static_cast<std::size_t>(e - b) * width);
  for (std::size_t t = 0; t < gid.size(); ++t)
    std::copy(gv.begin() + t * width, gv.begin() + (t + 1) * width, rows.begin() + (gid[t] - b) * width);
  if (row_offset) *row_offset = b;
  return rows;
}

}  // namespace snl

namespace snl {

void LocalizationProblem::resample_ranges(double sigma, std::uint64_t seed) {
  if (!has_truth_) throw Error("resampling ranges needs the true positions (dataset truth)");
  const int p = dim_;
  std::vector<double> t(std::size_t(graph_.num_local()) * p, 0.0);
  std::copy(truth_.begin(), truth_.end(), t.begin());
  graph_.halo().exchange(t.data(), p);
  const GlobalId n = num_sensors();
  auto dist = [&](const double* a, const double* b) {
    double s = 0;
    for (int c = 0; c < p; ++c) s += (a[c] - b[c]) * (a[c] - b[c]);
    return std::sqrt(s);
  };
  derived_cache_.reset();  // built from the ranges
  auto& ev = graph_.mutable_edge_values();
  const auto& off = graph_.offsets();
  const auto& adj = graph_.adjacency();
  for (LocalId v = 0; v < graph_.num_owned(); ++v) {
    for (auto e = off[v]; e < off[v + 1]; ++e) {
      const GlobalId a = graph_.global_id(v), b = graph_.global_id(adj[e]);
      const auto key = static_cast<std::uint64_t>(std::min(a, b)) * static_cast<std::uint64_t>(n) +
                       static_cast<std::uint64_t>(std::max(a, b));
      const double d = dist(&t[std::size_t(v) * p], &t[std::size_t(adj[e]) * p]);
      ev[e] = std::abs(d + sigma * standard_normal(seed, RngStream::kExperimentNoise, key));
    }
    for (auto e = anchor_offsets_[v]; e < anchor_offsets_[v + 1]; ++e) {
      const auto key = (static_cast<std::uint64_t>(graph_.global_id(v)) << 20) ^
                       static_cast<std::uint64_t>(anchor_ids_[e]) ^ 0x8000000000000000ULL;
      const double d = dist(&t[std::size_t(v) * p], &anchors_[std::size_t(anchor_ids_[e]) * p]);
      anchor_ranges_[e] = std::abs(d + sigma * standard_normal(seed, RngStream::kExperimentNoise, key));
    }
  }
}

}  // namespace snl
