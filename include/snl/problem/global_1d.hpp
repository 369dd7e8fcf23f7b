#pragma once
// The exact global minimum f* of the ML cost (003 eq. 2, the papers' eq. 1)
// of a small one-dimensional network, for comparing the true gap f* - f_hat*
// with the certificate (003 eq. 22) and the a-priori bound (eq. 23).
//
// Method (exact, serial): on the line (|z| - d)^2 = min_{s = +-1} (z - s d)^2,
// so f(x) = min_s Q_s(x) over the 2^T sign patterns s of the T = E + Ea
// measurements, with Q_s(x) = 1/2 ||A x - c_s||^2 the linear least-squares
// cost of one pattern (A: rows e_i - e_j for a sensor edge, e_i for an anchor
// edge; c_s: s_e d_ij, resp. a_k + s_e r_ik). Hence f* = min_s min_x Q_s(x):
// each inner minimum is 1/2 (c^T c - b^T M b) with b = A^T c and the fixed
// M = (A^T A)^{-1}; a Gray-code walk over the patterns changes one entry of c
// per step, so each pattern costs O(n). The minimiser x = M b of the best
// pattern is returned with f evaluated at it directly.
// Limit: T <= max_terms (2^T patterns; T = 20 took 0.05 s, T = 26 a few seconds).
#include <cstdint>
#include <string>
#include <vector>

#include "snl/io/network.hpp"

namespace snl {

struct GlobalOptimum1DOptions {
  int max_terms = 26;  ///< refuse networks with more measurements (2^T patterns)
  std::string validate() const;
};

struct GlobalOptimum1D {
  double cost = 0;                  ///< f*, the ML cost at `positions`
  std::vector<double> positions;    ///< a global minimiser, [n]
  std::uint64_t patterns = 0;       ///< sign patterns enumerated (2^T)
};

/// `net`: a whole network (not a slab) with dim 1, duplicates merged or not
/// (each row is one term), every connected component anchored. Throws
/// snl::Error with the reason otherwise (dim, size limit, singular A^T A).
GlobalOptimum1D global_ml_optimum_1d(const Network& net, const GlobalOptimum1DOptions& opt = {});

}  // namespace snl
