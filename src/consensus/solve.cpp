// The driver of `snl consensus solve`: builds the method's communication
// structure on the partitioned network, runs primal iterations with history
// records, checkpoints and stop signals, and reports.
#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "consensus/solver_detail.hpp"
#include "snl/core/mpi_util.hpp"
#include "snl/io/network.hpp"
#include "snl/core/stop_signal.hpp"

namespace snl::consensus {

namespace {

using detail::Counters;
using detail::Runner;

// This rank's share of the links (a block of rows), as partition_graph and
// DistGraph take them.
std::vector<GlobalId> my_links(MPI_Comm comm, const ProblemData& d) {
  GlobalId b, e;
  block_range(static_cast<GlobalId>(d.edges.size() / 2), comm_size(comm), comm_rank(comm), b, e);
  return std::vector<GlobalId>(d.edges.begin() + 2 * b, d.edges.begin() + 2 * e);
}

struct Built {
  std::unique_ptr<Runner> runner;
  std::string partition;
};

// The BFS tree from node 0 on the network (001 Sec. 5). Its construction is
// counted as each node telling its neighbours its level once (2E messages).
std::unique_ptr<Tree> bfs_tree(MPI_Comm comm, const ProblemData& d, const std::vector<int>& owner,
                               const std::vector<GlobalId>& links, int halo_width, Counters& c,
                               std::vector<GlobalId>* all_parents = nullptr) {
  DistGraph net(comm, d.num_nodes, owner, links, {}, 0, 1);
  const BfsTree bfs = distributed_bfs(net, 0);
  c.add(double(d.edges.size()), 1);
  std::vector<GlobalId> nodes(net.local_to_global().begin(), net.local_to_global().begin() + net.num_owned());
  if (all_parents) {
    NodeGather g(comm, d.num_nodes, nodes);
    std::vector<double> p(bfs.parent.begin(), bfs.parent.end());
    const auto all = g.to_all(p.data(), 1);
    all_parents->assign(all.begin(), all.end());
  }
  return std::make_unique<Tree>(comm, d.num_nodes, owner, nodes, bfs.parent, bfs.level, halo_width);
}

// The Hamilton path as a tree: root path[0], parent of path[i] is path[i-1].
std::unique_ptr<Tree> path_tree(MPI_Comm comm, const ProblemData& d, const std::vector<int>& owner,
                                int halo_width) {
  const int rank = comm_rank(comm);
  std::vector<GlobalId> nodes, parents;
  std::vector<std::int32_t> levels;
  for (std::size_t i = 0; i < d.truth_path.size(); ++i)
    if (owner[d.truth_path[i]] == rank) {
      nodes.push_back(d.truth_path[i]);
      parents.push_back(i == 0 ? -1 : d.truth_path[i - 1]);
      levels.push_back(static_cast<std::int32_t>(i));
    }
  return std::make_unique<Tree>(comm, d.num_nodes, owner, nodes, parents, levels, halo_width);
}

// Euler tour of a tree from node 0 (children in id order): the token's cycle
// when there is no Hamilton path; a node updates at its first visit.
void euler_tour(const std::vector<GlobalId>& parent, std::vector<GlobalId>& tour, std::vector<char>& update) {
  const GlobalId n = static_cast<GlobalId>(parent.size());
  std::vector<GlobalId> off(n + 1, 0), kids(n > 0 ? n - 1 : 0);
  for (GlobalId v = 0; v < n; ++v)
    if (parent[v] >= 0) ++off[parent[v] + 1];
  for (GlobalId v = 0; v < n; ++v) off[v + 1] += off[v];
  std::vector<GlobalId> fill(off.begin(), off.end() - 1);
  for (GlobalId v = 0; v < n; ++v)  // increasing v: each child list sorted by id
    if (parent[v] >= 0) kids[fill[parent[v]]++] = v;
  tour.assign(1, 0);
  update.assign(1, 1);
  std::vector<std::pair<GlobalId, GlobalId>> stack{{0, off[0]}};
  while (!stack.empty()) {
    auto& top = stack.back();
    if (top.second < off[top.first + 1]) {
      const GlobalId c = kids[top.second++];
      tour.push_back(c);
      update.push_back(1);
      stack.push_back({c, off[c]});
    } else {
      stack.pop_back();
      if (!stack.empty()) {
        tour.push_back(stack.back().first);
        update.push_back(0);
      }
    }
  }
}

Built build(MPI_Comm comm, const ProblemData& d, const SolveOptions& opt, Counters& c) {
  const int q = d.dim;
  const std::vector<GlobalId> links = my_links(comm, d);
  PartitionStats st;
  const std::vector<int> owner =
      partition_graph(comm, d.num_nodes, links, parse_partition_method(opt.partition), &st);
  Built b;
  b.partition = st.method;
  const int halo_width = 3 * q + q * q + 1;  // the splitting's packet, the widest
  switch (opt.method_kind()) {
    case Method::kCentral:
      b.runner = detail::make_central(comm, d, opt, owner);
      break;
    case Method::kNewtonTree:
      b.runner = detail::make_newton(comm, d, opt, bfs_tree(comm, d, owner, links, halo_width, c));
      break;
    case Method::kNewtonPath:
      b.runner = detail::make_newton(comm, d, opt, path_tree(comm, d, owner, halo_width));
      break;
    case Method::kSubgradient:
      b.runner = detail::make_subgradient(
          comm, d, opt, std::make_unique<DistGraph>(comm, d.num_nodes, owner, links, std::vector<double>{}, 0, q), c);
      break;
    case Method::kIncremental: {
      std::vector<GlobalId> tour;
      std::vector<char> update;
      const bool path = !d.truth_path.empty();
      if (path) {
        tour = d.truth_path;
        update.assign(tour.size(), 1);
      } else {
        std::vector<GlobalId> parents;
        bfs_tree(comm, d, owner, links, 1, c, &parents);
        euler_tour(parents, tour, update);
      }
      b.runner = detail::make_incremental(comm, d, opt, owner, std::move(tour), std::move(update), path);
      break;
    }
  }
  return b;
}

// History columns (result file and checkpoint), in HistoryRecord order.
struct Column {
  const char* name;
  double HistoryRecord::*field;
};
const Column kColumns[] = {{"max_abs_error", &HistoryRecord::max_abs_error},
                           {"F", &HistoryRecord::objective},
                           {"messages_per_node", &HistoryRecord::messages},
                           {"reals_per_node", &HistoryRecord::reals},
                           {"max_abs_error_running_average", &HistoryRecord::avg_max_abs_error},
                           {"F_running_average", &HistoryRecord::avg_objective},
                           {"decrement", &HistoryRecord::decrement},
                           {"step", &HistoryRecord::step}};

void write_history(H5File& f, const std::vector<HistoryRecord>& h) {
  std::vector<double> it, dit, ls;
  for (const auto& r : h) {
    it.push_back(double(r.iteration));
    dit.push_back(double(r.dual_iterations));
    ls.push_back(double(r.line_search_trials));
  }
  f.write_replicated("history/iteration", it);
  f.write_replicated("history/dual_iterations", dit);
  f.write_replicated("history/line_search_trials", ls);
  for (const auto& col : kColumns) {
    std::vector<double> v;
    for (const auto& r : h) v.push_back(r.*(col.field));
    f.write_replicated(std::string("history/") + col.name, v);
  }
}

std::vector<HistoryRecord> read_history(const H5File& f) {
  const auto len = f.shape("history/iteration").at(0);
  const auto it = f.read_rows_double("history/iteration", 0, len);
  const auto dit = f.read_rows_double("history/dual_iterations", 0, len);
  if (f.shape("history/line_search_trials").at(0) != len)
    throw Error(f.path() + ": checkpoint history columns differ in length");
  const auto ls = f.read_rows_double("history/line_search_trials", 0, len);
  std::vector<HistoryRecord> h(len);
  for (std::size_t i = 0; i < len; ++i) {
    h[i].iteration = static_cast<std::int64_t>(it[i]);
    h[i].dual_iterations = static_cast<std::int64_t>(dit[i]);
    h[i].line_search_trials = static_cast<std::int64_t>(ls[i]);
  }
  for (const auto& col : kColumns) {
    const std::string name = std::string("history/") + col.name;
    if (f.shape(name).at(0) != len) throw Error(f.path() + ": checkpoint history columns differ in length");
    const auto v = f.read_rows_double(name, 0, len);
    for (std::size_t i = 0; i < len; ++i) h[i].*(col.field) = v[i];
  }
  return h;
}

void write_checkpoint(MPI_Comm comm, const std::string& path, const ProblemData& d, const SolveOptions& opt,
                      std::int64_t k, const Counters& c, const std::vector<HistoryRecord>& h, const Runner& r) {
  H5File f(path, comm, H5File::Mode::kCreate);
  f.set_attr("format", std::string("snl-consensus-checkpoint"));
  f.set_attr("version", std::int64_t{1});
  f.set_attr("problem_fingerprint", problem_fingerprint(d));
  f.set_attr("options", opt.checkpoint_key());
  f.set_attr("iteration", k);
  f.set_attr("dual_iterations", c.dual_iterations);
  f.set_attr("line_search_trials", c.line_search_trials);
  f.set_attr("messages_total", c.messages);
  f.set_attr("reals_total", c.reals);
  write_history(f, h);
  r.save(f);
  f.commit();
}

std::int64_t read_checkpoint(MPI_Comm comm, const std::string& path, const ProblemData& d, const SolveOptions& opt,
                             Counters& c, std::vector<HistoryRecord>& h, Runner& r) {
  H5File f(path, comm, H5File::Mode::kRead);
  const std::string what = path + ": ";
  if (!f.has_attr("format") || f.attr_string("format") != "snl-consensus-checkpoint")
    throw Error(what + "not an snl consensus checkpoint (attribute format != snl-consensus-checkpoint)");
  if (f.attr_int("version") != 1) throw Error(what + "unsupported checkpoint version");
  if (f.attr_string("problem_fingerprint") != problem_fingerprint(d))
    throw Error(what + "checkpoint of another problem (fingerprint " + f.attr_string("problem_fingerprint") +
                ", this problem " + problem_fingerprint(d) + ")");
  if (f.attr_string("options") != opt.checkpoint_key())
    throw Error(what + "checkpoint of other options (" + f.attr_string("options") + "; now " + opt.checkpoint_key() +
                ")");
  const std::int64_t k = f.attr_int("iteration");
  if (k < 0) throw Error(what + "checkpoint iteration out of range");
  c.dual_iterations = f.attr_int("dual_iterations");
  c.line_search_trials = f.attr_int("line_search_trials");
  c.messages = f.attr_double("messages_total");
  c.reals = f.attr_double("reals_total");
  h = read_history(f);
  if (h.empty() || h.back().iteration != k) throw Error(what + "checkpoint history does not end at its iteration");
  r.load(f);
  f.commit();
  return k;
}

// The summary's totals from the last record and the counters.
void finish(SolveSummary& s, std::int64_t k, const Counters& c, double n, const Runner& r,
            std::vector<double>* x_rows) {
  s.iterations = k;
  s.dual_iterations = c.dual_iterations;
  s.line_search_trials = c.line_search_trials;
  s.max_abs_error = s.history.back().max_abs_error;
  s.objective = s.history.back().objective;
  s.messages_per_node = c.messages / n;
  s.reals_per_node = c.reals / n;
  if (x_rows) *x_rows = r.x_rows();
}

}  // namespace

const std::vector<HistoryColumn>& history_columns() {
  using R = HistoryRecord;
  static const std::vector<HistoryColumn> columns = {
      {"iteration", [](const R& r) { return double(r.iteration); }},
      {"dual_iterations", [](const R& r) { return double(r.dual_iterations); }},
      {"line_search_trials", [](const R& r) { return double(r.line_search_trials); }},
      {"F", [](const R& r) { return r.objective; }},
      {"max_abs_error", [](const R& r) { return r.max_abs_error; }},
      {"messages_per_node", [](const R& r) { return r.messages; }},
      {"reals_per_node", [](const R& r) { return r.reals; }},
      {"F_running_average", [](const R& r) { return r.avg_objective; }},
      {"max_abs_error_running_average", [](const R& r) { return r.avg_max_abs_error; }},
      {"decrement", [](const R& r) { return r.decrement; }},
      {"step", [](const R& r) { return r.step; }}};
  return columns;
}

SolveSummary solve(MPI_Comm comm, const ProblemData& data, const SolveOptions& opt,
                   const CheckpointSettings& ck, const RecordCallback& on_record, std::vector<double>* x_rows) {
  const std::string bad = opt.validate();
  if (!bad.empty()) throw Error(bad);
  validate_problem(data);
  const Method m = opt.method_kind();
  if (m == Method::kNewtonPath && data.truth_path.empty())
    throw Error("--method newton-path needs a Hamilton path and the problem has none (no dataset truth_path; "
                "generate one with --hamiltonian, or use --method newton-tree)");
  const double t0 = MPI_Wtime();
  SolveSummary s;
  s.method = opt.method;
  s.dual = dual_name(opt.dual_kind());
  s.step_rule = step_rule_name(opt.step_kind());
  s.ranks = comm_size(comm);
  // Not counted: the reference of the errors, trusted only if it converged.
  // SNL_TEST_REFERENCE_MAX_ITER: tests cap the reference to see an unconverged x* reported.
  const char* cap = std::getenv("SNL_TEST_REFERENCE_MAX_ITER");
  const Optimum ref = central_optimum(comm, data, cap ? std::atoll(cap) : 1000);
  s.x_star = ref.x;
  s.x_star_converged = ref.converged;
  s.x_star_iterations = ref.iterations;
  s.x_star_decrement = ref.decrement;
  Counters c;
  Built b;
  abort_on_local_failure(comm, "setup", [&] { b = build(comm, data, opt, c); });
  Runner& r = *b.runner;
  s.partition = b.partition;
  s.tree_depth = r.tree_depth();
  const double n = static_cast<double>(data.num_nodes);
  auto record = [&](std::int64_t k) {
    HistoryRecord h;
    h.iteration = k;
    r.measure(k, s.x_star, h);
    if (!s.x_star_converged) h.max_abs_error = h.avg_max_abs_error = NAN;  // never against an unconverged x*
    h.dual_iterations = c.dual_iterations;
    h.line_search_trials = c.line_search_trials;
    h.messages = c.messages / n;
    h.reals = c.reals / n;
    h.elapsed = MPI_Wtime() - t0;
    s.history.push_back(h);
    if (on_record) on_record(h);
  };
  std::int64_t k = 0;
  if (!ck.restart.empty())
    k = read_checkpoint(comm, ck.restart, data, opt, c, s.history, r);
  else
    record(0);
  const std::int64_t max_iter = opt.max_iterations();
  const double tol = opt.tolerance();
  s.termination = "NO_CONVERGENCE";
  while (k < max_iter) {
    test_delay("SNL_TEST_CONSENSUS_DELAY");  // seconds per primal iteration
    bool ok = true;
    abort_on_local_failure(comm, "iteration", [&] { ok = r.iterate(k, c); });
    ++k;
    record(k);
    if (!ok) {
      s.termination = "FAILURE";
      s.message = "non-finite Newton decrement, a Hessian that is not positive definite, or no Armijo step that decreases F";
      break;
    }
    if (r.converged(tol, s.history.back())) {
      s.termination = "CONVERGENCE";
      s.converged = true;
      break;
    }
    int stop = (ck.stop_on_signal && stop_signal_received()) ? 1 : 0, any = 0;
    MPI_Allreduce(&stop, &any, 1, MPI_INT, MPI_MAX, comm);
    // Checkpoint only while the run goes on, so a resume never repeats a stop.
    if (!ck.path.empty() && k < max_iter && (any || (ck.every > 0 && k % ck.every == 0)))
      write_checkpoint(comm, ck.path, data, opt, k, c, s.history, r);
    if (any) {
      s.termination = "SIGNAL";
      s.message = ck.path.empty() ? "stopped by a signal" : "stopped by a signal; checkpoint written to " + ck.path;
      break;
    }
  }
  finish(s, k, c, n, r, x_rows);
  s.wall_seconds = MPI_Wtime() - t0;
  return s;
}

std::vector<double> newton_dual(MPI_Comm comm, const ProblemData& data, const SolveOptions& opt,
                                const std::vector<double>& x_rows, std::int64_t* dual_iterations) {
  const std::string bad = opt.validate();
  if (!bad.empty()) throw Error(bad);
  if (opt.method_kind() != Method::kNewtonTree && opt.method_kind() != Method::kNewtonPath)
    throw Error("newton_dual: a Newton method is needed");
  Counters c;
  Built b = build(comm, data, opt, c);
  b.runner->set_x_rows(x_rows);
  b.runner->iterate(0, c);
  if (dual_iterations) *dual_iterations = c.dual_iterations;
  return b.runner->dual_rows();
}

}  // namespace snl::consensus
