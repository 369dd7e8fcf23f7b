// The Barzilai-Borwein baseline (Calafiore, Carlone, Wei 2010, as compared in
// 000). Every node sums its neighbours in global-id order, so iterates are
// bit-identical for any number of ranks. Each iteration: halo begin -> interior
// nodes -> halo end -> boundary, then T consensus rounds.
#include <algorithm>
#include <cmath>

#include "kernels/kernels.hpp"
#include "snl/problem/metrics.hpp"
#include "solvers/bb_common.hpp"

namespace snl {

namespace {

// Barzilai-Borwein gradient descent on the ML cost f (Calafiore et al. 2010's
// step rule, bb_common.hpp), the first step 1/L with the relaxation's L.
class BB final : public detail::BarzilaiBorweinBase {
 public:
  BB(LocalizationProblem& prob, int rounds) : BarzilaiBorweinBase(prob, rounds) {}
  std::string name() const override { return algorithm_info(AlgorithmId::kBB).name; }
  double lipschitz() const override { return relaxation_lipschitz(prob_); }
  double objective() override {
    prob_.graph().halo().exchange(x_.data(), prob_.dim());
    return evaluate_costs(prob_, x_.data()).ml;
  }

 private:
  void gradient(LocalId b, LocalId e) override { ml_gradient(prob_, x_.data(), g_.data(), b, e); }
  double first_step() const override { return 1.0 / relaxation_lipschitz(prob_); }
};

}  // namespace

namespace detail {

std::unique_ptr<Algorithm> make_bb(LocalizationProblem& prob, const SolverOptions& opt) {
  return std::make_unique<BB>(prob, opt.bb_rounds);
}

}  // namespace detail

}  // namespace snl
