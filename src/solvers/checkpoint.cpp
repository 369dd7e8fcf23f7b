#include "snl/solvers/checkpoint.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <utility>

#include "snl/core/mpi_util.hpp"
#include "snl/core/random.hpp"
#include "snl/solvers/registry.hpp"
#include "snl/solvers/solver.hpp"

namespace snl {

namespace {

struct KeyRec {
  GlobalId a, b;
};

bool operator<(const KeyRec& x, const KeyRec& y) { return x.a != y.a ? x.a < y.a : x.b < y.b; }
bool operator==(const KeyRec& x, const KeyRec& y) { return x.a == y.a && x.b == y.b; }

// Writes keyed records (a, b, values): each rank its rows at an offset from an exclusive scan.
void write_keyed(H5File& f, const std::string& name, const std::vector<GlobalId>& keys,
                 const std::vector<double>& vals, int width) {
  MPI_Comm comm = f.comm();
  long long mine = static_cast<long long>(keys.size() / 2), off = 0, total = 0;
  MPI_Exscan(&mine, &off, 1, MPI_LONG_LONG, MPI_SUM, comm);
  if (comm_rank(comm) == 0) off = 0;
  MPI_Allreduce(&mine, &total, 1, MPI_LONG_LONG, MPI_SUM, comm);
  f.write_rows(name + "_keys", total, 2, off, keys.data(), mine);
  f.write_rows(name, total, width, off, vals.data(), mine);
}

// Reads keyed records and hands each rank the values for the keys it asks for
// (`want`, pairs), through a directory on the block owner of key.a.
std::vector<double> read_keyed(const H5File& f, const std::string& name, const std::vector<GlobalId>& want,
                               int width, GlobalId n) {
  MPI_Comm comm = f.comm();
  const int size = comm_size(comm), rank = comm_rank(comm);
  const auto shape = f.shape(name + "_keys");
  if (shape.size() != 2 || shape[1] != 2) throw Error(f.path() + ": malformed checkpoint dataset " + name + "_keys");
  const auto vshape = f.shape(name);
  if (vshape.size() != 2 || vshape[0] != shape[0] || vshape[1] != static_cast<std::uint64_t>(width))
    throw Error(f.path() + ": malformed checkpoint dataset " + name);
  GlobalId b, e;
  block_range(static_cast<GlobalId>(shape[0]), size, rank, b, e);
  const auto keys = f.read_rows_int(name + "_keys", b, e - b);
  const auto vals = f.read_rows_double(name, b, e - b);
  // Records to the directory.
  std::vector<std::vector<KeyRec>> ko(size);
  std::vector<std::vector<double>> vo(size);
  for (GlobalId t = 0; t < e - b; ++t) {
    const GlobalId a = keys[2 * t];
    if (a < 0 || a >= n) throw Error(f.path() + ": checkpoint dataset " + name + "_keys has an invalid id");
    const int d = block_owner(n, size, a);
    ko[d].push_back({a, keys[2 * t + 1]});
    vo[d].insert(vo[d].end(), vals.begin() + t * width, vals.begin() + (t + 1) * width);
  }
  const auto dk = exchange_records(comm, ko);
  const auto dv = exchange_records(comm, vo);
  std::vector<std::size_t> order(dk.size());
  for (std::size_t t = 0; t < order.size(); ++t) order[t] = t;
  std::sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) { return dk[x] < dk[y]; });
  // Requests to the directory, answered in request order.
  std::vector<std::vector<KeyRec>> req(size);
  std::vector<std::vector<std::size_t>> req_pos(size);
  for (std::size_t t = 0; 2 * t < want.size(); ++t) {
    const int d = block_owner(n, size, want[2 * t]);
    req[d].push_back({want[2 * t], want[2 * t + 1]});
    req_pos[d].push_back(t);
  }
  std::vector<long long> cnt_out(size), cnt_in(size);
  for (int r = 0; r < size; ++r) cnt_out[r] = static_cast<long long>(req[r].size());
  MPI_Alltoall(cnt_out.data(), 1, MPI_LONG_LONG, cnt_in.data(), 1, MPI_LONG_LONG, comm);
  const auto asked = exchange_records(comm, req);
  std::vector<std::vector<double>> ans(size);
  std::string err;
  std::size_t pos = 0;
  for (int r = 0; r < size; ++r)
    for (long long t = 0; t < cnt_in[r]; ++t, ++pos) {
      auto it = std::lower_bound(order.begin(), order.end(), asked[pos],
                                 [&](std::size_t x, const KeyRec& k) { return dk[x] < k; });
      if (it == order.end() || !(dk[*it] == asked[pos])) {
        if (err.empty())
          err = f.path() + ": checkpoint has no " + name + " record for (" + std::to_string(asked[pos].a) + ", " +
                std::to_string(asked[pos].b) + ")";
        ans[r].insert(ans[r].end(), width, 0.0);
      } else {
        ans[r].insert(ans[r].end(), dv.begin() + *it * width, dv.begin() + (*it + 1) * width);
      }
    }
  agree(comm, err);
  const auto got = exchange_records(comm, ans);
  std::vector<double> out(want.size() / 2 * width);
  pos = 0;
  for (int r = 0; r < size; ++r)
    for (std::size_t t : req_pos[r]) {
      std::copy(got.begin() + pos * width, got.begin() + (pos + 1) * width, out.begin() + t * width);
      ++pos;
    }
  return out;
}

}  // namespace

