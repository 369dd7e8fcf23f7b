#include "snl/cli/commands.hpp"

#include "kernels/kernels.hpp"

#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include "snl/problem/analysis.hpp"
#include "core/json.hpp"
#include "snl/core/mpi_util.hpp"
#include "snl/io/network.hpp"
#include "snl/io/result_io.hpp"

namespace snl {

namespace {

bool is_root(MPI_Comm comm) { return comm_rank(comm) == 0; }

std::string dir_of(const std::string& path) {
  const auto s = path.find_last_of('/');
  if (s == std::string::npos) return ".";
  if (s == 0) return "/";
  return path.substr(0, s);
}

std::string fmt(double v, int prec = 6) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*g", prec, v);
  return b;
}

// Progress on rank 0 at recorded iterations, at most every `period` seconds.
class ProgressPrinter : public IterationCallback {
 public:
  ProgressPrinter(MPI_Comm comm, double period, std::int64_t max_iter, int phases)
      : root_(is_root(comm)), period_(period), max_iter_(max_iter), phases_(phases) {}
  CallbackReturn operator()(const IterationSummary& s) override {
    if (!root_) return CallbackReturn::kContinue;
    if (s.phase != phase_) {
      phase_ = s.phase;
      ++phase_index_;
      phase_start_ = s.elapsed;
      last_ = -1e300;
      std::fprintf(stderr, "%-10s %10s %14s %14s %11s %11s %9s %9s\n", "phase", "iter", "cost", "ml_cost",
                   "rel_change", "rmse", "elapsed", "eta");
    }
    if (s.elapsed - last_ < period_ && s.iteration != max_iter_) return CallbackReturn::kContinue;
    last_ = s.elapsed;
    const double per_it = s.iteration > 0 ? (s.elapsed - phase_start_) / s.iteration : 0;
    const double eta = per_it * (max_iter_ - s.iteration) + (phases_ - phase_index_) * per_it * max_iter_;
    std::fprintf(stderr, "%-10s %10lld %14.8g %14.8g %11.3e %11.4g %8.1fs %8.0fs\n", s.phase.c_str(),
                 static_cast<long long>(s.iteration), s.cost, s.ml_cost, s.rel_change, s.rmse, s.elapsed, eta);
    return CallbackReturn::kContinue;
  }

 private:
  bool root_;
  double period_;
  std::int64_t max_iter_;
  int phases_;
  std::string phase_;
  int phase_index_ = 0;
  double phase_start_ = 0, last_ = -1e300;
};


}  // namespace

void write_text_atomic(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp-" + std::to_string(getpid());
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f) throw Error(path + ": cannot create file (" + std::strerror(errno) + ")");
    f << text;
    f.flush();
    if (!f) {
      std::remove(tmp.c_str());
      throw Error(path + ": write failed (disk full?)");
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    std::remove(tmp.c_str());
    throw Error(path + ": cannot rename temporary file (" + why + ")");
  }
}

void check_output_path(const std::string& path, MPI_Comm comm) {
  std::string err;
  if (is_root(comm)) {
    const std::string d = dir_of(path);
    if (path.empty())
      err = "empty output path";
    else if (access(d.c_str(), F_OK) != 0)
      err = path + ": directory '" + d + "' does not exist";
    else if (access(d.c_str(), W_OK) != 0)
      err = path + ": directory '" + d + "' is not writable";
    else if (access(path.c_str(), F_OK) == 0 && access(path.c_str(), W_OK) != 0)
      err = path + ": file exists and is not writable";
    else if (struct stat st {}; stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode))
      err = path + (S_ISDIR(st.st_mode) ? ": is a directory"
                                        : ": exists and is not a regular file (e.g. a device); refusing to replace it");
  }
  agree(comm, err);
}

