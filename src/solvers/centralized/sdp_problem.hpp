#pragma once
// A semidefinite program in the standard primal-dual pair that DSDP solves
// (internal header):
//   (P) minimize <C, X>  s.t. <A_k, X> = b_k (k = 1..m),  X block-diagonal, X >= 0
//   (D) maximize b'y     s.t. C - sum_k y_k A_k >= 0.
// Every matrix is symmetric and given by its lower triangle: an entry (i, j, v)
// with i > j stands for v at (i, j) and at (j, i), so it adds 2 v X_ij to <A, X>
// (the SDPA convention). The relaxations (relaxations.hpp) are written in this
// form; sdp_dsdp.cpp solves it.
#include <string>
#include <vector>

namespace snl::detail {

struct SdpEntry {
  int block;  ///< 0-based block
  int i, j;   ///< 0-based row and column in the block, i >= j
  double v;
};

struct SdpProblem {
  std::vector<int> block_sizes;
  std::vector<SdpEntry> c;               ///< C
  std::vector<std::vector<SdpEntry>> a;  ///< A_1 .. A_m
  std::vector<double> b;                 ///< b_1 .. b_m
  /// The modelled objective is sign * (the optimal value of (P) and (D)) + offset.
  double sign = 1.0, offset = 0.0;
  int num_constraints() const { return static_cast<int>(b.size()); }
  /// A new constraint k (0-based) with right-hand side rhs.
  int add_constraint(double rhs) {
    a.emplace_back();
    b.push_back(rhs);
    return static_cast<int>(b.size()) - 1;
  }
  int add_block(int size) {
    block_sizes.push_back(size);
    return static_cast<int>(block_sizes.size()) - 1;
  }
};

struct SdpOptions {
  double gap_tol = 1e-9;  ///< DSDP's relative duality-gap tolerance (003 used SeDuMi's eps = 1e-9)
  int max_iter = 500;
  bool want_primal = true;  ///< compute X (the primal-form relaxations read it)
};

struct SdpSolution {
  bool ok = false;          ///< a solution was found (primal and dual feasible, converged)
  std::string status;       ///< the solver's words: "converged", "infeasible", ...
  double primal_objective = 0, dual_objective = 0;
  int iterations = 0;
  double seconds = 0;
  std::vector<double> y;                ///< [m]
  std::vector<std::vector<double>> x;   ///< per block, packed lower triangle: (i, j) at i(i+1)/2 + j
};

/// Solves with DSDP 5 (Benson and Ye), in this process.
SdpSolution solve_sdp_dsdp(const SdpProblem& prob, const SdpOptions& opt);

/// The problem in SDPA sparse format (for the external solvers' benchmark, bench/sdp_backends.sh).
void write_sdpa(const SdpProblem& prob, const std::string& path);

inline std::size_t packed_index(int i, int j) {
  return i >= j ? std::size_t(i) * (i + 1) / 2 + j : std::size_t(j) * (j + 1) / 2 + i;
}

}  // namespace snl::detail
