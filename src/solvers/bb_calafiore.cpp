// Calafiore, Carlone and Wei's distributed Barzilai-Borwein method (CDC 2010)
// as published: gradient descent on the squared-distance discrepancy
//   F(x) = sum_{i~j} (||x_i - x_j||^2 - d_ij^2)^2 + sum_{i,k} (||x_i - a_k||^2 - r_ik^2)^2,
// each node's step alpha_i = s's / s'y with both inner products estimated by T
// rounds of average consensus (Metropolis weights). The registry's `bb` is the
// project's variant of it on the ML cost f (bb.cpp). Every node sums its
// neighbours in global-id order, so iterates are bit-identical for any number
// of ranks.
#include <mpi.h>

#include <algorithm>
#include <cmath>

#include "core/exact_sum.hpp"
#include "snl/problem/metrics.hpp"
#include "solvers/bb_common.hpp"

namespace snl {

namespace {

class BBCalafiore final : public detail::BarzilaiBorweinBase {
 public:
  BBCalafiore(LocalizationProblem& prob, int rounds) : BarzilaiBorweinBase(prob, rounds) {}
  std::string name() const override { return algorithm_info(AlgorithmId::kBBCalafiore).name; }
  double lipschitz() const override { return 1.0 / alpha0_; }

  // The objective the method minimizes: F, summed exactly (the same for any partition).
  double objective() override {
    const int p = prob_.dim();
    prob_.graph().halo().exchange(x_.data(), p);
    detail::ExactSum s;
    each_term(0, prob_.num_owned(), [&](LocalId, const double*, double r, double w) { s.add(w * r * r); });
    detail::allreduce_exact(&s, 1, prob_.comm());
    return s.value();
  }

 private:
  // f(v, z, res, w) for every term of owned nodes [b, e): z = x_v - x_u (or - a_k),
  // res = ||z||^2 - d^2; w = 1/2 for sensor pairs (each is seen from both ends), 1 for anchors.
  template <class F>
  void each_term(LocalId b, LocalId e, F&& f) const {
    const int p = prob_.dim();
    const auto& gr = prob_.graph();
    const double* anc = prob_.anchors().data();
    double z[3];
    auto visit = [&](LocalId v, const double* other, double d, double w) {
      double n2 = 0;
      for (int c = 0; c < p; ++c) {
        z[c] = x_[std::size_t(v) * p + c] - other[c];
        n2 += z[c] * z[c];
      }
      f(v, z, n2 - d * d, w);
    };
    for (LocalId v = b; v < e; ++v) {
      for (auto t = gr.offsets()[v]; t < gr.offsets()[v + 1]; ++t)
        visit(v, &x_[std::size_t(gr.adjacency()[t]) * p], gr.edge_value(t), 0.5);
      for (auto t = prob_.anchor_offsets()[v]; t < prob_.anchor_offsets()[v + 1]; ++t)
        visit(v, anc + std::size_t(prob_.anchor_ids()[t]) * p, prob_.anchor_ranges()[t], 1.0);
    }
  }
  // grad_i F = sum_j 4 res_ij (x_i - x_j) + sum_k 4 res_ik (x_i - a_k), owned nodes [b, e).
  void gradient(LocalId b, LocalId e) override {
    const int p = prob_.dim();
    std::fill(g_.begin() + std::size_t(b) * p, g_.begin() + std::size_t(e) * p, 0.0);
    each_term(b, e, [&](LocalId v, const double* z, double res, double) {
      for (int c = 0; c < p; ++c) g_[std::size_t(v) * p + c] += 4.0 * res * z[c];
    });
  }
  // The first step (before any s, y exist): 1 / (8 D^2 L), with L the Lipschitz
  // constant of the ML relaxation's gradient and D the largest range: the
  // curvature of F near a fit, 8 ||z||^2 per term against 1 for f (the
  // project's choice; the published first step is not in our sources).
  double first_step() const override {
    double dmax = 0;
    const auto& gr = prob_.graph();
    for (std::size_t t = 0; t < gr.adjacency().size(); ++t) dmax = std::max(dmax, gr.edge_value(std::int64_t(t)));
    for (double r : prob_.anchor_ranges()) dmax = std::max(dmax, r);
    MPI_Allreduce(MPI_IN_PLACE, &dmax, 1, MPI_DOUBLE, MPI_MAX, prob_.comm());
    return 1.0 / (8.0 * std::max(dmax * dmax, 1e-12) * relaxation_lipschitz(prob_));
  }
};

}  // namespace

namespace detail {

std::unique_ptr<Algorithm> make_bb_calafiore(LocalizationProblem& prob, const SolverOptions& opt) {
  return std::make_unique<BBCalafiore>(prob, opt.bb_rounds);
}

}  // namespace detail

}  // namespace snl
