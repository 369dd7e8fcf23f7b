#pragma once
// The gradient stopping test on plain sums (internal to src/solvers/).
#include "kernels/kernels.hpp"
#include "snl/problem/problem.hpp"

namespace snl::detail {

/// An interval [lo, hi] that holds the relative gradient the Solver's exact
/// test forms, ||grad c(x)|| / (2 sqrt f(x)) with both sums exact (c = f_hat
/// with `relaxed`, else f; plain l2 model). valid = false: no bound (f may be
/// 0, a sum is not finite); the exact test must decide.
struct GradientBounds {
  double lo = 0, hi = 0;
  bool valid = false;
};

/// Collective. x: local rows with the ghost rows exchanged. One pass of the
/// relaxation kernel (ml flag = !relaxed: the same gradient bits per node as
/// the scalar gradient the exact test sums) and one of mm_cost_chunk without
/// y, in plain doubles, with their rounding bounds. scratch: owned rows (the
/// kernel's x(k) output, discarded).
GradientBounds bound_relative_gradient(const LocalizationProblem& prob, const NodeLanes& nl, const double* x,
                                       bool relaxed, double* scratch);

}  // namespace snl::detail
