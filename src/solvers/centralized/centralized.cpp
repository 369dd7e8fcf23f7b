// The centralized convex relaxations as methods of the registry: sdp, esdp and
// edm (relaxations.hpp). The first iteration gathers the network on rank 0 of
// the problem's communicator, solves the SDP there with DSDP and sends the
// positions back; the Solver then stops (AlgorithmInfo::one_shot). A solver
// failure or an infeasible SDP is a NumericalFailure on every rank (exit 4,
// no output).
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "snl/core/mpi_util.hpp"
#include "solvers/algorithm_util.hpp"
#include "solvers/centralized/relaxations.hpp"
#include "solvers/methods.hpp"

namespace snl {

namespace {

using detail::GatheredNetwork;
using detail::RelaxationKind;

// Largest networks accepted, by measurement on this project's 2-core machine
// (docs/reproduction.md, "The SDP solver"): beyond, DSDP takes minutes or
// fails (sdp at 300 sensors, esdp at 500).
constexpr GlobalId kMaxSensors[] = {200, 300, 300};  // sdp, esdp, edm

// Concatenation of every rank's doubles on rank 0 of comm (empty elsewhere).
std::vector<double> gather_doubles(MPI_Comm comm, const std::vector<double>& mine) {
  const int size = comm_size(comm), rank = comm_rank(comm);
  int cnt = static_cast<int>(mine.size());
  std::vector<int> counts(size), displs(size, 0);
  MPI_Gather(&cnt, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, comm);
  std::vector<double> all;
  if (rank == 0) {
    for (int r = 1; r < size; ++r) displs[r] = displs[r - 1] + counts[r - 1];
    all.resize(std::size_t(displs[size - 1]) + counts[size - 1]);
  }
  MPI_Gatherv(mine.data(), cnt, MPI_DOUBLE, all.data(), counts.data(), displs.data(), MPI_DOUBLE, 0, comm);
  return all;
}

// The whole network on rank 0: each sensor edge once (from its smaller end),
// every anchor measurement, sorted, so the SDP does not depend on the partition.
GatheredNetwork gather_network(const LocalizationProblem& prob) {
  const auto& gr = prob.graph();
  std::vector<double> e3, a3;  // (i, j, d) and (i, k, r); ids below 2^53 are exact doubles
  for (LocalId v = 0; v < gr.num_owned(); ++v) {
    const GlobalId gv = gr.global_id(v);
    for (auto e = gr.offsets()[v]; e < gr.offsets()[v + 1]; ++e) {
      const GlobalId gu = gr.global_id(gr.adjacency()[e]);
      if (gu > gv) e3.insert(e3.end(), {double(gv), double(gu), gr.edge_value(e)});
    }
    for (auto e = prob.anchor_offsets()[v]; e < prob.anchor_offsets()[v + 1]; ++e)
      a3.insert(a3.end(), {double(gv), double(prob.anchor_ids()[e]), prob.anchor_ranges()[e]});
  }
  const std::vector<double> ea = gather_doubles(prob.comm(), e3), aa = gather_doubles(prob.comm(), a3);
  GatheredNetwork net;
  net.p = prob.dim();
  net.n = prob.num_sensors();
  net.anchors = prob.anchors();
  for (std::size_t t = 0; t + 2 < ea.size(); t += 3)
    net.edges.push_back({GlobalId(ea[t]), GlobalId(ea[t + 1]), ea[t + 2]});
  for (std::size_t t = 0; t + 2 < aa.size(); t += 3)
    net.anchor_edges.push_back({GlobalId(aa[t]), GlobalId(aa[t + 1]), aa[t + 2]});
  std::sort(net.edges.begin(), net.edges.end(),
            [](const auto& a, const auto& b) { return a.i != b.i ? a.i < b.i : a.j < b.j; });
  std::sort(net.anchor_edges.begin(), net.anchor_edges.end(),
            [](const auto& a, const auto& b) { return a.i != b.i ? a.i < b.i : a.k < b.k; });
  return net;
}

class CentralizedRelaxation final : public Algorithm {
 public:
  CentralizedRelaxation(LocalizationProblem& prob, AlgorithmId id, RelaxationKind kind)
      : prob_(prob), id_(id), kind_(kind) {
    const GlobalId limit = kMaxSensors[static_cast<int>(kind)];
    if (prob.num_sensors() > limit)
      throw Error("--algorithm " + name() + " solves one centralized SDP and accepts at most " +
                  std::to_string(limit) + " sensors (DSDP's time and memory grow too fast beyond); this network has " +
                  std::to_string(prob.num_sensors()) + ": use a distributed method");
    if (kind == RelaxationKind::kEdm && prob.num_anchors() < prob.dim() + 1)
      throw Error("--algorithm edm needs at least p+1 = " + std::to_string(prob.dim() + 1) +
                  " anchors (its positions are aligned to the anchors); this network has " +
                  std::to_string(prob.num_anchors()));
  }
  std::string name() const override { return algorithm_info(id_).name; }
  double messages_per_iteration() const override { return 0.0; }  // centralized: no sensor communication
  double reals_per_iteration() const override { return 0.0; }

