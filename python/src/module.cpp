// _snl: the Python binding of libsnl (docs/python.md). Thin: every step is a
// library call the CLI makes too (src/cli/solve.cpp, eval.cpp, generate.cpp),
// so positions are bit-identical to `snl solve`. The pure-Python part
// (python/snl/__init__.py) shapes the arrays and wraps the results.
#include <mpi.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "binding_util.hpp"
#include "io/text_table.hpp"
#include "snl/core/mpi_util.hpp"
#include "snl/io/network.hpp"
#include "snl/problem/analysis.hpp"
#include "snl/problem/generate.hpp"
#include "snl/problem/metrics.hpp"
#include "snl/problem/noise.hpp"
#include "snl/problem/problem.hpp"
#include "snl/solvers/dv_start.hpp"
#include "snl/solvers/solver.hpp"

namespace py = pybind11;

namespace {

using snl::GlobalId;
using snl_py::Arr;
using snl_py::bcast_vec;
using snl_py::to_array;
using snl_py::to_comm;
using snl_py::to_vec;

bool g_owns_mpi = false;  // MPI_Init was ours: finalize at exit

// A whole network on the calling process.
struct PyNetwork {
  snl::Network net;
};

// Whole network broadcast from rank 0 (the other ranks' copies are replaced).
void bcast_network(MPI_Comm comm, snl::Network& w) {
  std::int64_t head[5] = {w.dim, w.num_sensors, w.has_truth, w.sigma.has_value(), 0};
  double sigma = w.sigma.value_or(0.0);
  snl::bcast_bytes(comm, head, sizeof head);
  snl::bcast_bytes(comm, &sigma, sizeof sigma);
  w.dim = static_cast<int>(head[0]);
  w.num_sensors = head[1];
  w.has_truth = head[2] != 0;
  w.sigma = head[3] ? std::optional<double>(sigma) : std::nullopt;
  bcast_vec(comm, w.anchors);
  bcast_vec(comm, w.sensor_edges);
  bcast_vec(comm, w.sensor_ranges);
  bcast_vec(comm, w.anchor_edges);
  bcast_vec(comm, w.anchor_ranges);
  bcast_vec(comm, w.truth);
  bcast_vec(comm, w.localizability);
  bcast_vec(comm, w.sensor_sigmas);
  bcast_vec(comm, w.anchor_sigmas);
  bcast_vec(comm, w.sensor_nlos);
  bcast_vec(comm, w.anchor_nlos);
}

// The whole network on every rank of comm: each rank's own (not copied), or
// rank 0's, broadcast, where some rank passed None ("given whole on rank 0").
struct Whole {
  snl::Network received;
  const snl::Network* net = nullptr;
};

void whole_network(const PyNetwork* given, MPI_Comm comm, Whole& w) {
  const bool root = snl::comm_rank(comm) == 0;
  std::string err = root && !given ? "the network must be given on rank 0" : "";
  snl::agree(comm, err);
  if (snl::all_ranks(comm, given != nullptr)) {
    w.net = &given->net;
    return;
  }
  if (root) w.received = given->net;
  bcast_network(comm, w.received);
  w.net = &w.received;
}

// What the CLI's --init names, or positions in file order ([n * p]).
struct Start {
  std::string kind = "auto";  // auto | random | dv | positions
  std::vector<double> rows;
};

// A Python callback at the Solver's records, collective: every rank learns
// whether any rank's callback asked to stop, raised, or saw Ctrl-C.
class PyCallbacks : public snl::IterationCallback {
 public:
  PyCallbacks(MPI_Comm comm, py::object progress, py::object callback)
      : guard_(comm), progress_(std::move(progress)), callback_(std::move(callback)) {}
  ~PyCallbacks() override {
    py::gil_scoped_acquire gil;
    progress_ = py::object();
    callback_ = py::object();
  }
  snl::CallbackReturn operator()(const snl::IterationSummary& s) override {
    int mine;
    {
      py::gil_scoped_acquire gil;
      mine = guard_.poll([&] {
        if (!progress_.is_none() && snl::comm_rank(guard_.comm()) == 0) progress_(record(s));
        return !callback_.is_none() && py::bool_(callback_(record(s)));
      });
    }
    return guard_.agree(mine) == snl_py::PyGuard::kContinue ? snl::CallbackReturn::kContinue
                                                             : snl::CallbackReturn::kAbort;
  }
  // After the solve (GIL held): raises what stopped the run, on every rank.
  void raise_if_needed() { guard_.raise_if_needed(); }
  static py::dict record(const snl::IterationSummary& s) {
    py::dict d;
    d["phase"] = s.phase;
    d["iteration"] = s.iteration;
    d["total_iteration"] = s.total_iteration;
    d["cost"] = s.cost;
    d["ml_cost"] = s.ml_cost;
    d["rel_change"] = s.rel_change;
    d["grad_norm"] = s.grad_norm;
    d["rmse"] = s.rmse;
    d["mpe"] = s.mpe;
    d["messages"] = s.messages;
    d["reals"] = s.reals;
    d["elapsed"] = s.elapsed;
    return d;
  }