void StateWriter::scalar(const std::string& name, double v) { f_.write_scalar(prefix_ + name, v); }

void StateWriter::node_rows(const std::string& name, const double* owned, int width) {
  GlobalId off = 0;
  const auto rows = prob_.owned_to_file_rows(owned, width, &off);
  f_.write_rows(prefix_ + name, prob_.num_sensors(), width, off, rows.data(), rows.size() / width);
}

void StateWriter::edge_rows(const std::string& name, const double* per_entry, int width) {
  edge_rows(name, width, [&](LocalId, std::int64_t e, int c) { return per_entry[e * width + c]; });
}

void StateWriter::edge_rows(const std::string& name, int width,
                            const std::function<double(LocalId, std::int64_t, int)>& get) {
  const auto& g = prob_.graph();
  std::vector<GlobalId> keys;
  std::vector<double> vals;
  for (LocalId v = 0; v < g.num_owned(); ++v)
    for (auto e = g.offsets()[v]; e < g.offsets()[v + 1]; ++e) {
      const GlobalId a = g.global_id(v), b = g.global_id(g.adjacency()[e]);
      if (a > b) continue;
      keys.push_back(a);
      keys.push_back(b);
      for (int c = 0; c < width; ++c) vals.push_back(get(v, e, c));
    }
  write_keyed(f_, prefix_ + name, keys, vals, width);
}

void StateWriter::anchor_rows(const std::string& name, const double* per_entry, int width) {
  const auto& g = prob_.graph();
  std::vector<GlobalId> keys;
  std::vector<double> vals;
  for (LocalId v = 0; v < g.num_owned(); ++v)
    for (auto e = prob_.anchor_offsets()[v]; e < prob_.anchor_offsets()[v + 1]; ++e) {
      keys.push_back(g.global_id(v));
      keys.push_back(prob_.anchor_ids()[e]);
      vals.insert(vals.end(), per_entry + e * width, per_entry + (e + 1) * width);
    }
  write_keyed(f_, prefix_ + name, keys, vals, width);
}

double StateReader::scalar(const std::string& name) const { return f_.read_scalar(prefix_ + name); }

void StateReader::node_rows(const std::string& name, double* owned, int width) const {
  MPI_Comm comm = prob_.comm();
  const auto shape = f_.shape(prefix_ + name);
  if (shape.size() != 2 || shape[0] != static_cast<std::uint64_t>(prob_.num_sensors()) ||
      shape[1] != static_cast<std::uint64_t>(width))
    throw Error(f_.path() + ": checkpoint dataset " + prefix_ + name + " has the wrong shape");
  GlobalId b, e;
  block_range(prob_.num_sensors(), comm_size(comm), comm_rank(comm), b, e);
  const auto rows = f_.read_rows_double(prefix_ + name, b, e - b);
  const auto o = prob_.file_rows_to_owned(rows, b, width);
  std::copy(o.begin(), o.end(), owned);
}

void StateReader::edge_rows(const std::string& name, double* per_entry, int width) const {
  edge_rows(name, width, [&](LocalId, std::int64_t e, int c, double x) { per_entry[e * width + c] = x; });
}

