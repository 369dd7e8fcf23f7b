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

/// Jones-Plassmann colouring with the distributed one's priorities.
std::vector<int> coloring(const Network& net);
/// `sweeps` sweeps of the projection method in (colour, id) order.
std::vector<double> pm(const Network& net, const std::vector<double>& x0, int sweeps);
/// `activations` activations of 003 Algorithm 2 (exact or eq. 20), one at a
/// time; f_hat after every activation goes to *fhat if non-null.
std::vector<double> async(const Network& net, const std::vector<double>& x0, long activations, std::uint64_t seed,
                          bool exact, std::vector<double>* fhat = nullptr);

}  // namespace snl::reference
