// The SDP solver: DSDP 5 (Benson and Ye), a dual-scaling interior-point method
// written for sparse SDPs such as the sensor-localization relaxations; chosen
// over CSDP by measurement (docs/reproduction.md, "The SDP solver").
#include <dsdp/dsdp5.h>
#include <fcntl.h>
#include <unistd.h>

#include <cstdio>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <map>
#include <utility>

#include "snl/core/common.hpp"
#include "solvers/centralized/sdp_problem.hpp"

namespace snl::detail {

namespace {

// One data matrix of one block in DSDP's packed sparse form (sorted, merged).
struct PackedMatrix {
  std::vector<int> ind;
  std::vector<double> val;
};

// (block, variable) -> matrix; variable 0 is C, k + 1 is A_k (DSDP's numbering).
using MatrixMap = std::map<std::pair<int, int>, PackedMatrix>;

void add_entries(MatrixMap& mats, const std::vector<SdpEntry>& entries, int var) {
  std::map<std::pair<int, std::size_t>, double> acc;  // sorted by (block, packed index)
  for (const SdpEntry& e : entries) acc[{e.block, packed_index(e.i, e.j)}] += e.v;
  for (const auto& kv : acc) {
    if (kv.second == 0) continue;
    PackedMatrix& m = mats[{kv.first.first, var}];
    m.ind.push_back(static_cast<int>(kv.first.second));
    m.val.push_back(kv.second);
  }
}

const char* stop_reason_text(DSDPTerminationReason r) {
  switch (r) {
    case DSDP_CONVERGED: return "converged";
    case DSDP_MAX_IT: return "iteration limit";
    case DSDP_SMALL_STEPS: return "small steps (numerical difficulties)";
    case DSDP_INFEASIBLE_START: return "infeasible start";
    case DSDP_INDEFINITE_SCHUR_MATRIX: return "indefinite Schur matrix";
    case DSDP_NUMERICAL_ERROR: return "numerical error";
    case DSDP_UPPERBOUND: return "dual objective bound reached";
    case DSDP_USER_TERMINATION: return "stopped";
    default: return "not converged";
  }
}

// Throws on a DSDP error code (a bug in the data we pass, or no memory).
void check(int info, const char* what) {
  if (info != 0) throw Error(std::string("DSDP: ") + what + " failed (code " + std::to_string(info) + ")");
}

// The solution DSDP reached: status, objectives, y and (if asked) X.
void read_solution(DSDP dsdp, SDPCone cone, const SdpProblem& prob, const SdpOptions& opt, SdpSolution& s) {
  DSDPTerminationReason reason;
  DSDPSolutionType type;
  check(DSDPStopReason(dsdp, &reason), "DSDPStopReason");
  check(DSDPGetSolutionType(dsdp, &type), "DSDPGetSolutionType");
  check(DSDPGetIts(dsdp, &s.iterations), "DSDPGetIts");
  s.status = stop_reason_text(reason);
  if (type == DSDP_INFEASIBLE) s.status = "dual infeasible (primal unbounded)";
  if (type == DSDP_UNBOUNDED) s.status = "dual unbounded (primal infeasible)";
  s.ok = reason == DSDP_CONVERGED && type == DSDP_PDFEASIBLE;
  check(DSDPGetDObjective(dsdp, &s.dual_objective), "DSDPGetDObjective");
  s.y.assign(prob.b.size(), 0.0);
  if (!s.y.empty()) check(DSDPGetY(dsdp, s.y.data(), static_cast<int>(s.y.size())), "DSDPGetY");
  s.primal_objective = s.dual_objective;
  if (!s.ok) return;
  // DSDP can call an unbounded dual (an infeasible primal) converged when y
  // reaches its box: the primal residual and the box tell.
  double ylo = 0, yhi = 0, ymax = 0, r = 0, pinf = 0, bmax = 0;
  check(DSDPGetYBounds(dsdp, &ylo, &yhi), "DSDPGetYBounds");
  check(DSDPGetYMaxNorm(dsdp, &ymax), "DSDPGetYMaxNorm");
  check(DSDPGetR(dsdp, &r), "DSDPGetR");
  check(DSDPComputeX(dsdp), "DSDPComputeX");
  check(DSDPGetPInfeasibility(dsdp, &pinf), "DSDPGetPInfeasibility");
  for (double v : prob.b) bmax = std::max(bmax, std::abs(v));
  if (ymax >= 0.5 * std::min(-ylo, yhi) || pinf > 1e-6 * (1 + bmax)) {
    s.ok = false;
    s.status = "primal infeasible (dual unbounded)";
    return;
  }
  if (r > 1e-6) {
    s.ok = false;
    s.status = "dual infeasible";
    return;
  }
  check(DSDPGetPObjective(dsdp, &s.primal_objective), "DSDPGetPObjective");
  if (!opt.want_primal) return;
  s.x.resize(prob.block_sizes.size());
  for (std::size_t j = 0; j < prob.block_sizes.size(); ++j) {
    double* xa = nullptr;
    int len = 0;
    check(SDPConeGetXArray(cone, static_cast<int>(j), &xa, &len), "SDPConeGetXArray");
    s.x[j].assign(xa, xa + len);
  }
}

}  // namespace

SdpSolution solve_sdp_dsdp(const SdpProblem& prob, const SdpOptions& opt) {
  const auto t0 = std::chrono::steady_clock::now();
  const int m = prob.num_constraints(), nb = static_cast<int>(prob.block_sizes.size());
  MatrixMap mats;  // must outlive the DSDP object (DSDP keeps pointers into it)
  add_entries(mats, prob.c, 0);
  for (int k = 0; k < m; ++k) add_entries(mats, prob.a[k], k + 1);
  DSDP dsdp = nullptr;
  SDPCone cone = nullptr;
  SdpSolution s;
  check(DSDPCreate(m, &dsdp), "DSDPCreate");
  try {
    for (int k = 0; k < m; ++k) check(DSDPSetDualObjective(dsdp, k + 1, prob.b[k]), "DSDPSetDualObjective");
    check(DSDPCreateSDPCone(dsdp, nb, &cone), "DSDPCreateSDPCone");
    for (int j = 0; j < nb; ++j) check(SDPConeSetBlockSize(cone, j, prob.block_sizes[j]), "SDPConeSetBlockSize");
    for (auto& kv : mats) {
      const int j = kv.first.first;
      check(SDPConeSetASparseVecMat(cone, j, kv.first.second, prob.block_sizes[j], 1.0, 0, kv.second.ind.data(),
                                    kv.second.val.data(), static_cast<int>(kv.second.ind.size())),
            "SDPConeSetASparseVecMat");
    }
    check(DSDPSetGapTolerance(dsdp, opt.gap_tol), "DSDPSetGapTolerance");
    check(DSDPSetMaxIts(dsdp, opt.max_iter), "DSDPSetMaxIts");
    // DSDP prints a line or two on standard output of its own accord: silenced.
    std::fflush(stdout);
    const int saved = dup(1), devnull = open("/dev/null", O_WRONLY);
    if (devnull >= 0) dup2(devnull, 1);
    int info = DSDPSetup(dsdp);
    if (info == 0) info = DSDPSolve(dsdp);
    std::fflush(stdout);
    if (saved >= 0) dup2(saved, 1), close(saved);
    if (devnull >= 0) close(devnull);
    if (info != 0) {
      s.status = "DSDPSolve failed (code " + std::to_string(info) + ")";
    } else {
      read_solution(dsdp, cone, prob, opt, s);
    }
  } catch (...) {
    DSDPDestroy(dsdp);
    throw;
  }
  DSDPDestroy(dsdp);
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return s;
}

// SDPA's pair is min c'x s.t. sum_k x_k F_k - F0 >= 0 and max <F0, Y> s.t.
// <F_k, Y> = c_k: ours with x = -y, c = b, F0 = -C, F_k = A_k.
void write_sdpa(const SdpProblem& prob, const std::string& path) {
  std::ofstream f(path);
  if (!f) throw Error("cannot write " + path);
  f.precision(17);
  f << prob.num_constraints() << "\n" << prob.block_sizes.size() << "\n";
  for (int s : prob.block_sizes) f << s << " ";
  f << "\n";
  for (double v : prob.b) f << v << " ";
  f << "\n";
  auto put = [&](int var, const std::vector<SdpEntry>& es, double sign) {
    for (const SdpEntry& e : es)
      if (e.v != 0) f << var << " " << e.block + 1 << " " << e.j + 1 << " " << e.i + 1 << " " << sign * e.v << "\n";
  };
  put(0, prob.c, -1.0);
  for (int k = 0; k < prob.num_constraints(); ++k) put(k + 1, prob.a[k], 1.0);
  if (!f) throw Error("cannot write " + path);
}

}  // namespace snl::detail