void StateReader::edge_rows(const std::string& name, int width,
                            const std::function<void(LocalId, std::int64_t, int, double)>& set) const {
  const auto& g = prob_.graph();
  std::vector<GlobalId> want;
  want.reserve(g.adjacency().size() * 2);
  for (LocalId v = 0; v < g.num_owned(); ++v)
    for (auto e = g.offsets()[v]; e < g.offsets()[v + 1]; ++e) {
      const GlobalId a = g.global_id(v), b = g.global_id(g.adjacency()[e]);
      want.push_back(std::min(a, b));
      want.push_back(std::max(a, b));
    }
  const auto vals = read_keyed(f_, prefix_ + name, want, width, prob_.num_sensors());
  // vals holds the entries in (v, e) order, as asked for.
  for (LocalId v = 0; v < g.num_owned(); ++v)
    for (auto e = g.offsets()[v]; e < g.offsets()[v + 1]; ++e)
      for (int c = 0; c < width; ++c) set(v, e, c, vals[std::size_t(e) * width + c]);
}

void StateReader::anchor_rows(const std::string& name, double* per_entry, int width) const {
  const auto& g = prob_.graph();
  std::vector<GlobalId> want;
  for (LocalId v = 0; v < g.num_owned(); ++v)
    for (auto e = prob_.anchor_offsets()[v]; e < prob_.anchor_offsets()[v + 1]; ++e) {
      want.push_back(g.global_id(v));
      want.push_back(prob_.anchor_ids()[e]);
    }
  const auto vals = read_keyed(f_, prefix_ + name, want, width, prob_.num_sensors());
  std::copy(vals.begin(), vals.end(), per_entry);
}

// ---------------------------------------------------------------------------
// History columns: the one table checkpoints and result files use.

namespace {
using H = IterationSummary;
const std::vector<HistoryColumn> kHistoryColumns = {
    // checkpoint name, result-file name, needs truth, get, set
    {"total_iteration", "iteration", false, [](const H& h) { return double(h.total_iteration); },
     [](H& h, double v) { h.total_iteration = static_cast<std::int64_t>(v); }},
    {"iteration", "phase_iteration", false, [](const H& h) { return double(h.iteration); },
     [](H& h, double v) { h.iteration = static_cast<std::int64_t>(v); }},
    {"phase", "phase", false, [](const H& h) { return double(algorithm_code(h.phase)); },
     [](H& h, double v) { h.phase = algorithm_name(static_cast<int>(v)); }},
    {"cost", "cost", false, [](const H& h) { return h.cost; }, [](H& h, double v) { h.cost = v; }},
    {"ml_cost", "ml_cost", false, [](const H& h) { return h.ml_cost; }, [](H& h, double v) { h.ml_cost = v; }},
    {"messages", "communications", false, [](const H& h) { return h.messages; },
     [](H& h, double v) { h.messages = v; }},
    {"reals", "reals", false, [](const H& h) { return h.reals; }, [](H& h, double v) { h.reals = v; }},
    {"rel_change", "rel_change", false, [](const H& h) { return h.rel_change; },
     [](H& h, double v) { h.rel_change = v; }},
    {"grad_norm", "grad_norm", false, [](const H& h) { return h.grad_norm; }, [](H& h, double v) { h.grad_norm = v; }},
    {"elapsed", "elapsed", false, [](const H& h) { return h.elapsed; }, [](H& h, double v) { h.elapsed = v; }},
    {"rmse", "rmse", true, [](const H& h) { return h.rmse; }, [](H& h, double v) { h.rmse = v; }},
    {"mpe", "mpe", true, [](const H& h) { return h.mpe; }, [](H& h, double v) { h.mpe = v; }},
};
}  // namespace

const std::vector<HistoryColumn>& history_columns() { return kHistoryColumns; }

std::vector<double> history_column(const std::vector<IterationSummary>& h, const HistoryColumn& c) {
  std::vector<double> v;
  v.reserve(h.size());
  for (const auto& it : h) v.push_back(c.get(it));
  return v;
}

// ---------------------------------------------------------------------------
// Checkpoint files: header attributes, history columns, algorithm state.

