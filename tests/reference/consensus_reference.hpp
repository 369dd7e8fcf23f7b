#pragma once
// Reference twin of the consensus optimum: x* = argmin sum_p f_p(x) computed
// serially from the problem's arrays with its own formulas (closed form for
// the quadratic and least-squares families, Newton in long double otherwise), for the tests to
// compare central_optimum and the distributed methods against.
#include <vector>

#include "snl/consensus/problem.hpp"

namespace snl::reference {

/// x* [q]; throws std::runtime_error if Newton does not reach rounding level.
std::vector<double> consensus_optimum(const consensus::ProblemData& d);

}  // namespace snl::reference
