#pragma once
// Reference twins: plain serial implementations of the kernels on a whole
// network held by one process, written independently of the distributed code
// (edge-list loops, no partitioning, no halo), for tests to compare against.
#include <cstdint>
#include <vector>

#include "snl/io/network.hpp"

namespace snl::reference {

/// f(x) and f_hat(x) on a whole network (duplicates already merged).
double ml_cost(const Network& net, const std::vector<double>& x);
double relaxed_cost(const Network& net, const std::vector<double>& x);
std::vector<double> relaxed_gradient(const Network& net, const std::vector<double>& x);
/// 2 delta_max + max |A_i|.
double relaxation_lipschitz(const Network& net);
/// `iters` iterations of 003 Algorithm 1 from x0.
std::vector<double> nesterov(const Network& net, const std::vector<double>& x0, int iters);
/// `iters` iterations of 000 Algorithm 1 from x0; surrogate values after each
/// iteration (index 0: at the start) go to *surrogate if non-null.
std::vector<double> mm(const Network& net, const std::vector<double>& x0, int iters,
                       std::vector<double>* surrogate = nullptr);
/// mm-accel (unweighted l2): the MM step above from the extrapolated point
/// z(k) + t/(t+3) (z(k) - z(k-1)), accepted when neither F nor the ML cost
/// rises, else a restart (t = 0, (y, w) at their best for x(k)). The ML cost
/// after each iteration into *ml, the rejected steps into *restarts.
std::vector<double> mm_accel(const Network& net, const std::vector<double>& x0, int iters,
                             std::vector<double>* ml = nullptr, int* restarts = nullptr);

/// Jones-Plassmann colouring with the distributed one's priorities.
std::vector<int> coloring(const Network& net);
/// `sweeps` sweeps of the projection method in (colour, id) order.
std::vector<double> pm(const Network& net, const std::vector<double>& x0, int sweeps);
/// `activations` activations of 003 Algorithm 2 (exact or eq. 20), one at a
/// time; f_hat after every activation goes to *fhat if non-null.
std::vector<double> async(const Network& net, const std::vector<double>& x0, long activations, std::uint64_t seed,
                          bool exact, std::vector<double>* fhat = nullptr);

}  // namespace snl::reference

namespace snl::reference {

/// A measurement model (src/problem/weights.cpp): a weight per sensor row and
/// per anchor row of the network, and the Huber threshold (0: l2). Each term
/// is w_e rho(r_e), rho(r) = r^2/2, or Huber beyond delta.
struct Model {
  std::vector<double> sensor_w, anchor_w;
  double delta = 0;
};
/// w = (sigma_min / sigma)^2 from the network's sensor_sigmas / anchor_sigmas
/// (weights 1 where it has none).
Model model_from_sigmas(const Network& net, double delta);
double model_ml_cost(const Network& net, const Model& m, const std::vector<double>& x);
double model_relaxed_cost(const Network& net, const Model& m, const std::vector<double>& x);
std::vector<double> model_relaxed_gradient(const Network& net, const Model& m, const std::vector<double>& x);
/// 003 Algorithm 1 with a step 1/D_i per sensor, D_i = 2 sum_j w_ij + sum_k w_ik.
std::vector<double> model_nesterov(const Network& net, const Model& m, const std::vector<double>& x0, int iters);
/// 000 Algorithm 1 with the Huber majorizer weights omega = min(1, delta/|x_i - x_j - y|)
/// and steps 1/D: D_x_i = 3 sum_j w_ij + 2 sum_k w_ik, D_y = 3 w_e (anchors 2 w); the objective
/// Phi = sum w rho(|x_i - x_j - y|) + anchors after each iteration into *phi.
std::vector<double> model_mm(const Network& net, const Model& m, const std::vector<double>& x0, int iters,
                             std::vector<double>* phi = nullptr);
/// mm-accel on the model: the MM step above from the extrapolated point
/// z(k) + t/(t+3) (z(k) - z(k-1)), accepted when neither Phi nor the ML cost
/// rises, else a restart (t = 0, y at its best for x(k)). The ML cost after
/// each iteration into *ml, the rejected steps into *restarts.
std::vector<double> model_mm_accel(const Network& net, const Model& m, const std::vector<double>& x0, int iters,
                                   std::vector<double>* ml = nullptr, int* restarts = nullptr);
/// The projection method with x_i <- sum_e a_e P_e(x_i) / sum_e a_e,
/// a_e = w_e omega(dist(x_i, disk e)), in pm's (colour, id) order.
std::vector<double> model_pm(const Network& net, const Model& m, const std::vector<double>& x0, int sweeps);
/// 003 Algorithm 2 on the weighted / Huber local costs: eq. (20) steps 1/L with
/// L = 2 max_i sum_j w_ij + max_i sum_k w_ik, or (exact) Algorithm 3 with
/// L_i = sum_j w_ij + sum_k w_ik.
std::vector<double> model_async(const Network& net, const Model& m, const std::vector<double>& x0, long activations,
                                std::uint64_t seed, bool exact);

}  // namespace snl::reference

namespace snl::reference {

/// The distance-vector start's anchor lists: per sensor the k nearest anchors
/// by shortest measured path (Dijkstra from every anchor over the sensor
/// edges; anchors do not relay), as (distance, anchor id) ascending.
std::vector<std::vector<std::pair<double, int>>> nearest_anchor_paths(const Network& net, int k);
/// Sum of |a - b| over sum of the shortest a -> b path r_ia + D_ib, over the
/// anchor pairs linked by a sensor i that measures a and lists b.
double path_correction(const Network& net, const std::vector<std::vector<std::pair<double, int>>>& lists);
/// The start: per sensor, min sum_t (|x - a_t| - c D_t)^2 / (c D_t)^2 from the weighted centroid by 20
/// damped Gauss-Newton steps (0.1 tr(H) on the diagonal, steps at most half the shortest c D_t); sensors
/// without a list keep their row of `fallback`.
std::vector<double> dv_start(const Network& net, int k, const std::vector<double>& fallback);
/// `iters` iterations of Nesterov's method on the ML cost f with the step 1/D_i
/// per sensor (D_i = 2 delta_i + |A_i|) and the gradient restart: after x(k),
/// when grad f(w(k)) . (x(k) - x(k-1)) > 0, the momentum starts again (ml-agd).
std::vector<double> ml_agd(const Network& net, const std::vector<double>& x0, int iters);

}  // namespace snl::reference