namespace {

// Async and async-exact draw their activation sequence from (seed, count).
bool seed_drives_iterates(const std::string& algorithm) {
  const AlgorithmInfo* a = find_algorithm(algorithm);
  if (!a) return false;
  for (AlgorithmId id : a->phases)
    if (id == AlgorithmId::kAsync || id == AlgorithmId::kAsyncExact) return true;
  return false;
}

// checkpoint_options() as (flag, value) pairs: "mm|max_iter=5" -> (--algorithm, mm), (--max-iter, 5).
std::vector<std::pair<std::string, std::string>> option_items(const std::string& s) {
  std::vector<std::pair<std::string, std::string>> out;
  std::size_t b = 0;
  while (b <= s.size()) {
    std::size_t e = s.find('|', b);
    if (e == std::string::npos) e = s.size();
    const std::string item = s.substr(b, e - b);
    const std::size_t eq = item.find('=');
    if (eq == std::string::npos) {
      out.emplace_back("--algorithm", item);
    } else {
      std::string flag = "--" + item.substr(0, eq);
      std::replace(flag.begin(), flag.end(), '_', '-');
      out.emplace_back(flag, item.substr(eq + 1));
    }
    b = e + 1;
  }
  return out;
}

// "--seed 1 in the checkpoint, 2 now" for the first option that differs.
std::string first_option_difference(const std::string& then, const std::string& now) {
  const auto a = option_items(then), b = option_items(now);
  auto value = [](const std::vector<std::pair<std::string, std::string>>& v, const std::string& flag) {
    for (const auto& kv : v)
      if (kv.first == flag) return kv.second;
    return std::string("its default");
  };
  auto all = a;
  all.insert(all.end(), b.begin(), b.end());
  for (const auto& kv : all) {
    const std::string x = value(a, kv.first), y = value(b, kv.first);
    if (x != y) return kv.first + " " + x + " in the checkpoint, " + y + " now";
  }
  return "options " + then + " in the checkpoint, " + now + " now";
}

}  // namespace

void write_checkpoint(const std::string& path, const LocalizationProblem& prob, const CheckpointHeader& h,
                      const std::vector<IterationSummary>& history, const Algorithm& alg) {
  static const double delay = [] {
    const char* d = std::getenv("SNL_TEST_CHECKPOINT_DELAY");  // test hook: a slow checkpoint write
    return d ? std::atof(d) : 0.0;
  }();
  H5File f(path, prob.comm(), H5File::Mode::kCreate);
  f.set_attr("format", std::string("snl-checkpoint"));
  f.set_attr("version", std::int64_t(1));
  f.set_attr("network_fingerprint", h.network_fingerprint);
  f.set_attr("options", h.options);
  f.set_attr("algorithm", h.algorithm);
  f.set_attr("phase", h.phase);
  f.set_attr("phase_algorithm", h.phase_algorithm);
  f.set_attr("phase_iteration", h.phase_iteration);
  f.set_attr("total_iteration", h.total_iteration);
  f.set_attr("messages", h.messages);
  f.set_attr("reals", h.reals);
  f.set_attr("elapsed", h.elapsed);
  f.set_attr("ranks", h.ranks);
  f.set_attr("num_sensors", h.num_sensors);
  f.set_attr("dim", h.dim);
  for (const auto& c : kHistoryColumns)
    f.write_replicated(std::string("history/") + c.name, history_column(history, c));
  StateWriter w(f, prob);
  alg.save(w);
  if (delay > 0) {
    MPI_Barrier(prob.comm());
    const double until = MPI_Wtime() + delay;
    while (MPI_Wtime() < until) {
    }
  }
  f.commit();
}

std::string checkpoint_options(const SolverOptions& opt) {
  std::ostringstream os;
  os.precision(17);
  os << opt.algorithm << "|max_iter=" << opt.max_iter << "|tol=" << opt.stop_tol() << "|grad_tol=" << opt.grad_tol
     << "|history_every=" << opt.history_every << "|bb_rounds=" << opt.bb_rounds;
  // Only when they matter, so that earlier checkpoints still match.
  if (opt.temporal_block != 1) os << "|temporal_block=" << opt.temporal_block;
  if (opt.test_every != 0) os << "|test_every=" << opt.test_every;
  if (seed_drives_iterates(opt.algorithm)) os << "|seed=" << opt.seed;
  if (opt.mode != "replay") os << "|mode=" << opt.mode;
  if (opt.target_cost > 0) os << "|target_cost=" << opt.target_cost;
  if (opt.weights != "auto") os << "|weights=" << opt.weights;
  if (opt.loss != "l2") os << "|loss=" << opt.loss;
  if (opt.esdp_rho != 1.0) os << "|esdp_rho=" << opt.esdp_rho;
  if (opt.algorithm == "dv-pipeline") os << "|smooth_iter=" << opt.smooth_iter << "|settle_iter=" << opt.settle_iter;
  if (opt.stop != "papers") os << "|stop=" << opt.stop;
  if (opt.algorithm == "pipeline" && opt.refine != "mm") os << "|refine=" << opt.refine;
  return os.str();
}