// ---------------------------------------------------------------------------
void run_generate(const GenerateCommand& cmd, MPI_Comm comm) {
  const std::string bad = cmd.options.validate();
  if (!bad.empty()) throw Error(bad);
  check_output_path(cmd.output, comm);
  std::string summary;
  collective_try(comm, [&] {
    if (!is_root(comm)) return;
    const double t0 = MPI_Wtime();
    GenerateReport rep;
    Network net = generate_network(cmd.options, &rep);
    const double t1 = MPI_Wtime();
    write_network(cmd.output, net);
    const double t2 = MPI_Wtime();
    std::ostringstream os;
    os << "generated " << cmd.output << ": n=" << net.num_sensors << " m=" << net.num_anchors() << " p=" << net.dim
       << ", " << net.local_sensor_edges() << " sensor pairs (average degree " << fmt(rep.achieved_avg_degree, 4)
       << ", radius " << fmt(rep.radius, 5) << "), " << net.local_anchor_edges() << " anchor pairs (radius "
       << fmt(rep.anchor_radius, 5) << "), sigma " << cmd.options.sigma << ", seed " << cmd.options.seed << "\n"
       << "draws: " << rep.draws << "\n"
       << rep.localizability.summary() << "\n"
       << "time: generate " << fmt(t1 - t0, 3) << " s, write " << fmt(t2 - t1, 3) << " s";
    summary = os.str();
  });
  if (is_root(comm) && !cmd.quiet) std::printf("%s\n", summary.c_str());
}

// ---------------------------------------------------------------------------
void run_info(const InfoCommand& cmd, MPI_Comm comm) {
  std::string text, json;
  bool unlocalizable = false;
  collective_try(comm, [&] {
    if (!is_root(comm)) return;
    Network net = read_network_serial(cmd.network);
    const MergeStats ms = merge_duplicates(net.sensor_edges, net.sensor_ranges, net.anchor_edges, net.anchor_ranges);
    net.total_sensor_edges = net.local_sensor_edges();
    net.total_anchor_edges = net.local_anchor_edges();
    const DegreeStats ds = degree_stats(net);
    const bool rig = net.has_truth && net.num_sensors <= kRigidityLimit;
    const LocalizabilityReport lr = analyze_localizability(net, rig);
    std::ostringstream os;
    os << cmd.network << ": valid snl-network v1\n"
       << "  sensors n = " << net.num_sensors << ", anchors m = " << net.num_anchors() << ", dimension p = " << net.dim
       << "\n"
       << "  sensor pairs = " << net.local_sensor_edges() << " (" << ms.merged_sensor_pairs
       << " duplicate rows merged), anchor pairs = " << net.local_anchor_edges() << " (" << ms.merged_anchor_pairs
       << " merged)\n"
       << "  sensor degree: mean " << fmt(ds.mean, 4) << ", min " << ds.min << ", max " << ds.max
       << "; anchor measurements per sensor: mean " << fmt(ds.mean_anchor, 4) << ", max " << ds.max_anchor << "\n"
       << "  truth: " << (net.has_truth ? "present" : "absent")
       << ", sigma: " << (net.sigma ? fmt(*net.sigma) : std::string("unknown")) << "\n"
       << "  " << lr.summary();
    if (!rig) os << "\n  (rigidity not checked: " << (net.has_truth ? "n > 20000" : "no truth positions") << ")";
    if (net.num_anchors() == 0) os << "\n  warning: no anchors; snl solve needs at least one";
    text = os.str();
    unlocalizable = !lr.localizable();
    JsonObject j;
    j.add("network", cmd.network)
        .add("num_sensors", static_cast<std::int64_t>(net.num_sensors))
        .add("num_anchors", static_cast<std::int64_t>(net.num_anchors()))
        .add("dim", net.dim)
        .add("sensor_pairs", static_cast<std::int64_t>(net.local_sensor_edges()))
        .add("anchor_pairs", static_cast<std::int64_t>(net.local_anchor_edges()))
        .add("merged_sensor_rows", static_cast<std::int64_t>(ms.merged_sensor_pairs))
        .add("merged_anchor_rows", static_cast<std::int64_t>(ms.merged_anchor_pairs))
        .add("mean_degree", ds.mean)
        .add("min_degree", ds.min)
        .add("max_degree", ds.max)
        .add("components", static_cast<std::int64_t>(lr.components))
        .add("unanchored_sensors", static_cast<std::int64_t>(lr.unanchored.size()))
        .add("few_measurement_sensors", static_cast<std::int64_t>(lr.few_measurements.size()))
        .add_bool("rigidity_checked", lr.rigidity_checked)
        .add_bool("rigid", lr.rigid)
        .add_bool("localizable", lr.localizable())
        .add_bool("has_truth", net.has_truth);
    json = j.str();
    if (!cmd.json.empty()) write_text_atomic(cmd.json, json);
  });
  if (is_root(comm)) std::printf("%s\n", text.c_str());
  int bad = unlocalizable ? 1 : 0;
  MPI_Bcast(&bad, 1, MPI_INT, 0, comm);
  if (cmd.strict && bad) throw Error(cmd.network + ": some sensors cannot be localized (--strict)");
}

