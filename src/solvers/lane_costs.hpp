#pragma once
// The exact costs and the exact test's gradient from the lane layout
// (internal to src/solvers/): the same bits as snl/problem/metrics.hpp's
// scalar passes, in a fraction of their time where a phase has built the
// layout (kernels.hpp, shared_lanes). The scalar passes look up both ends'
// global ids per slot to count each edge once; the layout has that as a bit
// per slot, its slots in sequence, and its anchor pairs copied beside them.
#include "snl/problem/metrics.hpp"
#include "snl/problem/problem.hpp"

namespace snl::detail {

/// Which sums exact_costs forms (evaluate_costs' fields).
enum CostSum : unsigned { kMlSum = 1, kRelaxedSum = 2, kCertificateSum = 4, kAprioriSum = 8, kAllSums = 15 };

/// Collective. evaluate_costs(prob, x)'s sums named by `sums` (the others
/// 0), the same bits: from the lane layout where a phase has built it (plain
/// l2 model, p >= 2), else by evaluate_costs. x: local rows, ghosts exchanged.
CostTerms exact_costs(const LocalizationProblem& prob, const double* x, unsigned sums);

/// Collective. ml_cost_and_gradient(prob, x, g, relaxed), the same bits; the
/// gradient by the relaxation kernel (the scalar gradient's bits per node)
/// and f's terms while the chunk's rows are in cache. Where exact_costs
/// would not use the layout, ml_cost_and_gradient itself.
double exact_ml_cost_and_gradient(const LocalizationProblem& prob, const double* x, double* g, bool relaxed);

/// Whether the two above run on the lane layout (plain l2, 2D or 3D, the layout built).
bool lane_costs_apply(const LocalizationProblem& prob);

}  // namespace snl::detail