  void start(const std::vector<double>& x0) override {
    x_ = detail::with_ghost_rows(prob_, x0);
    x_old_.assign(x_.begin(), x_.begin() + std::size_t(prob_.num_owned()) * prob_.dim());
    solved_ = false;
  }
  void iterate() override {
    std::copy(x_.begin(), x_.begin() + x_old_.size(), x_old_.begin());
    if (!solved_) solve();
    solved_ = true;
  }
  const std::vector<double>& positions() const override { return x_; }
  const double* previous_positions() const override { return x_old_.data(); }
  void change_norms(double* d, double* s) const override {
    detail::diff_norms(prob_, x_.data(), x_old_.data(), d, s);
  }
  // The relaxation's own objective (ML-cost units), once solved; the ML cost before.
  double objective() override {
    if (solved_) return objective_;
    prob_.graph().halo().exchange(x_.data(), prob_.dim());
    return evaluate_costs(prob_, x_.data()).ml;
  }
  void report(std::vector<std::pair<std::string, double>>* values,
              std::vector<std::pair<std::string, std::string>>* texts) const override {
    if (!solved_) return;
    values->push_back({"relaxation_objective", objective_});
    values->push_back({"sdp_seconds", seconds_});
    values->push_back({"sdp_iterations", double(iterations_)});
    texts->push_back({"sdp_solver", "DSDP 5.8"});
    texts->push_back({"sdp_status", status_});
  }
  // Solved in one step: nothing to resume (the CLI refuses --checkpoint for it).
  void save(StateWriter&) const override {}
  void load(const StateReader&) override {}

 private:
  // Collective: solve on rank 0, then everyone learns the outcome and its rows.
  void solve() {
    const GatheredNetwork net = gather_network(prob_);
    const int p = prob_.dim();
    std::vector<double> all(std::size_t(prob_.num_sensors()) * p, 0.0);
    double info[4] = {0, 0, 0, 0};  // ok, objective, seconds, iterations
    std::string status;
    if (comm_rank(prob_.comm()) == 0) {
      try {  // any failure here is rank 0's alone: it is told to every rank below
        test_fail_point("sdp");  // fault-injection tests
        const detail::SdpProblem sp = detail::build_relaxation(kind_, net);
        // The solver benchmark (bench/sdp_backends.sh) times other solvers on the same SDP.
        if (const char* dump = std::getenv("SNL_SDP_DUMP")) detail::write_sdpa(sp, dump);
        detail::SdpOptions o;
        o.want_primal = kind_ != RelaxationKind::kEsdp;
        const detail::SdpSolution s = detail::solve_sdp_dsdp(sp, o);
        status = s.status;
        info[0] = s.ok ? 1 : 0;
        info[1] = sp.sign * s.dual_objective + sp.offset;
        info[2] = s.seconds;
        info[3] = s.iterations;
        if (s.ok) all = detail::relaxation_positions(kind_, net, s);
      } catch (const std::exception& e) {
        info[0] = 0;
        status = e.what();
      }
    }
    MPI_Bcast(info, 4, MPI_DOUBLE, 0, prob_.comm());
    status = bcast_string(prob_.comm(), status);
    if (info[0] == 0 || !std::isfinite(info[1]))
      throw NumericalFailure("--algorithm " + name() + ": the SDP solver (DSDP) found no solution: " + status);
    bcast_bytes(prob_.comm(), all.data(), all.size() * sizeof(double));
    for (LocalId v = 0; v < prob_.num_owned(); ++v)
      for (int c = 0; c < p; ++c) x_[std::size_t(v) * p + c] = all[std::size_t(prob_.graph().global_id(v)) * p + c];
    objective_ = info[1];
    seconds_ = info[2];
    iterations_ = static_cast<int>(info[3]);
    status_ = status;
  }

  LocalizationProblem& prob_;
  AlgorithmId id_;
  RelaxationKind kind_;
  std::vector<double> x_, x_old_;
  bool solved_ = false;
  double objective_ = NAN, seconds_ = 0;
  int iterations_ = 0;
  std::string status_;
};

}  // namespace

namespace detail {

std::unique_ptr<Algorithm> make_sdp(LocalizationProblem& prob, const SolverOptions&) {
  return std::make_unique<CentralizedRelaxation>(prob, AlgorithmId::kSdp, RelaxationKind::kSdp);
}
std::unique_ptr<Algorithm> make_esdp(LocalizationProblem& prob, const SolverOptions&) {
  return std::make_unique<CentralizedRelaxation>(prob, AlgorithmId::kEsdp, RelaxationKind::kEsdp);
}
std::unique_ptr<Algorithm> make_edm(LocalizationProblem& prob, const SolverOptions&) {
  return std::make_unique<CentralizedRelaxation>(prob, AlgorithmId::kEdm, RelaxationKind::kEdm);
}

}  // namespace detail

}  // namespace snl