 private:
  snl_py::PyGuard guard_;
  py::object progress_, callback_;
};

// SolveCommand's options from keywords; the other keys are refused by name.
struct SolveKeywords {
  snl::SolverOptions solver;
  std::string partition = "auto";
  bool strict = false, check_monotone_given = false, stop_given = false;
  std::string checkpoint, restart;
  std::int64_t checkpoint_every = 0;
  double checkpoint_seconds = 0;
};

const char* kSolveKeys =
    "max_iter, tol, stop, refine, grad_tol, smooth_iter, settle_iter, seed, partition, history_every, test_every, "
    "bb_rounds, esdp_rho, temporal_block, weights, loss, check_monotone, strict, checkpoint, checkpoint_every, "
    "checkpoint_seconds, restart, mode, straggler_delay, straggler_rank, target_cost";

SolveKeywords parse_keywords(const std::string& algorithm, const py::dict& kw) {
  SolveKeywords k;
  snl::SolverOptions& o = k.solver;
  o.algorithm = algorithm;
  for (const auto& item : kw) {
    const std::string key = item.first.cast<std::string>();
    const py::handle v = item.second;
    try {
    if (key == "max_iter") o.max_iter = v.cast<std::int64_t>();
    else if (key == "tol") o.tol = v.cast<double>();
    else if (key == "stop") { o.stop = v.cast<std::string>(); k.stop_given = true; }
    else if (key == "refine") o.refine = v.cast<std::string>();
    else if (key == "grad_tol") o.grad_tol = v.cast<double>();
    else if (key == "smooth_iter") o.smooth_iter = v.cast<std::int64_t>();
    else if (key == "settle_iter") o.settle_iter = v.cast<std::int64_t>();
    else if (key == "seed") {
      if (v.cast<py::int_>() < py::int_(0)) throw py::value_error("seed must be an integer >= 0");
      o.seed = v.cast<std::uint64_t>();
    }
    else if (key == "partition") k.partition = v.cast<std::string>();
    else if (key == "history_every") o.history_every = v.cast<std::int64_t>();
    else if (key == "test_every") o.test_every = v.cast<std::int64_t>();
    else if (key == "bb_rounds") o.bb_rounds = v.cast<int>();
    else if (key == "esdp_rho") o.esdp_rho = v.cast<double>();
    else if (key == "temporal_block") o.temporal_block = v.cast<int>();
    else if (key == "weights") o.weights = v.cast<std::string>();
    else if (key == "loss") o.loss = v.cast<std::string>();
    else if (key == "check_monotone") { o.check_monotone = v.cast<bool>(); k.check_monotone_given = o.check_monotone; }
    else if (key == "strict") k.strict = v.cast<bool>();
    else if (key == "checkpoint") k.checkpoint = v.cast<std::string>();
    else if (key == "checkpoint_every") k.checkpoint_every = v.cast<std::int64_t>();
    else if (key == "checkpoint_seconds") k.checkpoint_seconds = v.cast<double>();
    else if (key == "restart") k.restart = v.cast<std::string>();
    else if (key == "mode") o.mode = v.cast<std::string>();
    else if (key == "straggler_delay") o.straggler_delay = v.cast<double>();
    else if (key == "straggler_rank") o.straggler_rank = v.cast<int>();
    else if (key == "target_cost") o.target_cost = v.cast<double>();
    else throw py::type_error("solve() got an unexpected keyword argument '" + key + "' (options: " + kSolveKeys + ")");
    } catch (const py::cast_error&) {
      throw py::type_error("solve(): " + key + " cannot be " + py::repr(v).cast<std::string>());
    }
  }
  // As the CLI: ADMM's iterate minimizes neither f nor f_hat, so without stop it takes the papers' rule.
  const snl::AlgorithmInfo* a = snl::find_algorithm(o.algorithm);
  if (!k.stop_given && a && a->admm) o.stop = "papers";
  return k;
}

// The CLI's checks before any work (src/cli/solve.cpp, check_solve_command), same messages.
void check_keywords(const SolveKeywords& k, const Start& start) {
  const std::string unsupported = k.solver.unsupported_option();
  if (!unsupported.empty()) throw snl::Error(unsupported);
  const snl::AlgorithmInfo* alg = snl::find_algorithm(k.solver.algorithm);
  if (k.check_monotone_given && alg && !alg->monotone_surrogate)
    throw snl::Error("check_monotone is not honoured by algorithm " + k.solver.algorithm + " (only by " +
                     snl::algorithms_with(&snl::AlgorithmInfo::monotone_surrogate) + "); leave it out");
  const bool init_given = start.kind != "random" && start.kind != "auto";
  if (alg && alg->one_shot && (init_given || !k.checkpoint.empty() || !k.restart.empty()))
    throw snl::Error(std::string(init_given ? "init" : "checkpoint/restart") + " is not honoured by algorithm " +
                     k.solver.algorithm +
                     " (a convex relaxation solved once: it needs no start and has no iterations to resume)");
  const std::string bad = k.solver.validate();
  if (!bad.empty()) throw snl::Error(bad);
  if (k.checkpoint_every < 0 || !(k.checkpoint_seconds >= 0))
    throw snl::Error("checkpoint_every and checkpoint_seconds must be >= 0");
  if ((k.checkpoint_every > 0 || k.checkpoint_seconds > 0) && k.checkpoint.empty())
    throw snl::Error("checkpoint_every/checkpoint_seconds need checkpoint=FILE");
}

// Owned rows -> every rank's copy of all n rows in file order.
std::vector<double> gather_rows(const snl::LocalizationProblem& prob, const double* owned, int width,
                                MPI_Comm comm) {
  GlobalId off = 0;
  const std::vector<double> mine = prob.owned_to_file_rows(owned, width, &off);
  const int size = snl::comm_size(comm);
  std::vector<int> counts(size), displs(size);
  for (int r = 0; r < size; ++r) {
    GlobalId b, e;
    snl::block_range(prob.num_sensors(), size, r, b, e);
    counts[r] = static_cast<int>((e - b) * width);
    displs[r] = static_cast<int>(b * width);
  }
  std::vector<double> all(static_cast<std::size_t>(prob.num_sensors()) * width);
  MPI_Allgatherv(mine.data(), static_cast<int>(mine.size()), MPI_DOUBLE, all.data(), counts.data(), displs.data(),
                 MPI_DOUBLE, comm);
  return all;
}

// This rank's block of rows of a whole [n * width] array, in the problem's owned order.
std::vector<double> owned_from_rows(const snl::LocalizationProblem& prob, const std::vector<double>& rows, int width,
                                    MPI_Comm comm) {
  GlobalId b, e;
  snl::block_range(prob.num_sensors(), snl::comm_size(comm), snl::comm_rank(comm), b, e);
  const std::vector<double> block(rows.begin() + b * width, rows.begin() + e * width);
  return prob.file_rows_to_owned(block, b, width);
}

std::unique_ptr<snl::LocalizationProblem> make_problem(snl::Network&& slab, snl::PartitionMethod pm,
                                                        snl::ProblemReport* rep, MPI_Comm comm) {
  std::unique_ptr<snl::LocalizationProblem> prob;
  snl::collective_try(comm,
                      [&] { prob = std::make_unique<snl::LocalizationProblem>(comm, std::move(slab), pm, rep); });
  return prob;
}

py::dict history_dict(const std::vector<snl::IterationSummary>& h) {
  py::dict d;
  py::list phase;
  for (const auto& r : h) phase.append(r.phase);
  d["phase"] = phase;
  const py::ssize_t K = static_cast<py::ssize_t>(h.size());
  auto col = [&](auto get) {
    py::array_t<double> a(K);
    for (py::ssize_t i = 0; i < K; ++i) a.mutable_at(i) = get(h[static_cast<std::size_t>(i)]);
    return a;
  };
  auto icol = [&](auto get) {
    py::array_t<std::int64_t> a(K);
    for (py::ssize_t i = 0; i < K; ++i) a.mutable_at(i) = get(h[static_cast<std::size_t>(i)]);
    return a;
  };
  d["iteration"] = icol([](const auto& r) { return r.iteration; });
  d["total_iteration"] = icol([](const auto& r) { return r.total_iteration; });
  d["cost"] = col([](const auto& r) { return r.cost; });
  d["ml_cost"] = col([](const auto& r) { return r.ml_cost; });
  d["rel_change"] = col([](const auto& r) { return r.rel_change; });
  d["grad_norm"] = col([](const auto& r) { return r.grad_norm; });
  d["rmse"] = col([](const auto& r) { return r.rmse; });
  d["mpe"] = col([](const auto& r) { return r.mpe; });
  d["messages"] = col([](const auto& r) { return r.messages; });
  d["reals"] = col([](const auto& r) { return r.reals; });
  d["elapsed"] = col([](const auto& r) { return r.elapsed; });
  return d;
}

// What run_solve does, from a network in memory, without files (src/cli/solve.cpp).
py::dict solve(const PyNetwork* net, const std::string& algorithm, const std::string& init_kind,
               const py::object& init_rows, const py::object& comm_handle, const py::object& progress,
               const py::object& callback, const py::dict& kw) {
  const MPI_Comm comm = to_comm(comm_handle);
  Start start;
  SolveKeywords k;
  snl::PartitionMethod pm{};
  // Checked before any other collective, and agreed: a rank with bad arguments
  // raises its error, the others say so instead of waiting for it.
  std::exception_ptr bad;
  try {
    start.kind = init_kind;
    start.rows = to_vec<double>(init_rows);
    k = parse_keywords(algorithm, kw);
    check_keywords(k, start);
    pm = snl::parse_partition_method(k.partition);
  } catch (...) {
    bad = std::current_exception();
  }
  if (snl::any_rank(comm, bad != nullptr)) {
    if (bad) std::rethrow_exception(bad);
    throw snl::Error("solve: invalid arguments on another rank");
  }
  auto cbs = std::make_unique<PyCallbacks>(comm, progress, callback);

  snl::Summary s;
  std::vector<double> positions, flags;
  snl::ProblemReport rep;
  snl::DvStartReport dv;
  std::string start_used;
  double t0 = 0, t_setup = 0, t_start = 0;
  int dim = 0;
  GlobalId n = 0;
  {
    py::gil_scoped_release nogil;
    t0 = MPI_Wtime();
    std::unique_ptr<snl::LocalizationProblem> prob;
    std::string fingerprint;
    {
      Whole whole;
      whole_network(net, comm, whole);
      std::string err;
      if (whole.net->num_anchors() == 0) err = "the network has no anchors; positions are not determined";
      const GlobalId want = whole.net->num_sensors * whole.net->dim;
      if (start.kind == "positions" && static_cast<GlobalId>(start.rows.size()) != want)
        err = "init has " + std::to_string(start.rows.size()) + " values, expected n * dim = " + std::to_string(want);
      snl::agree(comm, err);
      snl::Network slab = snl::network_slab(*whole.net, comm);
      // Only checkpoints read it (the CLI's load_problem computes it always).
      if (!k.checkpoint.empty() || !k.restart.empty()) fingerprint = snl::network_fingerprint(slab, comm);
      prob = make_problem(std::move(slab), pm, &rep, comm);
    }
    t_setup = MPI_Wtime();
    if (k.strict && rep.unlocalizable > 0)
      throw snl::Error(std::to_string(rep.unlocalizable) + " sensors cannot be localized (strict)");
    dim = prob->dim();
    n = prob->num_sensors();
    // The start, as the CLI's start_kind()/initial_positions().
    start_used = start.kind;
    if (!k.restart.empty()) start_used = "restart";
    else if (start_used == "auto")
      start_used = snl::find_algorithm(k.solver.algorithm)->id == snl::AlgorithmId::kDvPipeline ? "dv" : "random";
    std::vector<double> x0;
    if (start_used == "restart") x0.assign(std::size_t(prob->num_owned()) * dim, 0.0);
    else if (start_used == "random") x0 = snl::random_initial_positions(*prob, k.solver.seed);
    else if (start_used == "dv") x0 = snl::dv_initial_positions(*prob, k.solver.seed, &dv);
    else x0 = owned_from_rows(*prob, start.rows, dim, comm);
    t_start = MPI_Wtime();

    snl::Solver solver(*prob, k.solver);
    solver.add_callback(cbs.get());  // always: it also polls Ctrl-C
    snl::CheckpointConfig cc;
    cc.path = k.checkpoint;
    cc.every = k.checkpoint_every;
    cc.seconds = k.checkpoint_seconds;
    cc.restart = k.restart;
    cc.network_fingerprint = fingerprint;
    solver.set_checkpointing(cc);
    std::vector<double> x;
    s = solver.solve(x0, &x);
    positions = gather_rows(*prob, x.data(), dim, comm);
    std::vector<double> f(prob->flags().begin(), prob->flags().end());
    flags = gather_rows(*prob, f.data(), 1, comm);
  }
  cbs->raise_if_needed();

  py::dict sum;
  sum["algorithm"] = s.algorithm;
  sum["termination"] = snl::to_string(s.termination);
  sum["message"] = s.message;
  sum["iterations"] = s.iterations;
  sum["converged"] = s.converged;
  sum["initial_cost"] = s.initial_cost;
  sum["final_cost"] = s.final_cost;
  sum["ml_cost"] = s.costs.ml;
  sum["relaxed_cost"] = s.costs.relaxed;
  sum["gap_certificate"] = s.gap_certificate;
  sum["relaxed_optimum"] = s.relaxed_optimum;
  sum["apriori_bound"] = s.costs.apriori;
  sum["communications_per_sensor"] = s.messages_per_sensor;
  sum["reals_per_sensor"] = s.reals_per_sensor;
  sum["mpi_bytes"] = s.mpi_bytes;
  sum["comm_wait_fraction"] = s.comm_wait_fraction;
  sum["solve_seconds"] = s.wall_seconds;
  sum["iterate_seconds"] = s.iterate_seconds;
  sum["setup_seconds"] = t_setup - t0;
  sum["start_seconds"] = t_start - t_setup;
  sum["start"] = start_used;
  sum["ranks"] = s.ranks;
  sum["lipschitz"] = s.lipschitz;
  sum["partition"] = rep.partition.method;
  sum["unlocalizable_sensors"] = rep.unlocalizable;
  sum["merged_sensor_pairs"] = rep.merged.merged_sensor_pairs;
  sum["merged_anchor_pairs"] = rep.merged.merged_anchor_pairs;
  if (s.errors.valid) {
    sum["rmse"] = s.errors.rmse;
    sum["mpe"] = s.errors.mpe;
    sum["rmse_localizable"] = s.errors.rmse_localizable;
    sum["mpe_localizable"] = s.errors.mpe_localizable;
  }
  for (const auto& v : s.method_values) sum[py::str(v.first)] = v.second;
  for (const auto& v : s.method_texts) sum[py::str(v.first)] = v.second;
  sum["report"] = s.brief_report();

  py::dict out;
  out["positions"] = to_array(positions, {static_cast<py::ssize_t>(n), dim});
  out["summary"] = sum;
  out["history"] = history_dict(s.history);
  return out;
}

// snl eval's costs and errors (src/cli/eval.cpp: block partition, the same model).
py::dict evaluate(const PyNetwork* net, const py::object& rows_obj, const std::string& weights,
                  const std::string& loss, const py::object& comm_handle) {
  const MPI_Comm comm = to_comm(comm_handle);
  const std::vector<double> rows = to_vec<double>(rows_obj);
  snl::CostTerms costs;
  snl::ErrorMetrics err;
  std::vector<double> flags;
  GlobalId n = 0;
  {
    py::gil_scoped_release nogil;
    Whole whole;
    whole_network(net, comm, whole);
    n = whole.net->num_sensors;
    std::string bad;
    if (static_cast<GlobalId>(rows.size()) != n * whole.net->dim)
      bad = "positions have " + std::to_string(rows.size()) + " values, expected n * dim = " +
            std::to_string(n * whole.net->dim);
    snl::agree(comm, bad);
    snl::ProblemReport rep;
    auto prob = make_problem(snl::network_slab(*whole.net, comm), snl::PartitionMethod::kBlock, &rep, comm);
    std::vector<double> x = owned_from_rows(*prob, rows, prob->dim(), comm);
    x.resize(std::size_t(prob->num_local()) * prob->dim());
    prob->graph().halo().exchange(x.data(), prob->dim());
    prob->set_measurement_model(snl::parse_weights_spec(weights), snl::parse_loss_spec(loss));
    costs = snl::evaluate_costs(*prob, x.data());
    err = snl::evaluate_errors(*prob, x.data());
    std::vector<double> f(prob->flags().begin(), prob->flags().end());
    flags = gather_rows(*prob, f.data(), 1, comm);
  }
  py::dict d;
  d["ml_cost"] = costs.ml;
  d["relaxed_cost"] = costs.relaxed;
  d["gap_certificate"] = costs.certificate;
  d["apriori_bound"] = costs.apriori;
  d["rmse"] = err.rmse;
  d["mpe"] = err.mpe;
  d["rmse_localizable"] = err.rmse_localizable;
  d["mpe_localizable"] = err.mpe_localizable;
  d["num_localizable"] = err.localizable;
  py::array_t<bool> loc(n);
  py::array_t<std::uint8_t> fl(n);
  for (GlobalId i = 0; i < n; ++i) {
    fl.mutable_at(i) = static_cast<std::uint8_t>(flags[static_cast<std::size_t>(i)]);
    loc.mutable_at(i) = flags[static_cast<std::size_t>(i)] == 0;
  }
  d["localizable"] = loc;
  d["flags"] = fl;
  return d;
}

// snl eval --crlb's bound (per-sensor covariance blocks), on the calling process.
py::dict crlb(const PyNetwork& net, double sigma, const py::object& at_rows) {
  const std::vector<double> at = to_vec<double>(at_rows);
  snl::CrlbOptions o;
  o.sigma = sigma;
  o.covariance = true;
  if (!at_rows.is_none()) {
    if (static_cast<GlobalId>(at.size()) != net.net.num_sensors * net.net.dim)
      throw snl::Error("positions have " + std::to_string(at.size()) + " values, expected n * dim = " +
                       std::to_string(net.net.num_sensors * net.net.dim));
    o.positions = &at;
  }
  if (sigma == 0) throw snl::Error("no Cramer-Rao bound: sigma is zero");
  o.validate();
  snl::CrlbResult r;
  {
    py::gil_scoped_release nogil;
    r = snl::cramer_rao_bound(net.net, o);
  }
  if (!r.defined) throw snl::Error("no Cramer-Rao bound: " + r.reason);
  const int p = net.net.dim;
  const GlobalId n = net.net.num_sensors;
  py::dict d;
  d["covariance"] = to_array(r.covariance, {static_cast<py::ssize_t>(n), p, p});
  d["rmse"] = r.rmse;
  d["outside"] = r.outside;
  d["weighted"] = r.weighted;
  return d;
}

PyNetwork from_arrays(int dim, GlobalId n, const py::object& anchors, const py::object& sensor_edges,
                      const py::object& sensor_ranges, const py::object& anchor_edges, const py::object& anchor_ranges,
                      const py::object& truth, const py::object& sigma, const py::object& sensor_sigmas,
                      const py::object& anchor_sigmas) {
  PyNetwork w;
  snl::Network& net = w.net;
  net.dim = dim;
  net.num_sensors = n;
  net.anchors = to_vec<double>(anchors);
  net.sensor_edges = to_vec<GlobalId>(sensor_edges);
  net.sensor_ranges = to_vec<double>(sensor_ranges);
  net.anchor_edges = to_vec<GlobalId>(anchor_edges);
  net.anchor_ranges = to_vec<double>(anchor_ranges);
  net.has_truth = !truth.is_none();
  net.truth = to_vec<double>(truth);
  if (!sigma.is_none()) net.sigma = sigma.cast<double>();
  net.sensor_sigmas = to_vec<double>(sensor_sigmas);
  net.anchor_sigmas = to_vec<double>(anchor_sigmas);
  net.total_sensor_edges = net.local_sensor_edges();
  net.total_anchor_edges = net.local_anchor_edges();
  const snl::NetworkIssue issue = snl::check_network(net, true);
  if (!issue.ok()) throw snl::Error(issue.message);
  return w;
}

PyNetwork generate(const py::dict& kw) {
  snl::GenerateOptions o;
  snl::NoiseOptions noise;
  std::string anchors = "auto", localizable = "auto", topology = "random";
  for (const auto& item : kw) {
    const std::string key = item.first.cast<std::string>();
    const py::handle v = item.second;
    if (v.is_none()) continue;
    try {
    if (key == "sensors" || key == "n_sensors") o.sensors = v.cast<GlobalId>();
    else if (key == "dim") o.dim = v.cast<int>();
    else if (key == "avg_degree") o.avg_degree = v.cast<double>();
    else if (key == "sigma") o.sigma = v.cast<double>();
    else if (key == "sigma_rel") o.sigma_rel = v.cast<double>();
    else if (key == "side") o.side = v.cast<double>();
    else if (key == "anchors") anchors = py::str(v).cast<std::string>();
    else if (key == "anchor_radius") o.anchor_radius = v.cast<double>();
    else if (key == "seed") {
      if (v.cast<py::int_>() < py::int_(0)) throw py::value_error("seed must be an integer >= 0");
      o.seed = v.cast<std::uint64_t>();
    }
    else if (key == "localizable") localizable = v.cast<std::string>();
    else if (key == "max_draws") o.max_draws = v.cast<int>();
    else if (key == "topology") topology = v.cast<std::string>();
    else if (key == "star_center") o.star_center = v.cast<double>();
    else if (key == "star_anchors") o.star_anchors = v.cast<std::vector<double>>();
    else if (key == "noise") noise.model = v.cast<std::string>();
    else if (key == "nlos_fraction") noise.nlos_fraction = v.cast<double>();
    else if (key == "nlos_bias") noise.nlos_bias = v.cast<double>();
    else
      throw py::type_error("generate() got an unexpected keyword argument '" + key +
                           "' (options: sensors, dim, avg_degree, sigma, sigma_rel, side, anchors, anchor_radius, "
                           "seed, localizable, max_draws, topology, star_center, star_anchors, noise, "
                           "nlos_fraction, nlos_bias)");
    } catch (const py::cast_error&) {
      throw py::type_error("generate(): " + key + " cannot be " + py::repr(v).cast<std::string>());
    }
  }
  // The CLI's parse_generate_choices (apps/snl_main.cpp), same messages.
  if (anchors == "auto") o.num_random_anchors = snl::kAutoAnchors;
  else if (anchors == "corners") o.num_random_anchors = 0;
  else {
    try {
      std::size_t pos = 0;
      o.num_random_anchors = std::stoi(anchors, &pos);
      if (pos != anchors.size() || o.num_random_anchors < 1) throw std::invalid_argument("");
    } catch (const std::exception&) {
      throw snl::Error("--anchors must be 'auto', 'corners' or a positive number, not '" + anchors + "'");
    }
  }
  if (localizable == "auto") o.localizable = snl::GenerateOptions::Localizable::kAuto;
  else if (localizable == "yes") o.localizable = snl::GenerateOptions::Localizable::kYes;
  else if (localizable == "no") o.localizable = snl::GenerateOptions::Localizable::kNo;
  else throw snl::Error("--localizable must be auto, yes or no");
  if (topology == "random") o.topology = snl::GenerateOptions::Topology::kRandom;
  else if (topology == "star") o.topology = snl::GenerateOptions::Topology::kStar;
  else throw snl::Error("--topology must be random or star");
  // run_generate's steps (src/cli/generate.cpp).
  const std::string bad = o.validate();
  if (!bad.empty()) throw snl::Error(bad);
  const std::string bad_noise = noise.validate();
  if (!bad_noise.empty()) throw snl::Error(bad_noise);
  PyNetwork w;
  py::gil_scoped_release nogil;
  snl::GenerateReport rep;
  w.net = snl::generate_network(o, &rep);
  if (noise.changes_network()) snl::apply_noise_model(w.net, noise, o.sigma, rep.draw_seed);
  return w;
}

PyNetwork from_csv(const std::string& sensor_edges, const std::string& anchor_edges, const std::string& anchors,
                   const std::string& truth, GlobalId sensors, int index_base, double sigma) {
  // snl import's steps (src/cli/import.cpp).
  auto read = [](const std::string& path) {
    FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) throw snl::Error(path + ": cannot open (" + std::strerror(errno) + ")");
    std::string s;
    char buf[65536];
    std::size_t k;
    while ((k = std::fread(buf, 1, sizeof buf, f)) > 0) s.append(buf, k);
    std::fclose(f);
    return snl::text::TextFile{path, s};
  };
  snl::text::ImportInput in;
  in.sensor_edges = read(sensor_edges);
  in.anchor_edges = read(anchor_edges);
  in.anchors = read(anchors);
  if (!truth.empty()) in.truth = read(truth);
  snl::text::ImportOptions o;
  o.sensors = sensors;
  o.index_base = index_base;
  o.sigma = sigma;
  const std::string bad = o.validate();
  if (!bad.empty()) throw snl::Error(bad);
  PyNetwork w;
  w.net = snl::text::import_network(in, o);
  return w;
}

