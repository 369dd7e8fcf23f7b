#include "snl/solvers/registry.hpp"

#include <algorithm>

#include "snl/solvers/solver.hpp"
#include "solvers/methods.hpp"

namespace snl {

namespace {

using A = AlgorithmId;

// Capabilities, as the code has them: --temporal-block is honoured where
// Algorithm::max_levels() > 1 (relaxation, MM); --grad-tol where grad_norm_sq()
// is finite (relaxation, BB); --bb-rounds by BB alone; --weights/--loss where
// the method reads prob.model() (all of these; a pipeline only if all its phases do).
const std::vector<AlgorithmInfo> kRegistry = {
    // id             name           code  factory                   phases
    //   synchronous temporal_blocking gradient_stop consensus_rounds monotone_surrogate gap_certificate
    //   measurement_model
    // The default: the distance-vector start (dv_start.hpp), --smooth-iter
    // relaxation iterations, --settle-iter (200) of mm-accel, then ml-agd to
    // convergence (under weights or Huber, mm-accel to convergence instead).
    // Its relaxation is a smoother, not solved: no gap certificate.
    {A::kDvPipeline, "dv-pipeline", -1, nullptr, {A::kRelaxation, A::kMMAccel, A::kMlAgd},
     true, false, false, false, true, false, true},
    {A::kRelaxation, "relaxation", 0, detail::make_relaxation, {A::kRelaxation},
     true, true, true, false, false, true, true},
    {A::kMM, "mm", 1, detail::make_mm, {A::kMM},
     true, true, false, false, true, false, true},
    {A::kMMAccel, "mm-accel", 6, detail::make_mm_accel, {A::kMMAccel},
     true, false, false, false, true, false, true},
    // Nesterov's accelerated gradient on the ML cost with gradient restarts
    // (relaxation.cpp): the unweighted l2 cost only.
    {A::kMlAgd, "ml-agd", 13, detail::make_ml_agd, {A::kMlAgd},
     true, false, false, false, false, false, false},
    {A::kPipeline, "pipeline", -1, nullptr, {A::kRelaxation, A::kMM},
     true, true, true, false, true, true, true},
    {A::kBB, "bb", 2, detail::make_bb, {A::kBB},
     true, false, true, true, false, false, true},
    {A::kPM, "pm", 3, detail::make_pm, {A::kPM},
     false, false, false, false, false, false, true},
    // --mode replay (the default): the sequential order, bit for bit; --mode free: unsynchronised.
    {A::kAsync, "async", 4, detail::make_async, {A::kAsync},
     false, false, false, false, false, false, true, false, false, true},
    {A::kAsyncExact, "async-exact", 5, detail::make_async_exact, {A::kAsyncExact},
     false, false, false, false, false, false, true, false, false, true},
    {A::kBBCalafiore, "bb-calafiore", 10, detail::make_bb_calafiore, {A::kBBCalafiore},
     true, false, true, true, false, false, false, false},
    // The centralized SDP relaxations (solvers/centralized/), solved once by DSDP on rank 0.
    {A::kSdp, "sdp", 7, detail::make_sdp, {A::kSdp},
     true, false, false, false, false, false, false, true},
    {A::kEsdp, "esdp", 8, detail::make_esdp, {A::kEsdp},
     true, false, false, false, false, false, false, true},
    {A::kEdm, "edm", 11, detail::make_edm, {A::kEdm},
     true, false, false, false, false, false, false, true},
    // The same ESDP solved by distributed ADMM (esdp_dist.cpp): 003's Fig. 6 comparison.
    {A::kEsdpDist, "esdp-dist", 12, detail::make_esdp_dist, {A::kEsdpDist},
     true, false, false, false, false, false, false, false, true},
};

}  // namespace

const std::vector<AlgorithmInfo>& algorithm_registry() { return kRegistry; }

const AlgorithmInfo* find_algorithm(const std::string& name) {
  for (const auto& a : kRegistry)
    if (name == a.name) return &a;
  return nullptr;
}

const AlgorithmInfo& algorithm_info(AlgorithmId id) {
  for (const auto& a : kRegistry)
    if (a.id == id) return a;
  throw Error("algorithm id not in the registry");
}

std::string algorithm_names(const std::string& sep, const std::string& last_sep, bool single_phase_only) {
  std::vector<const char*> names;
  for (const auto& a : kRegistry)
    if (!single_phase_only || a.phases.size() == 1) names.push_back(a.name);
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i > 0) out += (i + 1 == names.size() && !last_sep.empty()) ? last_sep : sep;
    out += names[i];
  }
  return out;
}

std::string algorithms_with(bool AlgorithmInfo::*capability) {
  std::string out;
  for (const auto& a : kRegistry)
    if (a.*capability) out += std::string(out.empty() ? "" : ", ") + a.name;
  return out;
}

int algorithm_code(const std::string& name) {
  const AlgorithmInfo* a = find_algorithm(name);
  return a && a->code >= 0 ? a->code : 9;
}

namespace {
const AlgorithmInfo* find_code(int code) {
  for (const auto& a : kRegistry)
    if (code >= 0 && a.code == code) return &a;
  return nullptr;
}
}  // namespace

const char* algorithm_name(int code) {
  const AlgorithmInfo* a = find_code(code);
  return a ? a->name : "?";
}

std::string algorithm_codes_legend() {  // ascending codes; 9 is "anything else"
  int top = 0;
  for (const auto& a : kRegistry) top = std::max(top, a.code);
  std::string out;
  for (int c = 0; c <= top; ++c)
    if (find_code(c)) out += (out.empty() ? "" : " ") + std::to_string(c) + "=" + find_code(c)->name;
  return out;
}

std::unique_ptr<Algorithm> make_algorithm(AlgorithmId id, LocalizationProblem& prob, const SolverOptions& opt) {
  const AlgorithmInfo& a = algorithm_info(id);
  if (!a.make) throw Error(std::string("'") + a.name + "' is not a single method (the Solver runs its phases)");
  return a.make(prob, opt);
}

std::unique_ptr<Algorithm> make_algorithm(const std::string& name, LocalizationProblem& prob,
                                          const SolverOptions& opt) {
  const AlgorithmInfo* a = find_algorithm(name);
  if (!a || !a->make) throw Error("unknown algorithm '" + name + "'");
  return a->make(prob, opt);
}

std::unique_ptr<Algorithm> make_sequential_algorithm(const std::string& name, LocalizationProblem& prob,
                                                     const SolverOptions& opt) {
  const AlgorithmInfo* a = find_algorithm(name);
  if (!a || a->synchronous || !a->make) return nullptr;
  return a->make(prob, opt);
}

}  // namespace snl