// ---------------------------------------------------------------------------
int run_solve(const SolveCommand& cmd, MPI_Comm comm) {
  const std::string bad = cmd.solver.validate();
  if (!bad.empty()) throw Error(bad);
  const PartitionMethod pm = parse_partition_method(cmd.partition);
  check_output_path(cmd.output, comm);
  if (!cmd.json.empty()) check_output_path(cmd.json, comm);
  if (cmd.checkpoint_every < 0 || !(cmd.checkpoint_seconds >= 0))
    throw Error("--checkpoint-every and --checkpoint-seconds must be >= 0");
  if ((cmd.checkpoint_every > 0 || cmd.checkpoint_seconds > 0) && cmd.checkpoint.empty())
    throw Error("--checkpoint-every/--checkpoint-seconds need --checkpoint FILE");
  if (!cmd.checkpoint.empty()) check_output_path(cmd.checkpoint, comm);
  if (!cmd.checkpoint.empty()) install_stop_signal_handlers();
  const bool root = is_root(comm);
  const bool talk = root && !cmd.quiet;
  const double t0 = MPI_Wtime();

  Network slab = read_network(cmd.network, comm);
  if (slab.num_anchors() == 0) throw Error(cmd.network + ": the network has no anchors; positions are not determined");
  const double t_read = MPI_Wtime();

  const std::string fingerprint = network_fingerprint(slab, comm);
  ProblemReport rep;
  std::unique_ptr<LocalizationProblem> prob;
  collective_try(comm, [&] { prob = std::make_unique<LocalizationProblem>(comm, slab, pm, &rep); });
  slab = Network();  // the problem holds what it needs
  const double t_setup = MPI_Wtime();
  if (talk) {
    std::fprintf(stderr,
                 "snl solve: n=%lld m=%lld p=%d, %lld sensor pairs, %lld anchor pairs (%lld+%lld duplicate rows "
                 "merged)\n",
                 static_cast<long long>(prob->num_sensors()), static_cast<long long>(prob->num_anchors()), prob->dim(),
                 static_cast<long long>(rep.num_sensor_edges), static_cast<long long>(rep.num_anchor_edges),
                 static_cast<long long>(rep.merged.merged_sensor_pairs),
                 static_cast<long long>(rep.merged.merged_anchor_pairs));
    std::fprintf(stderr, "partition: %s on %d ranks, edge cut %lld, imbalance %.3f, ghosts %lld (max %lld/rank)%s%s\n",
                 rep.partition.method.c_str(), comm_size(comm), static_cast<long long>(rep.partition.edge_cut),
                 rep.partition.imbalance, static_cast<long long>(rep.partition.total_ghosts),
                 static_cast<long long>(rep.partition.max_ghosts), rep.partition.note.empty() ? "" : "; ",
                 rep.partition.note.c_str());
    if (rep.unlocalizable > 0) {
      std::string ids;
      for (auto g : rep.unlocalizable_sample) ids += " " + std::to_string(g);
      std::fprintf(stderr,
                   "warning: %lld sensors cannot be localized (%lld in components without anchors, %lld with fewer "
                   "than p+1 measurements); e.g.%s%s. Metrics count them apart (rmse_localizable).\n",
                   static_cast<long long>(rep.unlocalizable), static_cast<long long>(rep.unanchored),
                   static_cast<long long>(rep.few_measurements), ids.c_str(),
                   rep.unlocalizable > static_cast<GlobalId>(rep.unlocalizable_sample.size()) ? " ..." : "");
    }
  }
  if (cmd.strict && rep.unlocalizable > 0)
    throw Error(cmd.network + ": " + std::to_string(rep.unlocalizable) + " sensors cannot be localized (--strict)");

  std::vector<double> x0;
  if (!cmd.restart.empty()) {
    x0.assign(std::size_t(prob->num_owned()) * prob->dim(), 0.0);  // replaced by the checkpoint's state
  } else if (cmd.init == "random") {
    x0 = random_initial_positions(*prob, cmd.solver.seed);
  } else {
    GlobalId b, e;
    block_range(prob->num_sensors(), comm_size(comm), comm_rank(comm), b, e);
    const auto rows = read_positions(cmd.init, comm, prob->num_sensors(), prob->dim(), b, e - b);
    x0 = prob->file_rows_to_owned(rows, b, prob->dim());
  }

  Solver solver(*prob, cmd.solver);
  ProgressPrinter progress(comm, cmd.progress_seconds, cmd.solver.max_iter,
                           cmd.solver.algorithm == "pipeline" ? 2 : 1);
  if (!cmd.quiet) solver.add_callback(&progress);
  CheckpointConfig cc;
  cc.path = cmd.checkpoint;
  cc.every = cmd.checkpoint_every;
  cc.seconds = cmd.checkpoint_seconds;
  cc.restart = cmd.restart;
  cc.network_fingerprint = fingerprint;
  cc.stop_on_signal = !cmd.checkpoint.empty();
  solver.set_checkpointing(cc);
  std::vector<double> x;
  Summary s = solver.solve(x0, &x);
  const double t_solve = MPI_Wtime();
  if (s.termination == TerminationType::kSignal) {
    if (talk) std::fprintf(stderr, "snl solve: %s; resume with --restart %s\n", s.message.c_str(), cmd.checkpoint.c_str());
    return kExitCheckpointed;
  }

  // Result file: positions back in file order, history, summary attributes.
  ResultFile r;
  r.algorithm = cmd.solver.algorithm;
  r.iterations = s.iterations;
  r.converged = s.converged;
  r.dim = prob->dim();
  r.num_sensors = prob->num_sensors();
  r.positions = prob->owned_to_file_rows(x.data(), prob->dim(), &r.row_offset);
  auto series = [&](const char* name, auto get) {
    std::vector<double> v;
    v.reserve(s.history.size());
    for (const auto& h : s.history) v.push_back(get(h));
    r.history.emplace_back(name, std::move(v));
  };
  series("iteration", [](const IterationSummary& h) { return double(h.total_iteration); });
  series("phase_iteration", [](const IterationSummary& h) { return double(h.iteration); });
  series("phase", [](const IterationSummary& h) { return double(algorithm_code(h.phase)); });
  series("cost", [](const IterationSummary& h) { return h.cost; });
  series("ml_cost", [](const IterationSummary& h) { return h.ml_cost; });
  series("communications", [](const IterationSummary& h) { return h.messages; });
  series("reals", [](const IterationSummary& h) { return h.reals; });
  series("rel_change", [](const IterationSummary& h) { return h.rel_change; });
  series("grad_norm", [](const IterationSummary& h) { return h.grad_norm; });
  series("elapsed", [](const IterationSummary& h) { return h.elapsed; });
  if (s.errors.valid) {
    series("rmse", [](const IterationSummary& h) { return h.rmse; });
    series("mpe", [](const IterationSummary& h) { return h.mpe; });
  }
  r.string_attrs = {{"termination", to_string(s.termination)},
                    {"message", s.message},
                    {"network", cmd.network},
                    {"partition", rep.partition.method},
                    {"history_phase_codes", algorithm_codes_legend()}};
  r.double_attrs = {{"ml_cost", s.costs.ml},
                    {"relaxed_cost", s.costs.relaxed},
                    {"gap_certificate", s.gap_certificate},
                    {"apriori_bound", s.costs.apriori},
                    {"messages_per_sensor", s.messages_per_sensor},
                    {"reals_per_sensor", s.reals_per_sensor},
                    {"mpi_bytes", double(s.mpi_bytes)},
                    {"wall_seconds", s.wall_seconds},
                    {"ranks", double(s.ranks)},
                    {"seed", double(cmd.solver.seed)},
                    {"temporal_block", double(cmd.solver.temporal_block)},
                    {"lipschitz", s.lipschitz}};
  if (s.errors.valid) {
    r.double_attrs.push_back({"rmse", s.errors.rmse});
    r.double_attrs.push_back({"mpe", s.errors.mpe});
  }
  write_result(cmd.output, comm, r);
  const double t_write = MPI_Wtime();

  if (!cmd.json.empty()) {
    // Performance report (docs/performance.md): peak RSS of every rank (the
    // METIS graph on rank 0 included), halo volume, bytes of solver state.
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    long long loc[4] = {static_cast<long long>(ru.ru_maxrss) * 1024,  // Linux: KiB
                        static_cast<long long>(prob->graph().halo().send_volume()),
                        static_cast<long long>(prob->memory_bytes()), static_cast<long long>(prob->num_owned())},
              tot[4], mx[4];
    MPI_Allreduce(loc, tot, 4, MPI_LONG_LONG, MPI_SUM, comm);
    MPI_Allreduce(loc, mx, 4, MPI_LONG_LONG, MPI_MAX, comm);
    const double n_sens = static_cast<double>(prob->num_sensors());
    const std::int64_t iters = s.iterations;
    JsonObject j;
    j.add("algorithm", cmd.solver.algorithm)
        .add("iterations", static_cast<std::int64_t>(s.iterations))
        .add_bool("converged", s.converged)
        .add("termination", to_string(s.termination))
        .add("message", s.message)
        .add("ml_cost", s.costs.ml)
        .add("relaxed_cost", s.costs.relaxed)
        .add("gap_certificate", s.gap_certificate)
        .add("relaxed_optimum", s.relaxed_optimum)
        .add("apriori_bound", s.costs.apriori)
        .add("communications_per_sensor", s.messages_per_sensor)
        .add("reals_per_sensor", s.reals_per_sensor)
        .add("mpi_bytes", static_cast<std::int64_t>(s.mpi_bytes))
        .add("comm_wait_fraction", s.comm_wait_fraction)
        .add("wall_seconds", t_write - t0)
        .add("solve_seconds", s.wall_seconds)
        .add("read_seconds", t_read - t0)
        .add("setup_seconds", t_setup - t_read)
        .add("write_seconds", t_write - t_solve)
        .add("ranks", s.ranks)
        .add("num_sensors", static_cast<std::int64_t>(prob->num_sensors()))
        .add("num_anchors", static_cast<std::int64_t>(prob->num_anchors()))
        .add("sensor_pairs", static_cast<std::int64_t>(rep.num_sensor_edges))
        .add("anchor_pairs", static_cast<std::int64_t>(rep.num_anchor_edges))
        .add("partition", rep.partition.method)
        .add("edge_cut", static_cast<std::int64_t>(rep.partition.edge_cut))
        .add("ghosts", static_cast<std::int64_t>(rep.partition.total_ghosts))
        .add("unlocalizable_sensors", static_cast<std::int64_t>(rep.unlocalizable))
        .add("lipschitz", s.lipschitz)
        .add("iterate_seconds", s.iterate_seconds)
        .add("seconds_per_iteration", iters > 0 ? s.iterate_seconds / double(iters) : 0.0)
        .add("iterate_wait_fraction", s.iterate_seconds > 0 ? s.iterate_wait_seconds / s.iterate_seconds : 0.0)
        .add("peak_rss_bytes_total", static_cast<std::int64_t>(tot[0]))
        .add("peak_rss_bytes_max", static_cast<std::int64_t>(mx[0]))
        .add("max_owned", static_cast<std::int64_t>(mx[3]))
        .add("max_ghosts", static_cast<std::int64_t>(rep.partition.max_ghosts))
        .add("halo_nodes_sent_per_iteration", static_cast<std::int64_t>(tot[1]))
        .add("halo_bytes_per_iteration", static_cast<std::int64_t>(tot[1]) * prob->dim() * std::int64_t(sizeof(double)))
        .add("problem_bytes", static_cast<std::int64_t>(tot[2]))
        .add("algorithm_state_bytes", static_cast<std::int64_t>(s.algorithm_state_bytes))
        .add("state_bytes_per_sensor", (double(tot[2]) + double(s.algorithm_state_bytes)) / n_sens)
        .add("local_order", default_local_ordering() == LocalOrdering::kRcm ? "rcm" : "gid");
    for (const auto& ph : s.phase_iterate_seconds) j.add(ph.first + "_iterate_seconds", ph.second);
    for (const auto& ph : s.phase_traffic_bytes)
      if (std::isfinite(ph.second)) j.add(ph.first + "_traffic_bytes_per_iteration", ph.second);
    j.add("simd", detail::simd_name());
    j.add("temporal_block", cmd.solver.temporal_block);
    for (const auto& ph : rep.setup_phases) j.add("setup_" + ph.first + "_seconds", ph.second);
    if (s.errors.valid) {
      j.add("rmse", s.errors.rmse).add("mpe", s.errors.mpe);
      j.add("rmse_localizable", s.errors.rmse_localizable).add("mpe_localizable", s.errors.mpe_localizable);
    }
    std::string err;
    if (root) {
      try {
        write_text_atomic(cmd.json, j.str());
      } catch (const std::exception& e) {
        err = e.what();
      }
    }
    agree(comm, err);
  }
  if (talk) std::fprintf(stderr, "%s\n", s.brief_report().c_str());
  return s.termination == TerminationType::kFailure ? 4 : 0;
}

