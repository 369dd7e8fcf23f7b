// Initial point of a run (--init random).
#include <algorithm>

#include "snl/core/random.hpp"
#include "snl/solvers/solver.hpp"

namespace snl {

std::vector<double> random_initial_positions(const LocalizationProblem& prob, std::uint64_t seed) {
  const int p = prob.dim();
  std::vector<double> lo(p, 0.0), hi(p, 1.0);
  const auto& a = prob.anchors();
  if (!a.empty()) {
    for (int c = 0; c < p; ++c) lo[c] = hi[c] = a[c];
    for (std::size_t k = 0; k < a.size() / p; ++k)
      for (int c = 0; c < p; ++c) {
        lo[c] = std::min(lo[c], a[k * p + c]);
        hi[c] = std::max(hi[c], a[k * p + c]);
      }
  }
  std::vector<double> x(std::size_t(prob.num_owned()) * p);
  for (LocalId v = 0; v < prob.num_owned(); ++v) {
    const auto g = static_cast<std::uint64_t>(prob.graph().global_id(v));
    for (int c = 0; c < p; ++c)
      x[std::size_t(v) * p + c] = lo[c] + (hi[c] - lo[c]) * uniform01(seed, RngStream::kInit, g * p + c);
  }
  return x;
}

}  // namespace snl
