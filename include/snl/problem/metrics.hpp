#pragma once
// Costs, gradients and error metrics of the localization problem, evaluated in
// parallel. `x` is a local position array [num_local * p] whose ghost rows are
// up to date. Every edge is counted once: by the owner of its smaller global id.
#include <cmath>
#include <limits>

#include "snl/problem/problem.hpp"

namespace snl {

// Every cost, gradient and constant below uses the problem's measurement model
// (prob.model(), weights.hpp): each term weighted by w_e and, with the Huber
// loss, rho(r) in place of r^2/2. The unweighted l2 model is the papers' form.
struct CostTerms {
  double ml = 0;           ///< f(x), eq. (1) of both papers
  double relaxed = 0;      ///< f_hat(x), the disk relaxation (003, eq. 6/7)
  double certificate = 0;  ///< optimality-gap certificate (003, eq. 22)
  double apriori = 0;      ///< a-priori bound (003, eq. 23)
};
/// Collective.
CostTerms evaluate_costs(const LocalizationProblem& prob, const double* x);
/// Collective: evaluate_costs(prob, x).ml and .relaxed, the same bits, forming
/// only the one sum (the solver's stopping tests and records).
double evaluate_ml_cost(const LocalizationProblem& prob, const double* x);
double evaluate_relaxed_cost(const LocalizationProblem& prob, const double* x);
/// Collective: evaluate_ml_cost(prob, x), and into g the owned rows of
/// relaxed_gradient (relaxed) or ml_gradient, the same bits, in one pass over
/// the edges (the solver's gradient stopping test).
double ml_cost_and_gradient(const LocalizationProblem& prob, const double* x, double* g, bool relaxed);

struct ErrorMetrics {
  bool valid = false;  ///< truth present
  double rmse = std::numeric_limits<double>::quiet_NaN();  ///< 003 eq. (29), one trial
  double mpe = std::numeric_limits<double>::quiet_NaN();   ///< 000 eq. (14), per sensor
  double rmse_localizable = std::numeric_limits<double>::quiet_NaN();  ///< over unflagged sensors
  double mpe_localizable = std::numeric_limits<double>::quiet_NaN();
  GlobalId localizable = 0;
};
/// Collective.
ErrorMetrics evaluate_errors(const LocalizationProblem& prob, const double* x);

/// Lipschitz constant of grad f_hat (003, eq. 16): 2 delta_max + max_i |A_i|;
/// weighted: 2 max_i sum_j w_ij + max_i sum_k w_ik.
double relaxation_lipschitz(const LocalizationProblem& prob);

/// Gradient of f_hat at owned nodes [begin, end) (003, Alg. 1 steps 7-8):
/// sum_j e(x_i - x_j, d_ij) + sum_k e(x_i - a_k, r_ik), e(z, rho) = max(0, 1 - rho/|z|) z.
/// Neighbours in global-id order, then anchors in id order: bit-identical for any rank count.
void relaxed_gradient(const LocalizationProblem& prob, const double* x, double* g, LocalId begin, LocalId end);

/// Gradient of the ML cost f at owned nodes [begin, end):
/// sum_j (1 - d_ij/|x_i - x_j|)(x_i - x_j) + anchors alike (0 where |z| = 0).
void ml_gradient(const LocalizationProblem& prob, const double* x, double* g, LocalId begin, LocalId end);

/// Local (this rank's) sum of squares over owned rows of a local array.
double owned_norm_sq(const LocalizationProblem& prob, const double* v);

}  // namespace snl
