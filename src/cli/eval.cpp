// snl eval: costs, errors and the Cramer-Rao bound of a result on a network.
#include <cstdio>
#include <optional>

#include "cli/cli_util.hpp"
#include "core/json.hpp"
#include "snl/cli/commands.hpp"
#include "snl/io/network.hpp"
#include "snl/io/result_io.hpp"
#include "snl/problem/analysis.hpp"

namespace snl {

namespace {

using detail::is_root;

// What snl eval reports.
struct Evaluation {
  CostTerms costs;
  ErrorMetrics errors;
  GlobalId num_sensors = 0;
  CrlbResult crlb;
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

// --crlb: the Cramer-Rao bound on rank 0 (whole: the network read serially there).
void evaluate_crlb(const EvalCommand& cmd, const Network& whole, std::optional<double> sigma, MPI_Comm comm,
                   Evaluation& ev) {
  std::string crlb_err;
  if (cmd.crlb && is_root(comm)) {
    const double sg = cmd.sigma >= 0 ? cmd.sigma : (sigma ? *sigma : -1);
    if (sg <= 0) {
      ev.crlb.reason = "sigma unknown (give --sigma) or zero";
    } else {
      try {
        ev.crlb = cramer_rao_bound(whole, sg);
      } catch (const std::exception& e) {
        crlb_err = e.what();
      }
    }
  }
  agree(comm, crlb_err);
}

void print_evaluation(const EvalCommand& cmd, const Evaluation& ev) {
  const CostTerms& c = ev.costs;
  const ErrorMetrics& em = ev.errors;
  const CrlbResult& cr = ev.crlb;
  std::printf("%s on %s\n", cmd.result.c_str(), cmd.network.c_str());
  std::printf("  ML cost f = %.10g\n  relaxed cost f_hat = %.10g\n  sum of nonconvex terms of edges inside their disks = %.6g (the 003 eq. 22 certificate when RESULT minimizes f_hat)\n"
              "  a-priori bound (003 eq. 23) = %.6g\n",
              c.ml, c.relaxed, c.certificate, c.apriori);
  if (em.valid)
    std::printf("  RMSE = %.6g, MPE = %.6g (over all %lld sensors); over %lld localizable: RMSE %.6g, MPE %.6g\n",
                em.rmse, em.mpe, static_cast<long long>(ev.num_sensors),
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

std::string json_evaluation(const EvalCommand& cmd, const Evaluation& ev) {
  const CostTerms& c = ev.costs;
  const ErrorMetrics& em = ev.errors;
  JsonObject j;
  j.add("network", cmd.network).add("result", cmd.result).add("ml_cost", c.ml).add("relaxed_cost", c.relaxed);
  j.add("gap_certificate", c.certificate).add("apriori_bound", c.apriori);
  if (em.valid)
    j.add("rmse", em.rmse).add("mpe", em.mpe).add("rmse_localizable", em.rmse_localizable)
        .add("mpe_localizable", em.mpe_localizable);
  if (cmd.crlb) {
    j.add_bool("crlb_defined", ev.crlb.defined);
    if (ev.crlb.defined)
      j.add("crlb_rmse", ev.crlb.rmse);
    else
      j.add("crlb_reason", ev.crlb.reason);
  }
  return j.str();
}

}  // namespace

void run_eval(const EvalCommand& cmd, MPI_Comm comm) {
  Network slab = read_network(cmd.network, comm);
  if (slab.num_anchors() == 0) throw Error(cmd.network + ": the network has no anchors");
  const std::optional<double> sigma = slab.sigma;
  Network whole;
  if (cmd.crlb) {
    collective_try(comm, [&] {
      if (is_root(comm)) {
        whole = read_network_serial(cmd.network);
        merge_duplicates(whole.sensor_edges, whole.sensor_ranges, whole.anchor_edges, whole.anchor_ranges);
      }
    });
  }
  Evaluation ev;
  evaluate_result(cmd, slab, comm, ev);
  evaluate_crlb(cmd, whole, sigma, comm, ev);
  if (is_root(comm)) print_evaluation(cmd, ev);
  if (!cmd.json.empty()) detail::write_text_on_root(cmd.json, json_evaluation(cmd, ev), comm);
}

}  // namespace snl