// save: rank 0 of comm writes; every rank learns of a failure.
void save(const PyNetwork& w, const std::string& path, const py::object& comm_handle) {
  const MPI_Comm comm = to_comm(comm_handle);
  py::gil_scoped_release nogil;
  snl::collective_try(comm, [&] {
    if (snl::comm_rank(comm) == 0) snl::write_network(path, w.net);
  });
}

}  // namespace

PYBIND11_MODULE(_snl, m) {
  m.doc() = "libsnl bindings (use the snl package)";
  static py::exception<snl::Error> error(m, "Error", PyExc_ValueError);
  py::register_exception<snl::NumericalFailure>(m, "NumericalFailure", error.ptr());
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const snl::NumericalFailure& e) {
      throw;
    } catch (const snl::Error& e) {
      PyErr_SetString(error.ptr(), e.what());
    }
  });

  m.def("init_mpi", [] {
    int flag = 0;
    MPI_Initialized(&flag);
    if (flag) return false;
    int provided = 0;
    MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
    g_owns_mpi = true;
    return true;
  });
  m.def("finalize_mpi", [] {
    int fin = 0;
    MPI_Finalized(&fin);
    if (g_owns_mpi && !fin) MPI_Finalize();
  });
  m.def("comm_rank", [](const py::object& c) { return snl::comm_rank(to_comm(c)); }, py::arg("comm") = py::none());
  m.def("comm_size", [](const py::object& c) { return snl::comm_size(to_comm(c)); }, py::arg("comm") = py::none());
  m.def("default_algorithm", [] { return snl::SolverOptions().algorithm; });
  m.def("algorithms", [] {
    py::list l;
    for (const auto& a : snl::algorithm_registry()) l.append(a.name);
    return l;
  });

  py::class_<PyNetwork>(m, "_Network")
      .def_property_readonly("dim", [](const PyNetwork& w) { return w.net.dim; })
      .def_property_readonly("n_sensors", [](const PyNetwork& w) { return w.net.num_sensors; })
      .def_property_readonly("n_anchors", [](const PyNetwork& w) { return w.net.num_anchors(); })
      .def_property_readonly("anchors", [](const PyNetwork& w) {
        return to_array(w.net.anchors, {static_cast<py::ssize_t>(w.net.num_anchors()), w.net.dim});
      })
      .def_property_readonly("sensor_edges", [](const PyNetwork& w) {
        return to_array(w.net.sensor_edges, {static_cast<py::ssize_t>(w.net.local_sensor_edges()), 2});
      })
      .def_property_readonly("sensor_ranges", [](const PyNetwork& w) {
        return to_array(w.net.sensor_ranges, {static_cast<py::ssize_t>(w.net.local_sensor_edges())});
      })
      .def_property_readonly("anchor_edges", [](const PyNetwork& w) {
        return to_array(w.net.anchor_edges, {static_cast<py::ssize_t>(w.net.local_anchor_edges()), 2});
      })
      .def_property_readonly("anchor_ranges", [](const PyNetwork& w) {
        return to_array(w.net.anchor_ranges, {static_cast<py::ssize_t>(w.net.local_anchor_edges())});
      })
      .def_property_readonly("sensor_sigmas", [](const PyNetwork& w) -> py::object {
        if (w.net.sensor_sigmas.empty()) return py::none();
        return to_array(w.net.sensor_sigmas, {static_cast<py::ssize_t>(w.net.sensor_sigmas.size())});
      })
      .def_property_readonly("anchor_sigmas", [](const PyNetwork& w) -> py::object {
        if (w.net.anchor_sigmas.empty()) return py::none();
        return to_array(w.net.anchor_sigmas, {static_cast<py::ssize_t>(w.net.anchor_sigmas.size())});
      })
      .def_property_readonly("truth", [](const PyNetwork& w) -> py::object {
        if (!w.net.has_truth) return py::none();
        return to_array(w.net.truth, {static_cast<py::ssize_t>(w.net.num_sensors), w.net.dim});
      })
      .def_property_readonly("sigma", [](const PyNetwork& w) -> py::object {
        return w.net.sigma ? py::object(py::float_(*w.net.sigma)) : py::none();
      })
      .def("save", &save, py::arg("path"), py::arg("comm") = py::none());

  m.def("from_arrays", &from_arrays);
  m.def("read_network", [](const std::string& path) {
    PyNetwork w;
    py::gil_scoped_release nogil;
    w.net = snl::read_network_serial(path);
    return w;
  });
  m.def("from_csv", &from_csv);
  m.def("generate", &generate);
  m.def("solve", &solve);
  m.def("evaluate", &evaluate);
  m.def("crlb", &crlb);
  snl_py::add_consensus(m);
}
