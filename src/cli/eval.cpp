// snl eval: costs, errors and the Cramer-Rao bound of a result on a network.
#include <cstdio>
#include <optional>

#include "cli/cli_util.hpp"
#include "core/json.hpp"
#include "snl/cli/commands.hpp"
#include "snl/io/network.hpp"
#include "snl/io/result_io.hpp"
#include "snl/problem/analysis.hpp"
#include "snl/problem/global_1d.hpp"

namespace snl {

namespace {

using detail::is_root;

// What snl eval reports.
struct Evaluation {
  CostTerms costs;
  ErrorMetrics errors;
  GlobalId num_sensors = 0;
  CrlbResult crlb;
  std::string crlb_at;            ///< "truth" or "estimate"
  bool covariance_written = false;
  bool has_global = false;        ///< --global-opt ran
  GlobalOptimum1D global;
};

// The costs and errors of the result's positions on the network (block partition).
void evaluate_result(const EvalCommand& cmd, Network& slab, MPI_Comm comm, Evaluation& ev) {
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
  prob->set_measurement_model(parse_weights_spec(cmd.weights), parse_loss_spec(cmd.loss));  // same on every rank
  ev.costs = evaluate_costs(*prob, x.data());
  ev.errors = evaluate_errors(*prob, x.data());
  ev.num_sensors = prob->num_sensors();
}

// Where --crlb evaluates the Fisher information: "truth" or "estimate".
std::string fim_point(const EvalCommand& cmd, const Network& slab) {
  if (cmd.fim_at == "truth" || cmd.fim_at == "estimate") return cmd.fim_at;
  return slab.has_truth ? "truth" : "estimate";
}

// --crlb: the Cramer-Rao bound on rank 0 (whole: the network read serially
// there; estimate: the whole result's positions there, when J is taken at
// them). --sigma overrides the network's sigmas; without it, per-measurement
// sigmas when the network has them, else its scalar sigma.
void evaluate_crlb(const EvalCommand& cmd, const Network& whole, const std::vector<double>& estimate, MPI_Comm comm,
                   Evaluation& ev) {
  std::string crlb_err;
  if (cmd.crlb && is_root(comm)) {
    CrlbOptions o;
    o.sigma = cmd.sigma >= 0 ? cmd.sigma : -1;
    o.positions = ev.crlb_at == "estimate" ? &estimate : nullptr;
    o.covariance = !cmd.no_covariance;
    try {
      if (cmd.sigma == 0) {
        ev.crlb.reason = "sigma unknown (give --sigma) or zero";
      } else {
        o.validate();
        ev.crlb = cramer_rao_bound(whole, o);
      }
    } catch (const std::exception& e) {
      crlb_err = e.what();
    }
  }
  agree(comm, crlb_err);
}

// --global-opt: the exact f* on rank 0 from the whole network (global_1d.hpp);
// its refusal (dim, size, an unanchored component) is every rank's error.
void evaluate_global(const EvalCommand& cmd, const Network& whole, MPI_Comm comm, Evaluation& ev) {
  if (!cmd.global_opt) return;
  std::string err;
  const bool weighted = cmd.weights != "none" && (cmd.weights != "auto" || !whole.sensor_sigmas.empty() ||
                                                   !whole.anchor_sigmas.empty());
  if (is_root(comm) && (weighted || cmd.loss != "l2")) {
    err = "--global-opt: the exact optimum is of the unweighted l2 ML cost (003 eq. 2); this evaluation has "
          "--weights/--loss or per-measurement sigmas (give --weights none --loss l2)";
  } else if (is_root(comm)) {
    try {
      GlobalOptimum1DOptions o;
      o.max_terms = cmd.global_opt_max_terms;
      ev.global = global_ml_optimum_1d(whole, o);
    } catch (const std::exception& e) {
      err = "--global-opt: " + std::string(e.what());
    }
  }
  agree(comm, err);
  ev.has_global = true;
}

// --crlb without --no-covariance: the per-sensor covariances into the result
// file (rank 0; the edit is atomic, and every rank learns of a failure).
void store_covariance(const EvalCommand& cmd, const Network& whole, MPI_Comm comm, Evaluation& ev) {
  if (!cmd.crlb || cmd.no_covariance) return;
  std::string err;
  if (is_root(comm) && ev.crlb.defined) {
    ResultCovariance c;
    c.dim = whole.dim;
    c.num_sensors = whole.num_sensors;
    c.covariance = std::move(ev.crlb.covariance);
    c.covered.assign(static_cast<std::size_t>(whole.num_sensors), 1);
    for (const GlobalId i : ev.crlb.outside) c.covered[static_cast<std::size_t>(i)] = 0;
    c.at = ev.crlb_at;
    c.sigma_model = ev.crlb.weighted ? "per-measurement" : "uniform";
    c.sigma = ev.crlb.weighted ? 0.0 : (cmd.sigma >= 0 ? cmd.sigma : whole.sigma.value_or(0.0));
    c.rmse = ev.crlb.rmse;
    try {
      add_covariance_to_result(cmd.result, c);
      ev.covariance_written = true;
    } catch (const std::exception& e) {
      err = e.what();
    }
  }
  agree(comm, err);
}

// Up to `cap` ids, then how many more.
std::string id_list(const std::vector<GlobalId>& ids, std::size_t cap) {
  std::string s;
  for (std::size_t a = 0; a < ids.size() && a < cap; ++a) s += (a ? ", " : "") + std::to_string(ids[a]);
  if (ids.size() > cap) s += ", ... (" + std::to_string(ids.size() - cap) + " more; all in --json)";
  return s;
}

void print_errors(const Evaluation& ev) {
  const ErrorMetrics& em = ev.errors;
  if (!em.valid) {
    std::printf("  no truth in the network: RMSE/MPE unavailable\n");
    return;
  }
  std::printf("  RMSE = %.6g, MPE = %.6g (over all %lld sensors); ", em.rmse, em.mpe,
              static_cast<long long>(ev.num_sensors));
  if (em.localizable > 0)
    std::printf("over %lld localizable: RMSE %.6g, MPE %.6g\n", static_cast<long long>(em.localizable),
                em.rmse_localizable, em.mpe_localizable);
  else
    std::printf("over the localizable sensors: n/a (no sensor is localizable)\n");
}

void print_crlb(const Evaluation& ev) {
  const CrlbResult& cr = ev.crlb;
  if (!cr.defined) {
    std::printf("  Cramer-Rao bound: not defined (%s)\n", cr.reason.c_str());
    if (!cr.outside.empty())
      std::printf("  %zu sensor(s) outside the anchored rigid part: %s\n", cr.outside.size(),
                  id_list(cr.outside, 20).c_str());
    return;
  }
  std::printf("  Cramer-Rao bound RMSE_CRLB = %.6g over the %lld sensor(s) of the anchored rigid part (of %lld; "
              "Fisher information at the %s, %s sigma)\n",
              cr.rmse, static_cast<long long>(cr.covered), static_cast<long long>(ev.num_sensors),
              ev.crlb_at == "truth" ? "true positions" : "estimate", cr.weighted ? "per-measurement" : "one");
  if (!cr.outside.empty())
    std::printf("  %zu sensor(s) outside it, no finite bound: %s\n", cr.outside.size(),
                id_list(cr.outside, 20).c_str());
  if (ev.covariance_written) std::printf("  per-sensor covariances written to group crlb of the result file\n");
}

void print_evaluation(const EvalCommand& cmd, const Evaluation& ev) {
  const CostTerms& c = ev.costs;
  std::printf("%s on %s\n", cmd.result.c_str(), cmd.network.c_str());
  std::printf("  ML cost f = %.10g\n  relaxed cost f_hat = %.10g\n  sum of nonconvex terms of edges inside their disks = %.6g (the 003 eq. 22 certificate when RESULT minimizes f_hat)\n"
              "  a-priori bound (003 eq. 23) = %.6g\n",
              c.ml, c.relaxed, c.certificate, c.apriori);
  if (ev.has_global)
    std::printf("  exact global ML optimum f* = %.10g (%llu sign patterns); f* - f_hat(RESULT) = %.6g (the true gap "
                "f* - f_hat* of 003 Table I when RESULT minimizes f_hat)\n",
                ev.global.cost, static_cast<unsigned long long>(ev.global.patterns), ev.global.cost - c.relaxed);
  print_errors(ev);
  if (cmd.crlb) print_crlb(ev);
}

std::string json_evaluation(const EvalCommand& cmd, const Evaluation& ev) {
  const CostTerms& c = ev.costs;
  const ErrorMetrics& em = ev.errors;
  JsonObject j;
  j.add("network", cmd.network).add("result", cmd.result).add("ml_cost", c.ml).add("relaxed_cost", c.relaxed);
  j.add("gap_certificate", c.certificate).add("apriori_bound", c.apriori);
  if (ev.has_global)
    j.add("global_ml_optimum", ev.global.cost)
        .add("true_gap", ev.global.cost - c.relaxed)
        .add("global_patterns", static_cast<std::int64_t>(ev.global.patterns));
  if (em.valid) {
    j.add("rmse", em.rmse).add("mpe", em.mpe);
    if (em.localizable > 0) {
      j.add("rmse_localizable", em.rmse_localizable).add("mpe_localizable", em.mpe_localizable);
    } else {
      j.add_null("rmse_localizable").add_null("mpe_localizable");
      j.add("localizable_reason", "no sensor is localizable");
    }
  }
  if (cmd.crlb) {
    j.add_bool("crlb_defined", ev.crlb.defined);
    if (ev.crlb.defined) {
      j.add("crlb_rmse", ev.crlb.rmse);
      j.add("crlb_sensors", static_cast<std::int64_t>(ev.crlb.covered));
      j.add("crlb_at", ev.crlb_at).add("crlb_sigma", ev.crlb.weighted ? "per-measurement" : "uniform");
    } else {
      j.add("crlb_reason", ev.crlb.reason);
    }
    j.add("crlb_outside", ev.crlb.outside);
  }
  return j.str();
}

}  // namespace

void run_eval(const EvalCommand& cmd, MPI_Comm comm) {
  if (!cmd.json.empty()) check_output_path(cmd.json, comm, {{"the network", cmd.network}, {"the result", cmd.result}});
  Network slab = read_network(cmd.network, comm);
  if (slab.num_anchors() == 0) throw Error(cmd.network + ": the network has no anchors");
  Evaluation ev;
  ev.crlb_at = fim_point(cmd, slab);
  Network whole;
  std::vector<double> estimate;
  if (cmd.crlb || cmd.global_opt) {
    collective_try(comm, [&] {
      if (is_root(comm)) {
        whole = read_network_serial(cmd.network);
        merge_duplicates(whole.sensor_edges, whole.sensor_ranges, MeasurementExtras{&whole.sensor_sigmas, nullptr},
                         whole.anchor_edges, whole.anchor_ranges, MeasurementExtras{&whole.anchor_sigmas, nullptr});
        if (ev.crlb_at == "estimate")
          estimate = read_positions(cmd.result, MPI_COMM_SELF, whole.num_sensors, whole.dim, 0, whole.num_sensors);
      }
    });
  }
  evaluate_global(cmd, whole, comm, ev);
  evaluate_result(cmd, slab, comm, ev);
  evaluate_crlb(cmd, whole, estimate, comm, ev);
  store_covariance(cmd, whole, comm, ev);
  if (is_root(comm)) print_evaluation(cmd, ev);
  if (!cmd.json.empty()) detail::write_text_on_root(cmd.json, json_evaluation(cmd, ev), comm);
}

}  // namespace snl