// ---------------------------------------------------------------------------
void run_eval(const EvalCommand& cmd, MPI_Comm comm) {
  Network slab = read_network(cmd.network, comm);
  if (slab.num_anchors() == 0) throw Error(cmd.network + ": the network has no anchors");
  std::optional<double> sigma = slab.sigma;
  Network whole;
  if (cmd.crlb) {
    collective_try(comm, [&] {
      if (is_root(comm)) {
        whole = read_network_serial(cmd.network);
        merge_duplicates(whole.sensor_edges, whole.sensor_ranges, whole.anchor_edges, whole.anchor_ranges);
      }
    });
  }
  ProblemReport rep;
  std::unique_ptr<LocalizationProblem> prob;
  collective_try(comm,
                 [&] { prob = std::make_unique<LocalizationProblem>(comm, slab, PartitionMethod::kBlock, &rep); });
  const GlobalId row0 = slab.sensor_row_offset;
  const GlobalId rows = slab.has_truth ? GlobalId(slab.truth.size() / slab.dim) : [&] {
    GlobalId b, e;
    block_range(slab.num_sensors, comm_size(comm), comm_rank(comm), b, e);
    return e - b;
  }();
  const auto xr = read_positions(cmd.result, comm, prob->num_sensors(), prob->dim(), row0, rows);
  std::vector<double> x = prob->file_rows_to_owned(xr, row0, prob->dim());
  x.resize(std::size_t(prob->num_local()) * prob->dim());
  prob->graph().halo().exchange(x.data(), prob->dim());
  const CostTerms c = evaluate_costs(*prob, x.data());
  const ErrorMetrics em = evaluate_errors(*prob, x.data());
  CrlbResult cr;
  std::string crlb_err;
  if (cmd.crlb && is_root(comm)) {
    const double sg = cmd.sigma >= 0 ? cmd.sigma : (sigma ? *sigma : -1);
    if (sg <= 0) {
      cr.reason = "sigma unknown (give --sigma) or zero";
    } else {
      try {
        cr = cramer_rao_bound(whole, sg);
      } catch (const std::exception& e) {
        crlb_err = e.what();
      }
    }
  }
  agree(comm, crlb_err);
  if (is_root(comm)) {
    std::printf("%s on %s\n", cmd.result.c_str(), cmd.network.c_str());
    std::printf("  ML cost f = %.10g\n  relaxed cost f_hat = %.10g\n  sum of nonconvex terms of edges inside their disks = %.6g (the 003 eq. 22 certificate when RESULT minimizes f_hat)\n"
                "  a-priori bound (003 eq. 23) = %.6g\n",
                c.ml, c.relaxed, c.certificate, c.apriori);
    if (em.valid)
      std::printf("  RMSE = %.6g, MPE = %.6g (over all %lld sensors); over %lld localizable: RMSE %.6g, MPE %.6g\n",
                  em.rmse, em.mpe, static_cast<long long>(prob->num_sensors()),
                  static_cast<long long>(em.localizable), em.rmse_localizable, em.mpe_localizable);
    else
      std::printf("  no truth in the network: RMSE/MPE unavailable\n");
    if (cmd.crlb) {
      if (cr.defined)
        std::printf("  Cramer-Rao bound RMSE_CRLB = %.6g\n", cr.rmse);
      else
        std::printf("  Cramer-Rao bound: not defined (%s)\n", cr.reason.c_str());
    }
  }
  if (!cmd.json.empty()) {
    JsonObject j;
    j.add("network", cmd.network).add("result", cmd.result).add("ml_cost", c.ml).add("relaxed_cost", c.relaxed);
    j.add("gap_certificate", c.certificate).add("apriori_bound", c.apriori);
    if (em.valid) j.add("rmse", em.rmse).add("mpe", em.mpe).add("rmse_localizable", em.rmse_localizable);
    if (cmd.crlb) {
      j.add_bool("crlb_defined", cr.defined);
      if (cr.defined) j.add("crlb_rmse", cr.rmse);
      else j.add("crlb_reason", cr.reason);
    }
    std::string err;
    if (is_root(comm)) {
      try {
        write_text_atomic(cmd.json, j.str());
      } catch (const std::exception& e) {
        err = e.what();
      }
    }
    agree(comm, err);
  }
}

}  // namespace snl
