#pragma once
// The factories of the methods, one .cpp file each (internal header): the
// registry (registry.cpp) lists them; nothing else calls them.
#include <memory>

#include "snl/solvers/solver.hpp"

namespace snl::detail {

std::unique_ptr<Algorithm> make_relaxation(LocalizationProblem& prob, const SolverOptions& opt);  // relaxation.cpp
std::unique_ptr<Algorithm> make_mm(LocalizationProblem& prob, const SolverOptions& opt);          // mm.cpp
std::unique_ptr<Algorithm> make_ml_agd(LocalizationProblem& prob, const SolverOptions& opt);      // relaxation.cpp
std::unique_ptr<Algorithm> make_mm_accel(LocalizationProblem& prob, const SolverOptions& opt);    // mm_accel.cpp
std::unique_ptr<Algorithm> make_bb(LocalizationProblem& prob, const SolverOptions& opt);          // bb.cpp
std::unique_ptr<Algorithm> make_pm(LocalizationProblem& prob, const SolverOptions& opt);          // pm.cpp
std::unique_ptr<Algorithm> make_async(LocalizationProblem& prob, const SolverOptions& opt);       // async.cpp
std::unique_ptr<Algorithm> make_async_exact(LocalizationProblem& prob, const SolverOptions& opt); // async.cpp
/// The relaxation and MM under a weighted or Huber model (weighted.cpp); make_relaxation
/// and make_mm return these when prob.model().active().
std::unique_ptr<Algorithm> make_model_relaxation(LocalizationProblem& prob);
std::unique_ptr<Algorithm> make_model_mm(LocalizationProblem& prob);
std::unique_ptr<Algorithm> make_bb_calafiore(LocalizationProblem& prob, const SolverOptions& opt);  // bb_calafiore.cpp
std::unique_ptr<Algorithm> make_sdp(LocalizationProblem& prob, const SolverOptions& opt);   // centralized/centralized.cpp
std::unique_ptr<Algorithm> make_esdp(LocalizationProblem& prob, const SolverOptions& opt);  // centralized/centralized.cpp
std::unique_ptr<Algorithm> make_esdp_dist(LocalizationProblem& prob, const SolverOptions& opt);  // esdp_dist.cpp
std::unique_ptr<Algorithm> make_edm(LocalizationProblem& prob, const SolverOptions& opt);   // centralized/centralized.cpp

}  // namespace snl::detail