CheckpointHeader read_checkpoint_header(const H5File& f, const std::string& network_fingerprint,
                                        const std::string& options) {
  const std::string what = f.path() + ": ";
  if (!f.has_attr("format") || f.attr_string("format") != "snl-checkpoint")
    throw Error(what + "not an snl checkpoint (attribute format != snl-checkpoint)");
  if (f.attr_int("version") != 1) throw Error(what + "unsupported checkpoint version");
  if (f.attr_string("network_fingerprint") != network_fingerprint)
    throw Error(what + "checkpoint of another network (fingerprint " + f.attr_string("network_fingerprint") +
                ", this network " + network_fingerprint + ")");
  if (f.attr_string("options") != options)
    throw Error(what + "checkpoint of incompatible options: " + first_option_difference(f.attr_string("options"), options) +
                "; a restart must repeat it (checkpoint: " + f.attr_string("options") + ")");
  CheckpointHeader h;
  h.network_fingerprint = network_fingerprint;
  h.options = options;
  h.algorithm = f.attr_string("algorithm");
  h.phase_algorithm = f.attr_string("phase_algorithm");
  h.phase = f.attr_int("phase");
  h.phase_iteration = f.attr_int("phase_iteration");
  h.total_iteration = f.attr_int("total_iteration");
  h.messages = f.attr_double("messages");
  h.reals = f.attr_double("reals");
  h.elapsed = f.attr_double("elapsed");
  return h;
}

std::vector<IterationSummary> read_checkpoint_history(const H5File& f) {
  const auto len = f.shape("history/phase");
  const std::uint64_t rows = len.empty() ? 0 : len[0];
  std::vector<std::vector<double>> cols;
  for (const auto& c : kHistoryColumns) {
    cols.push_back(f.read_rows_double(std::string("history/") + c.name, 0, rows));
    if (cols.back().size() != cols.front().size()) throw Error(f.path() + ": malformed history");
  }
  std::vector<IterationSummary> history(cols.front().size());
  for (std::size_t c = 0; c < kHistoryColumns.size(); ++c)
    for (std::size_t r = 0; r < history.size(); ++r) kHistoryColumns[c].set(history[r], cols[c][r]);
  return history;
}

std::string network_fingerprint(const Network& s, MPI_Comm comm) {
  // Sum (mod 2^64) of a hash of every row with its global index: independent
  // of how the rows are split over ranks.
  auto h = [](std::uint64_t tag, std::uint64_t row, const void* data, std::size_t bytes) {
    std::uint64_t x = mix64(tag * 0x9e3779b97f4a7c15ULL ^ row);
    const unsigned char* p = static_cast<const unsigned char*>(data);
    for (std::size_t t = 0; t < bytes; t += 8) {
      std::uint64_t w = 0;
      std::memcpy(&w, p + t, std::min<std::size_t>(8, bytes - t));
      x = mix64(x ^ w);
    }
    return x;
  };
  std::uint64_t acc = 0;
  for (GlobalId e = 0; e < s.local_sensor_edges(); ++e) {
    acc += h(1, s.sensor_edge_offset + e, &s.sensor_edges[2 * e], 16);
    acc += h(2, s.sensor_edge_offset + e, &s.sensor_ranges[e], 8);
  }
  for (GlobalId e = 0; e < s.local_anchor_edges(); ++e) {
    acc += h(3, s.anchor_edge_offset + e, &s.anchor_edges[2 * e], 16);
    acc += h(4, s.anchor_edge_offset + e, &s.anchor_ranges[e], 8);
  }
  std::uint64_t total = 0;
  MPI_Allreduce(&acc, &total, 1, MPI_UINT64_T, MPI_SUM, comm);
  total = mix64(total ^ h(5, 0, s.anchors.data(), s.anchors.size() * 8) ^
                mix64(static_cast<std::uint64_t>(s.num_sensors) * 31 + s.dim));
  char b[24];
  std::snprintf(b, sizeof b, "%016llx", static_cast<unsigned long long>(total));
  return b;
}

}  // namespace snl
